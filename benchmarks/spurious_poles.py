"""Why no rule drops a spurious mode: each one's order-group poles and the rules' quantities.

    python benchmarks/validation.py --jobs 1 --keep /tmp/K --out /tmp/K.jsonl --no-docs
    python benchmarks/spurious_poles.py /tmp/K.jsonl /tmp/K --only paper:physics=added_mass

For every spurious row of a kept case (``benchmarks/spurious.py``: no truth mode within
0.3 %), the modal stage is run again on the kept ``run/frf.h5`` over the kept band (the
same table to the bit: the stage is deterministic) and the adopted mode's quantities are
printed against the conditions of :func:`tiremodal_cli.modal.leaks.under_residual` — (a)
physical share < ``min_significance``, (c) frequency scatter over the model orders > one
line, (d) a mode of another group with a larger peak within that mode's half-power
half-width, (e) the channel MAC with the strongest of those ≥ 0.9 — with ``-`` where a
condition fails (what keeps the mode), its peak against its group's residual RMS (the
own-peak rule's (b), ``PEAK_OVER_NOISE``), the classifier's ``in_order`` and, for its
group's data, the swap cost
ΔE (:func:`~tiremodal_cli.modal.merge.swap_cost`) of the nearest stronger pole of another
group (what keeps it apart in the merge: above the χ²(2)/2 quantile 6.9).
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np

from spurious import classify_spurious, matrix_parser, spurious_cases
from tiremodal_cli.io.frffile import read_frf
from tiremodal_cli.modal import modes as stage
from tiremodal_cli.modal.groupfit import PEAK_OVER_NOISE
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.leaks import channel_mac
from tiremodal_cli.modal.options import ModalOptions


def rerun(run: Path):
    """The modal stage again on a kept run: (table, group modes, adopted merged modes, line Hz, live channels)."""
    with h5py.File(run / "modal.h5") as f:
        band = json.loads(f.attrs["meta"])["band_hz"]
    r = read_frf(run / "frf.h5")
    seen = {}
    merge, result = stage.merge_groups, stage._result

    def keep_found(found, **kw):
        seen["found"], seen["line"] = found, kw.get("line_hz", 0.0)
        return merge(found, **kw)

    def keep_modes(b, shape, modes, *a, **kw):
        seen["modes"], seen["n_ch"] = modes, b.Hb.shape[0]
        return result(b, shape, modes, *a, **kw)

    stage.merge_groups, stage._result = keep_found, keep_modes
    try:
        table, _ = stage.modal_table_from_frf(r, ModalOptions(band_hz=tuple(band)))
    finally:
        stage.merge_groups, stage._result = merge, result
    return table, seen["found"], seen["modes"], float(seen["line"]), seen["n_ch"]


def conditions(m, modes, found, line_hz: float, n_ch: int, min_significance: float = 0.05) -> str:
    """One line: the merged mode ``m`` against (a), (c)–(e) of ``under_residual`` and its merge's swap cost."""
    fn, zeta = poles_to_modal(np.array([o.pole for o in modes]))
    j = next(k for k, o in enumerate(modes) if o is m)
    over = [i for i, o in enumerate(modes) if o.group != m.group and o.peak > m.peak
            and abs(fn[j] - fn[i]) <= zeta[i] * fn[i]]
    mac = channel_mac(modes[max(over, key=lambda i: modes[i].peak)].residues, m.residues, n_ch) if over else np.nan
    flags = [m.significance < min_significance, m.frequency_std_hz > line_hz, bool(over), mac >= 0.9]
    txt = " ".join(c if ok else "-" for c, ok in zip("acde", flags))
    own = next(g for g in found if g.pole == m.pole and g.group == m.group)
    others = [g for g in found if g.group != m.group and g.peak > m.peak]
    swap = ""
    if others:
        near = min(others, key=lambda g: abs(g.pole.imag - m.pole.imag))
        f_near = poles_to_modal(np.array([near.pole]))[0][0]
        swap = f" swap vs {f_near:.2f} Hz (group {near.group}): {own.swap_cost(near.pole):.1f}"
    above = m.peak >= PEAK_OVER_NOISE * m.group_noise
    return (f"[{txt}] share {m.significance:.3f}, peak/residual {m.peak / max(m.group_noise, 1e-300):.2f}"
            f"{' (above ' + format(PEAK_OVER_NOISE, 'g') + ')' if above else ''}, "
            f"scatter {m.frequency_std_hz:.2f} Hz (line {line_hz:.3g}), MAC {mac:.3f}, groups "
            f"{sorted(m.order_energy)}{swap}")


def main(argv=None) -> int:
    a = matrix_parser(__doc__).parse_args(argv)
    for rec, run, truth, rows in spurious_cases(a.records, a.keep, a.only):
        table, found, modes, line_hz, n_ch = rerun(run)
        print(f"{rec['name']}: {rec['spurious']} spurious of {rec['adopted']}")
        for s in classify_spurious(rows, truth):
            m = modes[s["row"]]
            print(f"  {s['frequency_hz']:8.2f} Hz {s['class']:8s} group {m.group:3d} in_order "
                  f"{rows[s['row']].get('in_order', '')}: {conditions(m, modes, found, line_hz, n_ch)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
