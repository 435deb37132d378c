"""The local search lands where the full search does, on the validation matrix (issue 19).

``diagnose`` refits every candidate on top of the current model by least squares from the
current fit, safeguarded by a short evolutionary search (``DiagnoseOptions.search="local"``,
the default); ``search="global"`` runs the full differential evolution for every refit.
For every case of the validation matrix kept by ``benchmarks/validation.py --keep DIR``,
this re-diagnoses the run's own modal table (the same modes, options, rim and geometry as
``run`` used) with the full search, and compares with the run's diagnosis (the local
search):

* the same effects adopted (and parameters found off), in the same order — and, printed
  beside it, the same final model whatever the order of adoption (the issue's wording:
  the same adopted effects and parameters within their standard errors);
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


def physical_limits() -> dict:
    """{"effect.param": upper} of every parameter whose upper bound is a physical limit
    (docs/diagnose.md, "Selection" 3): a value resting on it is determined by the limit, its
    standard error is ~0, and two fits that both rest on it agree whatever the last digits."""
    from tiremodal_cli.tyre.effects import EFFECTS

    return {f"{e.name}.{p.name}": p.upper for e in EFFECTS.values() for p in e.parameters if p.upper_is_physical}


def _at(value: float, limit: float) -> bool:
    """Within 0.1 % of the limit (the search's bound tolerance, 1e-3 in log units)."""
    return abs(value / limit - 1) <= 1e-3


def run_rows(run: Path, table) -> list[dict]:
    """The rows ``run`` diagnosed: ``to_rows`` of modal.h5 with each mode's frequency
    uncertainty from modes.csv. modal.h5 does not store the modal stage's uncertainties and
    ``to_rows`` rebuilds them from the clusters, which differs from the stage's for some
    modes (two modes of one group within 1 %: sidewall_coupling+mass, 5 of 90); modes.csv,
    written from the stage's table, has them exactly (shortest round-trip repr)."""
    import csv

    from tiremodal_cli.modal.table import to_rows

    rows = to_rows(table)
    with open(run / "modes.csv", newline="", encoding="utf-8") as f:
        kept = list(csv.DictReader(f))
    if len(kept) != len(rows):
        raise SystemExit(f"{run}: modes.csv has {len(kept)} modes, modal.h5 {len(rows)}")
    for row, c in zip(rows, kept):
        if int(c["mode"]) != row["mode"] or float(c["frequency_hz"]) != row["frequency_hz"]:
            raise SystemExit(f"{run}: modes.csv's mode {c['mode']} is not modal.h5's")
        u = c.get("frequency_uncertainty_hz", "")
        row["frequency_uncertainty_hz"] = float(u) if u not in ("", None) else None
    return rows


def compare(folder: str) -> dict:
    """Re-diagnose one kept run folder as ``run`` did (its own modal table, options, rim and
    grid, through :func:`tiremodal_cli.workflow.pipeline.model_inputs`, the function ``run``
    calls) with the local search and with the full search; check that the local search is
    the run's diagnosis.json, and compare the two."""
    from threadpoolctl import threadpool_limits

    from tiremodal_cli.diagnose import report
    from tiremodal_cli.io.modalfile import read_modal
    from tiremodal_cli.tyre.model import TyreParameters
    from tiremodal_cli.workflow.pipeline import model_inputs
    from tiremodal_cli.workflow.run_options import RunOptions

    run = Path(folder) / "run"
    man = json.loads((run / "run.json").read_text())
    opt = RunOptions.from_mapping(man["options"], f"{run}/run.json")
    # run's parameters: the nominal ones with the P0 and rim mass it used (run.json records both)
    params = TyreParameters.from_mapping(man["params"]).replace(P0=man["model_P0"], m_w=man["model_m_w"])
    table = read_modal(run / "modal.h5")
    rows = run_rows(run, table)
    out = {}
    for search in ("local", "global"):
        with threadpool_limits(1):
            t = time.perf_counter()
            fits = model_inputs(table, params, man["summary"]["rim"], opt, {"path": str(run / "modal.h5")},
                                rows=rows, search=search)
            out[search] = report(fits.diagnose())
            out[search + "_s"] = time.perf_counter() - t
    kept = json.loads((run / "diagnosis.json").read_text())
    as_run = (out["local"]["adopted_effects"] == kept["adopted_effects"]
              and out["local"]["parameter_off"] == kept["parameter_off"]
              and abs(out["local"]["augmented"]["rms_error_pct"] - kept["augmented"]["rms_error_pct"]) <= 1e-9)
    local, glob = out["local"], out["global"]

    def adopted(d):
        return list(dict.fromkeys(list(d["adopted_effects"]) + list(d["parameter_off"])))

    worst = 0.0
    pinned = []
    pl, pg = local["augmented"]["parameters"], glob["augmented"]["parameters"]
    same_set = set(pl) == set(pg)
    limits = physical_limits()
    if same_set:
        for k in pl:
            a, b = pl[k]["value"], pg[k]["value"]
            if k in limits and _at(a, limits[k]) and _at(b, limits[k]):
                pinned.append(k)  # both rest on the physical limit: determined by it, the same
                continue
            if k in local["augmented"]["undetermined"] and k in glob["augmented"]["undetermined"]:
                pinned.append(k)  # neither fit's modes determine it (its SE from pinv is 0, not ∞)
                continue
            se = max(pl[k]["std_error"] or 0.0, pg[k]["std_error"] or 0.0)
            d = abs(a - b)
            worst = max(worst, d / se if se > 0 else (0.0 if d == 0 else float("inf")))
    return {"case": Path(folder).name, "as_run": as_run, "local": adopted(local), "global": adopted(glob),
            "same_effects": adopted(local) == adopted(glob) and same_set, "worst_se": worst,
            "same_set_of_effects": set(adopted(local)) == set(adopted(glob)) and same_set,
            "rms_local": local["augmented"]["rms_error_pct"], "rms_global": glob["augmented"]["rms_error_pct"],
            "global_s": out["global_s"], "local_s": out["local_s"],
            "pinned": pinned}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("folder", help="the --keep folder of benchmarks/validation.py")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--only", nargs="*", default=(), help="substrings of the case folders to run")
    args = ap.parse_args()
    folders = sorted(str(p) for p in Path(args.folder).iterdir() if (p / "run" / "modal.h5").is_file()
                     and (not args.only or any(o in p.name for o in args.only)))
    with ProcessPoolExecutor(args.jobs) as ex:
        recs = list(ex.map(compare, folders))
    bad = 0
    for r in recs:
        ok = r["same_effects"] and r["worst_se"] <= 1.0
        bad += not ok
        print(f"{'same' if ok else 'DIFFERENT':<10} {r['case'][:70]:<70} "
              f"{'' if r['as_run'] else 'NOT-AS-RUN '}local {','.join(r['local']) or '-':<28} "
              f"global {','.join(r['global']) or '-':<28} worst {r['worst_se']:.3g} SE  "
              f"RMS {r['rms_local']:.3f}/{r['rms_global']:.3f} %  local {r['local_s']:.1f} s global {r['global_s']:.1f} s"
              + (f"  (at a physical limit or undetermined in both: {', '.join(r['pinned'])})" if r["pinned"] else ""))
    model = sum(r["same_set_of_effects"] and r["worst_se"] <= 1.0 for r in recs)
    print(f"# {sum(r['as_run'] for r in recs)} / {len(recs)} cases: the local search is the run's diagnosis.json")
    print(f"# {len(recs) - bad} / {len(recs)} cases: the same effects and every parameter within 1 SE")
    print(f"# {model} / {len(recs)} cases: the same final model (the same effects in any order of adoption, "
          "every parameter within 1 SE)")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
