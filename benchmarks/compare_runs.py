"""Two runs of the validation matrix compared case by case: the scorecard and the fits.

A change to the modal stage can leave every count of the scorecard as it was and still move
the diagnosis: a mode labelled otherwise reaches ``identify`` (session 13: a first version of
an alias rule scored the same modal tables while the paper's failed-points case's final fit
went 0.09 → 2.1 % RMS with 8 modes set aside). So besides found / mislabelled / missed /
spurious / adopted per generator, every case whose base or final RMS moved by more than
``--rms-tol`` (percentage points), whose set-aside count, adopted effects or diagnosis verdict
changed is listed.

Usage::

    python benchmarks/validation.py --out /tmp/before.jsonl ...   # on the old code
    python benchmarks/validation.py --out /tmp/after.jsonl ...    # on the new code
    python benchmarks/compare_runs.py /tmp/before.jsonl /tmp/after.jsonl
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

COUNTS = ("expected", "found", "mislabelled", "missed", "spurious", "adopted")
#: percentage points of RMS below which a fit is the same (the matrix's repeat runs agree to
#: well under it: the records are deterministic, seeded)
RMS_TOL = 0.01


def read_records(path) -> dict:
    """{case name: record} of a ``benchmarks/validation.py --out`` file."""
    with open(path, encoding="utf-8") as fh:
        return {r["name"]: r for r in map(json.loads, fh) if r.get("name")}


def _fit_changes(x: dict, y: dict, rms_tol: float) -> list[str]:
    out = []
    for k in ("base_rms_pct", "final_rms_pct"):
        a, b = x.get(k), y.get(k)
        if (a is None) != (b is None) or (a is not None and abs(a - b) > rms_tol):
            out.append(f"{k.split('_')[0]} RMS {_pct(a)} → {_pct(b)} %")
    for k in ("set_aside", "diagnosis_right"):
        if x.get(k) != y.get(k):
            out.append(f"{k} {x.get(k)} → {y.get(k)}")
    if x.get("adopted_effects") != y.get("adopted_effects"):
        out.append(f"effects {x.get('adopted_effects')} → {y.get('adopted_effects')}")
    return out


def _pct(v) -> str:
    return "–" if v is None else f"{v:.3f}"


def compare(before: dict, after: dict, rms_tol: float = RMS_TOL) -> list[str]:
    """Lines of text: per generator the totals before → after (cases in both runs), then
    every case that changed in its counts or its fits."""
    common = [n for n in after if n in before]
    lines = []
    for g in sorted({after[n]["case"]["generator"] for n in common}):
        names = [n for n in common if after[n]["case"]["generator"] == g]
        tot = "  ".join(f"{k} {sum(before[n].get(k, 0) for n in names)} → {sum(after[n].get(k, 0) for n in names)}"
                        for k in COUNTS)
        lines.append(f"{g}: {tot}")
    for n in common:
        x, y = before[n], after[n]
        changes = [f"{k} {x.get(k)} → {y.get(k)}" for k in COUNTS if x.get(k) != y.get(k)]
        changes += _fit_changes(x, y, rms_tol)
        if changes:
            lines.append(f"{n}: " + "; ".join(changes))
    missing = sorted(set(before) ^ set(after))
    if missing:
        lines.append(f"in one run only: {', '.join(missing)}")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=Path)
    ap.add_argument("after", type=Path)
    ap.add_argument("--rms-tol", type=float, default=RMS_TOL, help="percentage points (default %(default)s)")
    args = ap.parse_args(argv)
    for line in compare(read_records(args.before), read_records(args.after), args.rms_tol):
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
