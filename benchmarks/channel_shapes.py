"""The merge's channel-shape rule on the validation matrix: how often two poles of different
order groups that it keeps apart are two truth modes, and how often copies.

    python benchmarks/validation.py --no-docs --out /tmp/m0.jsonl --keep /tmp/m0 [--seed-offset N]
    python benchmarks/channel_shapes.py /tmp/m0.jsonl /tmp/m0 [--only CASE]

(``--keep`` records with ``--seed-offset N`` name the simulated seed in each record: the
truth is simulated again from it.)

For every kept case the modal stage is run again on its ``run/frf.h5`` (``run``'s defaults)
and every candidate pair of :func:`~tiremodal_cli.modal.merge.merge_groups` is recorded: a
dominant pole and a weaker pole of another group within the dominant's half-power
half-width. A pair is *two modes* when the generator's truth (the case simulated again) holds
a mode of the weaker pole's order group (its order folded by the points' aliasing) within
that half-width of the weaker pole, else a *copy*; a pair of two modes is also marked
*on a truth mode* when the weaker pole lies within the ruler's tolerance (0.3 %) of a truth
frequency, as the scorecard counts a row that is not spurious (session 30: in a crowd of
one branch's orders under an added mass, one pole of a group stands for several modes, and
the half-width test calls its blend "two modes" though the scorecard counts it spurious).
Printed: the pairs the rule keeps apart
(:func:`~tiremodal_cli.modal.merge._other_channel_shape`: the weaker visible, pinned and a
normal mode, channel-shape MAC under :data:`~tiremodal_cli.modal.merge.CHANNEL_MAC_MAX`) and the others, each split into
two modes and copies, and every copy the rule keeps apart (a false split).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import tiremodal_cli.modal.modes as modes_module  # noqa: E402
from tiremodal_cli.io.frffile import read_frf  # noqa: E402
from tiremodal_cli.modal.groupfit import PEAK_OVER_NOISE  # noqa: E402
from tiremodal_cli.modal.lsce import poles_to_modal  # noqa: E402
from tiremodal_cli.modal.lsfd import mpc  # noqa: E402
from tiremodal_cli.modal.merge import CHANNEL_MAC_MAX, channel_shape  # noqa: E402
from tiremodal_cli.modal.modes import ModalOptions, modal_table_from_frf  # noqa: E402
from tiremodal_cli.tyre.simulate import simulate  # noqa: E402
from tiremodal_cli.workflow.validation import Case, config_for  # noqa: E402
from tiremodal_cli.workflow.validation_scoring import TOLERANCE  # noqa: E402


def _fold(n: int, n_points: int) -> int:
    r = n % n_points
    return min(r, n_points - r)


def candidate_pairs(found, n_channels: int, line_hz: float) -> list[dict]:
    """Every (dominant, weaker) pair of poles of different groups within the dominant's
    half-power half-width, with the weaker's channel-shape MAC and visibility."""
    fn, zeta = poles_to_modal(np.array([m.pole for m in found]))
    energy = np.array([np.linalg.norm(m.residues) ** 2 for m in found])
    out = []
    for i in range(len(found)):
        for j in range(len(found)):
            if found[j].group == found[i].group or energy[j] >= energy[i] or abs(fn[j] - fn[i]) > zeta[i] * fn[i]:
                continue
            u, v = channel_shape(found[i], n_channels), channel_shape(found[j], n_channels)
            out.append({"f_dominant": float(fn[i]), "g_dominant": int(found[i].group), "f": float(fn[j]),
                        "g": int(found[j].group), "half_width": float(zeta[i] * fn[i]),
                        "mac": float(abs(np.vdot(u, v)) ** 2), "visible": bool(found[j].visibility >= PEAK_OVER_NOISE),
                        "pinned": bool(found[j].frequency_std_hz <= line_hz), "normal": bool(mpc(found[j].residues) >= 0.5),
                        "energy_ratio": float(energy[j] / energy[i])})
            p = out[-1]
            p["kept_apart"] = (n_channels >= 2 and line_hz > 0 and p["visible"] and p["pinned"] and p["normal"]
                               and p["mac"] < CHANNEL_MAC_MAX)
    return out


def case_pairs(rec: dict, keep: Path) -> list[dict]:
    """The candidate pairs of one kept case, each marked ``two`` (two truth modes) and ``kept_apart``."""
    d = keep / rec["name"].replace(":", "_").replace("=", "-").replace(" ", "").replace(",", "_")
    seen: list[dict] = []
    original = modes_module.merge_groups

    def spy(found, *args, **kwargs):
        seen.extend(candidate_pairs(found, kwargs.get("n_channels", 1), kwargs.get("line_hz", 0.0)))
        return original(found, *args, **kwargs)

    modes_module.merge_groups = spy
    try:
        modal_table_from_frf(read_frf(d / "run" / "frf.h5"), ModalOptions())
    finally:
        modes_module.merge_groups = original
    case = Case(**rec["case"])
    sim = simulate(config_for(case))
    truth = [(m["frequency_hz"], _fold(m["n"], case.n_points)) for m in sim.truth["modes"]]
    for p in seen:
        p["two"] = any(g == p["g"] and abs(f - p["f"]) <= p["half_width"] for f, g in truth)
        p["on_truth"] = any(abs(f / p["f"] - 1) <= TOLERANCE for f, _ in truth)
        p["case"] = rec["name"]
    return seen


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("records")
    ap.add_argument("keep")
    ap.add_argument("--only", action="append", default=[])
    args = ap.parse_args(argv)
    pairs = []
    for line in Path(args.records).read_text(encoding="utf-8").splitlines():
        rec = json.loads(line)
        if rec.get("status") != "ok" or (args.only and rec["name"] not in args.only):
            continue
        got = case_pairs(rec, Path(args.keep))
        pairs += got
        print(f"{rec['name']}: {len(got)} pairs, {sum(p['kept_apart'] for p in got)} kept apart", file=sys.stderr)
    for apart in (True, False):
        sel = [p for p in pairs if p["kept_apart"] is apart]
        two = sum(p["two"] for p in sel)
        on = sum(p["two"] and p["on_truth"] for p in sel)
        label = "kept apart by the channel shapes" if apart else "not kept apart by them"
        print(f"{label}: {len(sel)} pairs, {two} two truth modes ({on} with the weaker on a truth mode's "
              f"frequency, {two - on} a blend off every one), {len(sel) - two} copies")
    for p in pairs:
        if p["kept_apart"] and not p["two"]:
            print(f"    copy kept apart: {p['case']} {p['f']:.2f} Hz (group {p['g']}) beside {p['f_dominant']:.2f} Hz "
                  f"(group {p['g_dominant']}), MAC {p['mac']:.2f}, energy {p['energy_ratio']:.1e}")
    blends = sorted({(p["case"], round(p["f"], 2)) for p in pairs if p["kept_apart"] and p["two"] and not p["on_truth"]})
    for case, f in blends:
        print(f"    blend kept apart (off every truth frequency by more than {100 * TOLERANCE:g} %): {case} {f:.2f} Hz")
    return 0


if __name__ == "__main__":
    sys.exit(main())
