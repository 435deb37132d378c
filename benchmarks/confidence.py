"""How far the modal table's confidences can be trusted: the share of right readings per
confidence bin, on a kept validation run.

    python benchmarks/validation.py --no-docs --out /tmp/m0.jsonl --keep /tmp/m0
    python benchmarks/confidence.py /tmp/m0.jsonl /tmp/m0 [--only CASE]

Every row of a case's ``modes.csv`` within the ruler's tolerance (0.3 %) of truth modes of one
branch (``same`` or ``opposite``; rows at a cavity, tangential or rim mode, which the tool has
no label for, and rows between two branches' modes are left out) is a reading of that branch;
of one order, a reading of that order. Per bin of ``branch_confidence`` the share of rows
whose branch is the truth's; per bin of ``n_confidence`` the share whose ``n`` is the truth's,
apart for the rows flagged ``n_aliased`` (their ``n`` is the alias walk's choice among the
orders that alias onto ``n_spatial``, which ``n_confidence`` — the spatial order's share of the
tread shape — does not measure). A calibrated confidence c is right in a share c of its rows.
The confident wrong readings (confidence ≥ 0.9) are listed.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from tiremodal_cli.workflow.validation_scoring import TOLERANCE


def _load(name):
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


spurious = _load("spurious")

#: the confidence bins, [lo, hi)
BINS = ((0.0, 0.5), (0.5, 0.7), (0.7, 0.9), (0.9, 0.99), (0.99, 1.01))
#: a reading at or above this confidence that is wrong is listed
CONFIDENT = 0.9


def reading(row: dict, truth: list[dict]) -> dict | None:
    """A table row (``modes.csv`` strings) as a reading of the truth modes within the ruler's
    tolerance of it, or None where those are not of one branch among same / opposite."""
    f = float(row["frequency_hz"])
    near = [m for m in truth if abs(m["frequency_hz"] / f - 1) <= TOLERANCE]
    branches = {m["branch"] for m in near}
    if not row.get("branch") or len(branches) != 1 or not branches <= {"same", "opposite"}:
        return None
    return {"frequency_hz": f, "branch": row["branch"], "branch_confidence": float(row["branch_confidence"]),
            "n": int(row["n"]), "n_confidence": float(row["n_confidence"]),
            "aliased": row.get("n_aliased") == "True", "truth_branch": branches.pop(),
            "truth_n": sorted({m["n"] for m in near})}


def readings(records, keep, only=()) -> list[dict]:
    """Every kept case's rows at truth modes of one branch (:func:`reading`), with the case's name."""
    out = []
    for rec, _, _, sim, rows in spurious.kept_cases(records, keep, only):
        for r in rows:
            x = reading(r, sim.truth["modes"])
            if x is not None:
                out.append(x | {"case": rec["name"]})
    return out


def calibration(conf, right) -> list[tuple]:
    """Per bin of :data:`BINS` holding readings: (lo, hi, rows, mean confidence, share right)."""
    conf, right = np.asarray(conf, dtype=float), np.asarray(right, dtype=bool)
    out = []
    for lo, hi in BINS:
        m = (conf >= lo) & (conf < hi)
        if m.any():
            out.append((lo, hi, int(m.sum()), float(conf[m].mean()), float(right[m].mean())))
    return out


def _table(label: str, conf, right) -> None:
    print(f"{label}: {len(conf)} readings, {np.mean(right) if len(conf) else float('nan'):.3f} right")
    for lo, hi, n, mean, share in calibration(conf, right):
        print(f"    [{lo:.2f}, {min(hi, 1.0):.2f}{')' if hi <= 1 else ']'}: {n:5d} rows, "
              f"mean confidence {mean:.3f}, right {share:.3f}")


def main(argv=None) -> int:
    a = spurious.matrix_parser(__doc__).parse_args(argv)
    rows = readings(a.records, a.keep, a.only)
    _table("branch", [r["branch_confidence"] for r in rows], [r["branch"] == r["truth_branch"] for r in rows])
    one = [r for r in rows if len(r["truth_n"]) == 1]
    for aliased in (False, True):
        sub = [r for r in one if r["aliased"] is aliased]
        _table(f"n ({'flagged aliased: the walk' if aliased else 'not aliased'})",
               [r["n_confidence"] for r in sub], [r["n"] in r["truth_n"] for r in sub])
    print(f"confident wrong readings (confidence ≥ {CONFIDENT}):")
    for r in rows:
        if r["branch_confidence"] >= CONFIDENT and r["branch"] != r["truth_branch"]:
            print(f"    branch {r['case']} {r['frequency_hz']:.2f} Hz read {r['branch']} "
                  f"({r['branch_confidence']:.2f}), truth {r['truth_branch']} n={r['truth_n']}")
    for r in one:
        if not r["aliased"] and r["n_confidence"] >= CONFIDENT and r["n"] not in r["truth_n"]:
            print(f"    n      {r['case']} {r['frequency_hz']:.2f} Hz read n = {r['n']} "
                  f"({r['n_confidence']:.2f}), truth n = {r['truth_n']} {r['truth_branch']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
