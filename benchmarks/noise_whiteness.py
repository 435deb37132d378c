"""How far the order groups' residuals are from the flat noise the modal stage's tests assume.

The modal stage judges every pole against the noise of its group's rows
(``groupfit._above_noise``, ``groupfit.row_visibility``, ``refine``): one variance per row,
σ² = median |e|² / ln 2 over the band (the median of a complex Gaussian's power), as if the
noise were white and of one level over the whole band. This script measures that
assumption on a kept validation run (``benchmarks/validation.py --keep DIR``): for each case
the residual of the final modal model (``modal.h5``'s synthesis) is split into the grid's
order groups (``spatial.decompose``), and for every row the share of lines whose power
exceeds ln(1000) σ² is counted — a complex Gaussian of variance σ² exceeds it on 0.1 % of
lines. The same count with a local σ² (the running median of the power over ``--window``
lines, / ln 2) tells a noise whose level changes over the band (the force spectrum's
roll-off, the form's power of ω) from a misfit at the modes: the first falls to ≈ 0.1 %
with the local σ², the second does not.

    python benchmarks/noise_whiteness.py KEEP_DIR [--window 101]

Prints one line per case and the medians; stdout is data (tab-separated), stderr the summary.
Measured on session 16's final run in docs/lsce.md ("The noise the tests assume").
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import h5py
import numpy as np
import scipy.ndimage

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.spatial import decompose

#: a complex Gaussian's power exceeds ln(1/p) σ² with probability p
LEVEL_P = 1e-3


def exceedance(groups, window: int) -> tuple[float, float, float]:
    """(share of lines over the flat σ²'s 0.1 % level, the same with the local σ², the median
    over rows of mean power / flat σ²) in %, %, ratio.

    groups : iterable of (n_rows, K) complex arrays, the residual's rows ; window : lines of
    the running median that gives the local σ².
    """
    level = np.log(1 / LEVEL_P)
    over = over_local = total = 0
    ratio = []
    for rows in groups:
        p = rows.real**2 + rows.imag**2
        flat = np.median(p, axis=1, keepdims=True) / np.log(2)
        local = scipy.ndimage.median_filter(p, size=(1, window), mode="nearest") / np.log(2)
        over += int(np.sum(p > level * flat))
        over_local += int(np.sum(p > level * local))
        total += p.size
        ratio += list(p.mean(axis=1) / flat[:, 0])
    return 100 * over / total, 100 * over_local / total, float(np.median(ratio))


def case_exceedance(run: Path, window: int) -> tuple[float, float, float]:
    """:func:`exceedance` of one kept case's ``run`` folder: the residual of its modal model,
    in accelerance, by order group."""
    with h5py.File(run / "frf.h5", "r") as f, h5py.File(run / "modal.h5", "r") as m:
        freq, H, live, angle = f["freq_hz"][:], f["frf"][:], f["channel_live"][:], f["point_angle"][:]
        q = FORM_POWER[str(f.attrs["form"])]
        lo, hi = json.loads(m.attrs["meta"])["band_hz"]
        w = (freq >= lo - 1e-9) & (freq <= hi + 1e-9)
        res = (H[live][:, :, w] - m["synthesis"][:][live]) * (2j * np.pi * freq[w]) ** (2 - q)  # accelerance
    return exceedance((rows for rows, _ in decompose(res, angle).values()), window)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("keep", type=Path, help="a validation run's --keep folder")
    ap.add_argument("--window", type=int, default=101, help="lines of the running median (local σ²)")
    a = ap.parse_args(argv)
    runs = sorted(p for p in a.keep.glob("*/run") if (p / "modal.h5").exists())
    if not runs:
        print(f"no kept case (*/run/modal.h5) under {a.keep}", file=sys.stderr)
        return 2
    print("case\tover_flat_pct\tover_local_pct\tmean_over_flat")
    rows = []
    for run in runs:
        r = case_exceedance(run, a.window)
        rows.append(r)
        print(f"{run.parent.name}\t{r[0]:.2f}\t{r[1]:.2f}\t{r[2]:.2f}")
    x = np.array(rows)
    print(f"{len(rows)} cases; lines over the {100 * LEVEL_P:g} % level of white noise: flat σ² median "
          f"{np.median(x[:, 0]):.2f} % (range {x[:, 0].min():.2f}–{x[:, 0].max():.2f} %), local σ² ({a.window} "
          f"lines) median {np.median(x[:, 1]):.2f} % (range {x[:, 1].min():.2f}–{x[:, 1].max():.2f} %); "
          f"mean power over flat σ²: median {np.median(x[:, 2]):.2f} (white noise: 1)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
