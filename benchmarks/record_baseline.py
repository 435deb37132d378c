"""Record the identify/diagnose results of the present implementation (issue 19 baseline).

Run once on the commit named in the output, BEFORE the evaluation machinery changed:

    python benchmarks/record_baseline.py tests/data/perf_baseline

It runs ``tiremodal run`` on the bundled sample, keeps the sample's modal table
(``modes.csv``) so that the check does not depend on the lsce stage, and records for the
sample's table and for the paper's Table A1: the base fit (identify's defaults and
diagnose's base), the adopted effects and every fitted parameter with its standard error.
tests/test_speed_equivalence.py checks the present code against these numbers.
"""

import csv
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from tiremodal_cli.diagnose.loop import DiagnoseOptions, diagnose
from tiremodal_cli.tyre.fit import fit
from tiremodal_cli.tyre.fit_types import FitOptions
from tiremodal_cli.tyre.measured import modes_from_rows
from tiremodal_cli.io.measurement import open_measurement
from tiremodal_cli.tyre.model import TyreParameters

ROOT = Path(__file__).resolve().parents[1]


def fit_block(res):
    return {"free": list(res.free), "values": [float(v) for v in res.values],
            "std_errors": [float(s) for s in res.std_errors], "rms_error_pct": res.rms_error_pct,
            "effects": res.effects}


def record(rows, base, n_points=None):
    modes, _ = modes_from_rows(rows)
    ident = fit(modes, base, FitOptions())
    d = diagnose(rows, base, n_points=n_points)
    return {"identify": fit_block(ident), "diagnose": {"adopted": list(d.adopted), "base": fit_block(d.base),
                                                        "augmented": fit_block(d.augmented)}}


def main(out):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, "-m", "tiremodal_cli", "run", str(ROOT / "sample_data/gl073a_sim.h5"),
                        "-o", tmp, "--overwrite"], check=True)
        (out / "sample_modes.csv").write_text((Path(tmp) / "modes.csv").read_text())
    with open_measurement(ROOT / "sample_data/gl073a_sim.h5") as m:  # what `run` takes
        nominal = TyreParameters(m_w=1000.0, P0=float(m.inflation_pressure))
        n_points = int(m.n_points)
    sample_rows = list(csv.DictReader((out / "sample_modes.csv").open()))
    a1_rows = list(csv.DictReader((ROOT / "sample_data/paper_table_a1.csv").open()))
    res = {"commit": commit,
           "how": "benchmarks/record_baseline.py: sample = modes.csv of `tiremodal run sample_data/gl073a_sim.h5`, "
                  "Table A1 = sample_data/paper_table_a1.csv; identify = fit(FitOptions()), diagnose = "
                  "diagnose(rows, base) with default options; base = TyreParameters(m_w=1000.0, P0=the file's pressure) and n_points=34 for the sample, "
                  "TyreParameters() for Table A1 (as the diagnose CLI)",
           "sample_n_points": n_points, "sample_P0": nominal.P0,
           "sample": record(sample_rows, nominal, n_points), "table_a1": record(a1_rows, TyreParameters())}
    (out / "results.json").write_text(json.dumps(res, indent=1) + "\n")
    print(json.dumps(res, indent=1))


if __name__ == "__main__":
    main(sys.argv[1])
