"""On grids with missing points: a mode's spatial reading against its order group, scored by the truth.

    python benchmarks/validation.py --jobs 2 --keep /tmp/K --out /tmp/K.jsonl --no-docs
    python benchmarks/gappy_readings.py /tmp/K.jsonl /tmp/K

The rule measured (``classify._read``, docs/lsce.md "Session 21"): on a grid with missing
points a mode whose shape reads another order than the order group its pole was estimated in
is read at the group's order. For every mode of every case whose grid has failed points, this
script reads the shape alone (the tread channel's order energy, ``classify.order_energy`` on
the kept ``run/modal.h5`` — the reading before the rule), takes its group, and checks both
against the alias classes of the truth modes within 0.3 % (the ruler's tolerance; structural
branches only). Prints every disagreement and the counts: agreements (both right, both
wrong) and disagreements (which one is right; "crowd" when both are among the truth classes).
The case is re-simulated from its seed for the truth.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path

import h5py
import numpy as np

from tiremodal_cli.modal.classify import _real, order_energy
from tiremodal_cli.modal.spatial import grid_points
from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.validation import Case, config_for
from tiremodal_cli.workflow.validation_scoring import TOLERANCE

from spurious import folder_of  # noqa: E402  (benchmarks/ is the script's folder)


def alias_class(n: int, n_grid: int) -> int:
    """The grid's order group that order n falls in (n and N − n are one group)."""
    g = n % n_grid
    return min(g, n_grid - g)


def readings(modal_path: Path):
    """Per mode: (frequency Hz, the shape's own reading, its group); None if no tread channel."""
    with h5py.File(modal_path) as f:
        locs = [x.decode() if isinstance(x, bytes) else str(x) for x in f["channel_location"][()]]
        if "tread" not in locs:
            return None, None
        it = locs.index("tread")
        ang = f["point_angle"][()]
        shapes, fr, grp = f["shapes"][()], f["frequency_hz"][()], f["group"][()]
    out = []
    for r in range(fr.size):
        e = order_energy(_real(shapes[r, it]), ang)
        out.append((float(fr[r]), int(max(e, key=e.get)), int(grp[r])))
    return out, ang


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("records", type=Path)
    ap.add_argument("keep", type=Path)
    a = ap.parse_args()
    tally = Counter()
    for line in a.records.read_text().splitlines():
        rec = json.loads(line)
        run = a.keep / folder_of(rec["name"]) / "run"
        if rec.get("status") != "ok" or not (run / "modal.h5").exists():
            continue
        rows, ang = readings(run / "modal.h5")
        if rows is None or grid_points(ang) == len(ang):
            continue  # complete grids: the rule does not apply
        case = Case(**rec["case"])
        truth = simulate(config_for(case)).truth["modes"]
        n_grid = grid_points(ang)
        for f, own, grp in rows:
            near = {alias_class(m["n"], n_grid) for m in truth
                    if abs(m["frequency_hz"] / f - 1) <= TOLERANCE and m["branch"] in ("same", "opposite", "rim")}
            if not near:
                continue
            if own == grp:
                tally["agree, right" if own in near else "agree, wrong"] += 1
                continue
            which = ("crowd: both truth classes" if own in near and grp in near else
                     "the group right" if grp in near else "the shape right" if own in near else "neither right")
            tally[f"disagree, {which}"] += 1
            print(f"{rec['name']}: {f:.2f} Hz  shape {own}  group {grp}  truth classes {sorted(near)}  -> {which}")
    for k, v in sorted(tally.items()):
        print(f"{k}: {v}")


if __name__ == "__main__":
    main()
