"""How the modal stage holds as points go missing: one test, k of its points left out.

    python benchmarks/gaps_sweep.py                       # the paper's 24-point Timoshenko + rim test
    python benchmarks/gaps_sweep.py --missing 0 1 2 5 --seeds 0 1000 --out /tmp/gaps.jsonl

A validation-matrix test without its faults (``--case``, by default the paper's 2,560 Hz,
24-point, one-hit, 2 % noise Timoshenko + rim combination with bounces and overloads: the
failed-points combination, here without them) is simulated at each seed, its FRFs estimated as ``run``
does, and k of its points dropped (seeded, the same k-subsets for every build) before the
modal stage (``run``'s options and band). The table is scored by the validation ruler
(``workflow/validation_scoring.py``) against the generator's truth for the full grid: a
grid with gaps is judged by what the complete grid would show. Prints one line per
(seed, k, path) — each test through the modal stage as ``run`` does it (``mirror``) and with
the sensors' angles withheld (``gappy``, the baseline: the gaps kept) — expected, found,
mislabelled, missed, spurious / adopted, seconds; then the totals of each path and the ratio
of their times.

Why: a point whose every hit is rejected leaves a gap, and with one hit per point that is a
fifth of the points when a fifth of the hits bounce; since session 22 the bounced hits are
kept (``frf.screening.bounced_only_hits``), so a one-hit test with an overload has *one*
gap — and the modal stage must hold on a grid with one gap as on one with five.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.modal.modes import modal_table_from_frf
from tiremodal_cli.modal.options import ModalOptions
from tiremodal_cli.modal.table import to_rows
from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.run_options import RunOptions
from tiremodal_cli.workflow.validation import config_for, matrix
from tiremodal_cli.workflow.validation_scoring import expected_groups, score_modes

CASE = ("paper:combo: sample_rate=2560.0, n_points=24, n_hits=1, noise=0.02, faults=bounced+overload, "
        "physics=timoshenko+rim")


def rows_of(table) -> list[dict]:
    """The table's rows as :func:`~tiremodal_cli.workflow.validation_scoring.score_modes` reads them."""
    out = []
    for r in to_rows(table):
        out.append({"frequency_hz": float(r["frequency_hz"]), "damping_ratio": float(r["damping_ratio"]),
                    "n": r.get("n"), "branch": r.get("branch"), "aliased": bool(r.get("n_aliased")),
                    "n_spatial": r.get("n_spatial"), "n_candidates": list(r.get("n_candidates") or [])})
    return out


def one(case, k: int, rng_seed: int, drop=None) -> list[dict]:
    """One test with k points left out, through the modal stage twice: as ``run`` does it
    (``mirror``: a missing point read from its mirror image when the test shows the
    symmetry, modal.mirror) and with the sensors' angles withheld (``gappy``: the gaps kept,
    the gappy-grid path — the baseline, and what ran before session 22)."""
    cfg = config_for(case)
    sim = simulate(cfg)
    opt = RunOptions()
    r = compute_frf(sim.measurement, FRFOptions(band_hz=(0.0, opt.frf_top * cfg.sample_rate), exp_end=opt.exp_end))
    n_p = r.point_index.size
    if drop is None:
        drop = np.sort(np.random.default_rng(rng_seed).choice(n_p, size=k, replace=False)) if k else np.array([], int)
    drop = np.asarray(drop, dtype=int)
    keep = np.setdiff1d(np.arange(n_p), drop)
    r = dataclasses.replace(r, H=r.H[:, keep], coherence=r.coherence[:, keep], n_averages=r.n_averages[keep],
                            point_index=r.point_index[keep], point_angle=r.point_angle[keep],
                            force_autospectrum=None if r.force_autospectrum is None else r.force_autospectrum[keep])
    groups = expected_groups(sim, cfg)
    out = []
    for path, rr in (("mirror", r), ("gappy", dataclasses.replace(r, channel_angle=None))):
        t = time.perf_counter()
        table, _ = modal_table_from_frf(rr, ModalOptions(order_within_band=True))
        sc = score_modes(groups, rows_of(table), sim.truth["modes"])
        out.append({"case": case.name, "seed": case.seed, "missing": int(k), "dropped": [int(i) for i in drop],
                    "path": path, **{x: sc[x] for x in ("expected", "found", "mislabelled", "missed", "spurious",
                                                        "adopted")},
                    "seconds": round(time.perf_counter() - t, 2),
                    "not_found": [d for d in sc["detail"] if d["status"] != "found"]})
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default=CASE)
    ap.add_argument("--missing", type=int, nargs="+", default=[1, 2, 3, 5])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1000, 2000, 3000], help="offsets of the case's seed")
    ap.add_argument("--drop", type=int, nargs="+", help="these points (0-based) instead of --missing's random ones")
    ap.add_argument("--out", type=Path)
    a = ap.parse_args(argv)
    base = dataclasses.replace(next(c for c in matrix() if c.name == a.case), faults="none")  # its gaps are ours
    every = []
    for off in a.seeds:
        case = dataclasses.replace(base, seed=base.seed + off)
        for k in ([len(a.drop)] if a.drop else a.missing):
            recs = one(case, k, 7919 * (off + 1) + k, a.drop)
            for rec in recs:
                print(f"seed +{off:<5} missing {k:2d} {rec['dropped']} {rec['path']:6s}: found {rec['found']}/"
                      f"{rec['expected']}, mislabelled {rec['mislabelled']}, missed {rec['missed']}, spurious "
                      f"{rec['spurious']}/{rec['adopted']} ({rec['seconds']} s)", flush=True)
                if a.out:
                    with open(a.out, "a", encoding="utf-8") as fh:
                        fh.write(json.dumps(rec) + "\n")
            every += recs
    print("\ntotals (path: found / expected, mislabelled, spurious / adopted, tests over 5 % spurious, seconds)")
    tot = {}
    for path in ("mirror", "gappy"):
        R = [x for x in every if x["path"] == path]
        tot[path] = sum(x["seconds"] for x in R)
        print(f"  {path:6s}: {sum(x['found'] for x in R)} / {sum(x['expected'] for x in R)}, "
              f"{sum(x['mislabelled'] for x in R)}, {sum(x['spurious'] for x in R)} / {sum(x['adopted'] for x in R)}, "
              f"{sum(x['spurious'] > 0.05 * x['adopted'] for x in R)} of {len(R)}, {tot[path]:.1f} s")
    print(f"  modal stage time, gappy / mirror: {tot['gappy'] / max(tot['mirror'], 1e-9):.1f} ×")
    return 0


if __name__ == "__main__":
    sys.exit(main())
