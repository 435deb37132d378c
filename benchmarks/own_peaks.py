"""What the own-peak rule reads for each weak candidate, against the generator's truth.

    python benchmarks/validation.py --jobs 1 --keep /tmp/K --out /tmp/K.jsonl --no-docs
    python benchmarks/own_peaks.py /tmp/K.jsonl /tmp/K --only paper:physics=sidewall_membrane --band 285 380

The modal stage is run again on each kept case's ``run/frf.h5`` over the kept band (the
same table: the stage is deterministic) with :func:`tiremodal_cli.modal.groupfit.own_peaks`
wrapped, and the last verdict of every pole of every order group (its final pass) is
printed with the rule's quantities: its group, its share (the larger of the physical and
the in-group significance), its peak over the group's residual RMS per line ((b),
``PEAK_OVER_NOISE``), its cluster's scatter over the model orders and the standard error
σ_f of :func:`~tiremodal_cli.modal.groupfit.pin_limit` (both in lines; (c)), whether its
half-power band lies inside the analysis band, whether it is outside every stronger
group mode's band ((a)) and alone in its half-power band (the condition of the σ_f
bound), the verdict, and the nearest truth mode of *any* kind (the generator's, expected
or not: a pole between two aliases of its group is told from one on a mode), with the
orders that alias into the pole's group (n ≡ ±group mod N).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from spurious import folder_of, matrix_parser
from spurious_poles import rerun
from tiremodal_cli.modal import groupfit
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.validation import Case, config_for


def candidates(run: Path) -> list:
    """Every group pole's last own-peak verdict on a rerun of the kept modal stage: dicts."""
    seen, wrapped = {}, groupfit.own_peaks

    def logged(data, s, residues, synthesis, strength, std_hz):
        out = wrapped(data, s, residues, synthesis, strength, std_hz)
        fn, zeta = poles_to_modal(s)
        res = data.rows - synthesis
        noise = np.sqrt(np.mean(np.sum(res.real**2 + res.imag**2, axis=0)))
        peak = np.linalg.norm(residues, axis=0) * np.abs(s) ** 2 / np.abs(s.real) / noise
        df, hw = data.freq[1] - data.freq[0], zeta * fn
        sigma = np.sqrt(2 * hw * df / np.pi) / np.maximum(peak, np.finfo(float).tiny)
        for r in range(s.size):
            stronger = strength > strength[r]
            seen[(data.group, round(float(fn[r]), 1))] = {
                "group": int(data.group), "f": float(fn[r]), "share": float(strength[r]), "peak": float(peak[r]),
                "scatter": float(std_hz[r] / df), "sigma": float(sigma[r] / df),
                "inside": bool(fn[r] - hw[r] >= data.freq[0] and fn[r] + hw[r] <= data.freq[-1]),
                "a": not np.any(stronger & (np.abs(fn - fn[r]) <= np.maximum(hw, df))),
                "alone": not np.any(stronger & (np.abs(fn - fn[r]) < hw + hw[r])), "kept": bool(out[r])}
        return out

    groupfit.own_peaks = logged
    try:
        rerun(run)
    finally:
        groupfit.own_peaks = wrapped
    return sorted(seen.values(), key=lambda c: c["f"])


def main(argv=None) -> int:
    ap = matrix_parser(__doc__)
    ap.add_argument("--band", nargs=2, type=float, default=(0.0, np.inf), metavar=("LO", "HI"), help="Hz")
    a = ap.parse_args(argv)
    for line in Path(a.records).read_text(encoding="utf-8").splitlines():
        rec = json.loads(line)
        if a.only and rec["name"] not in a.only:
            continue
        case = Case(**{k: v for k, v in rec["case"].items() if k in Case.__dataclass_fields__})
        truth = simulate(config_for(case)).truth["modes"]
        tf = np.array([t["frequency_hz"] for t in truth])
        n_pts = case.n_points
        print(f"## {rec['name']}\n\n| group | f Hz | truth (nearest) | err % | aliases in group | share | peak/res "
              "| scatter (lines) | σ_f (lines) | inside | (a) | alone | kept |\n|" + "---|" * 13)
        for c in candidates(Path(a.keep) / folder_of(rec["name"]) / "run"):
            if not a.band[0] <= c["f"] <= a.band[1]:
                continue
            k = int(np.argmin(np.abs(tf - c["f"])))
            ali = sorted({t["n"] for t in truth if t["branch"] in ("same", "opposite")
                          and c["group"] >= 0 and min(t["n"] % n_pts, -t["n"] % n_pts) == c["group"]
                          and abs(t["frequency_hz"] - c["f"]) < 0.1 * c["f"]})
            print(f"| {c['group']} | {c['f']:.2f} | {tf[k]:.2f} n={truth[k]['n']} {truth[k]['branch']} "
                  f"| {100 * (c['f'] / tf[k] - 1):+.2f} | {ali} | {c['share']:.3f} | {c['peak']:.1f} "
                  f"| {c['scatter']:.2f} | {c['sigma']:.2f} | {c['inside']:d} | {c['a']:d} | {c['alone']:d} "
                  f"| {c['kept']:d} |")
        print()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
