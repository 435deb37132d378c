"""Circumferential decomposition of FRFs measured around an axisymmetric structure.

On a tyre every mode has one circumferential order n: its tread shape over the impact
angles is cos n(θ − φ). Fitting the FRFs of each response channel over the points with
the harmonics 1, cos θ, sin θ, …, cos Nθ (least squares, so missing points are allowed)
turns them into *order-n FRFs* that each hold only the modes of order n (and of the
orders that alias onto n on the point grid: N_p − n, N_p + n, …). Modes that crowd together
in frequency but differ in n — the paper's 179–193 Hz holds five — fall into different
groups and are estimated separately. This is the "spatial orthogonality of different n";
it is a preprocessing step: LSCE, stabilization and LSFD stay general.
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.errors import DataFormatError

__all__ = ["harmonic_design", "max_order", "decompose"]


def max_order(n_points: int) -> int:
    """Highest order the point grid resolves: ⌊n_points / 2⌋ (⌊(n_points − 1)/2⌋ keeps it
    square for odd counts)."""
    return n_points // 2


def harmonic_design(angles_rad, n_max: int) -> tuple[np.ndarray, list[tuple[int, str]]]:
    """Columns 1, cos θ, sin θ, …, cos n_max θ, sin n_max θ at the given angles.

    A column that vanishes on the grid, or a sine collinear with its cosine (n = N/2 on N
    uniform points, from any first angle), is left out: one column for that order.

    Returns
    -------
    D : (n_points, n_cols) ndarray ; columns : list of (n, "cos" | "sin")
    """
    th = np.asarray(angles_rad, dtype=float)
    cols, names = [np.ones_like(th)], [(0, "cos")]
    tiny = 1e-8 * np.sqrt(th.size)
    for n in range(1, n_max + 1):
        pair = [(kind, fn(n * th)) for kind, fn in (("cos", np.cos), ("sin", np.sin))]
        pair = [(kind, c) for kind, c in pair if np.linalg.norm(c) > tiny]
        if len(pair) == 2:
            (_, c), (_, sn) = pair
            # n = N/2 on N uniform points from any start: cos and sin are both ±1 times a
            # constant, one column; keep the larger
            if abs(c @ sn) >= (1 - 1e-10) * np.linalg.norm(c) * np.linalg.norm(sn):
                pair = [max(pair, key=lambda kc: np.linalg.norm(kc[1]))]
        for kind, c in pair:
            cols.append(c)
            names.append((n, kind))
    return np.column_stack(cols), names


def decompose(H, angles_rad) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Order-n FRFs of every channel, and the map back to the points.

    Parameters
    ----------
    H : (n_channels, n_points, n_freq) complex array
    angles_rad : (n_points,) array

    Returns
    -------
    groups : {n: (rows, back)}
        ``rows`` (n_rows, n_freq): the cos and sin coefficients of order n of every channel
        (rows ordered harmonic-major, channel-minor); ``back`` (n_channels·n_points, n_rows):
        the physical FRFs' share of them, so that ``Σ_n back_n @ rows_n`` equals the
        least-squares fit of H over the harmonics (H itself on a uniform grid).
    """
    H = np.asarray(H)
    n_c, n_p, n_f = H.shape
    if n_p < 3:
        raise DataFormatError(f"a circumferential decomposition needs ≥ 3 points; got {n_p}")
    n_max = max_order(n_p)
    D, names = harmonic_design(angles_rad, n_max)
    while D.shape[1] > n_p:  # fewer points than columns (missing points): drop the top order
        n_max -= 1
        D, names = harmonic_design(angles_rad, n_max)
    coef = np.linalg.lstsq(D, H.transpose(1, 0, 2).reshape(n_p, -1), rcond=None)[0]
    coef = coef.reshape(len(names), n_c, n_f)
    eye = np.eye(n_c)
    groups: dict[int, tuple[list, list]] = {}
    for k, (n, _) in enumerate(names):
        rows, cols = groups.setdefault(n, ([], []))
        rows.append(coef[k])
        # physical index (c, p) ← row (k, c'): D[p, k] δ(c, c')
        cols.append(np.einsum("p,cd->cpd", D[:, k], eye).reshape(n_c * n_p, n_c))
    return {n: (np.concatenate(r, axis=0), np.concatenate(c, axis=1)) for n, (r, c) in groups.items()}
