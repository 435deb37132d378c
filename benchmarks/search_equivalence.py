"""The local search lands where the full search does, on the validation matrix (issue 19).

``diagnose`` refits every candidate on top of the current model by least squares from the
current fit, safeguarded by a short evolutionary search (``DiagnoseOptions.search="local"``,
the default); ``search="global"`` runs the full differential evolution for every refit.
For every case of the validation matrix kept by ``benchmarks/validation.py --keep DIR``,
this re-diagnoses the run's own modal table (the same modes, options, rim and geometry as
``run`` used) with the full search, and compares with the run's diagnosis (the local
search):

* the same effects adopted (and parameters found off), in the same order;
* every parameter of the final model within one standard error (the larger of the two
  fits') of the other's value;
* the final RMS error, and the time each took.

Run: ``python benchmarks/validation.py --jobs 2 --keep /tmp/val`` then
``python benchmarks/search_equivalence.py /tmp/val [--jobs 2]``. Prints one line per case
and a tally; exit status 1 when a case differs.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path


def compare(folder: str) -> dict:
    """Re-diagnose one kept run folder with the full search; compare with its diagnosis."""
    from threadpoolctl import threadpool_limits

    from tiremodal_cli.diagnose import DiagnoseOptions, diagnose, report, usable_modes
    from tiremodal_cli.io.modalfile import read_modal
    from tiremodal_cli.modal.table import to_rows
    from tiremodal_cli.tyre.model import TyreParameters
    from tiremodal_cli.workflow.pipeline import rim_state

    run = Path(folder) / "run"
    man = json.loads((run / "run.json").read_text())
    local = json.loads((run / "diagnosis.json").read_text())
    opts = man["options"]
    params = TyreParameters.from_mapping(man["params"]).replace(P0=man["model_P0"], m_w=man["model_m_w"])
    table = read_modal(run / "modal.h5")
    dopt = DiagnoseOptions(seed=opts["seed"], noise_floor_pct=opts["noise_floor_pct"],
                           max_effects=opts["max_effects"], rim=rim_state(man["summary"]["rim"]), search="global")
    with threadpool_limits(1):
        measured = usable_modes(to_rows(table), dopt, source="modal.h5")
        t = time.perf_counter()
        glob = report(diagnose(measured, params, dopt, n_points=int(table.point_angle.size)))
        t_global = time.perf_counter() - t

    def adopted(d):
        return list(dict.fromkeys(list(d["adopted_effects"]) + list(d["parameter_off"])))

    worst = 0.0
    pl, pg = local["augmented"]["parameters"], glob["augmented"]["parameters"]
    same_set = set(pl) == set(pg)
    if same_set:
        for k in pl:
            se = max(pl[k]["std_error"] or 0.0, pg[k]["std_error"] or 0.0)
            d = abs(pl[k]["value"] - pg[k]["value"])
            worst = max(worst, d / se if se > 0 else (0.0 if d == 0 else float("inf")))
    return {"case": Path(folder).name, "local": adopted(local), "global": adopted(glob),
            "same_effects": adopted(local) == adopted(glob) and same_set, "worst_se": worst,
            "rms_local": local["augmented"]["rms_error_pct"], "rms_global": glob["augmented"]["rms_error_pct"],
            "global_s": t_global}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("folder", help="the --keep folder of benchmarks/validation.py")
    ap.add_argument("--jobs", type=int, default=1)
    args = ap.parse_args()
    folders = sorted(str(p) for p in Path(args.folder).iterdir() if (p / "run" / "diagnosis.json").is_file())
    with ProcessPoolExecutor(args.jobs) as ex:
        recs = list(ex.map(compare, folders))
    bad = 0
    for r in recs:
        ok = r["same_effects"] and r["worst_se"] <= 1.0
        bad += not ok
        print(f"{'same' if ok else 'DIFFERENT':<10} {r['case'][:70]:<70} local {','.join(r['local']) or '-':<28} "
              f"global {','.join(r['global']) or '-':<28} worst {r['worst_se']:.3g} SE  "
              f"RMS {r['rms_local']:.3f}/{r['rms_global']:.3f} %  global {r['global_s']:.1f} s")
    print(f"# {len(recs) - bad} / {len(recs)} cases: the same effects and every parameter within 1 SE")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
