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

__all__ = ["harmonic_design", "max_order", "grid_points", "grid_design", "decompose", "leakage",
           "is_circumferential"]

#: how far (in grid steps) an angle may lie from its grid node: angles stored in single
#: precision (≈ 1e-7 rad) on grids of up to a few hundred points are far inside it
GRID_TOL_STEPS = 1e-3


def max_order(n_points: int) -> int:
    """Highest order the point grid resolves: ⌊n_points / 2⌋ (⌊(n_points − 1)/2⌋ keeps it
    square for odd counts)."""
    return n_points // 2


def grid_points(angles_rad) -> int:
    """The number of points of the uniform grid round the circle that the angles lie on.

    A test whose points failed (every hit of a point rejected) keeps its grid: 31 points
    left of a 40-point grid alias as the 40 do (n and 40 − n), not as 31 would. The grid
    is the smallest N ≥ the number of points, up to twice it (at most half the grid
    failed: points rounded to whole degrees would otherwise lie on a 360-point "grid"),
    with every angle within :data:`GRID_TOL_STEPS` of a step of 2π/N from the first;
    points on no such grid are their own (N = the number of points).
    """
    th = np.asarray(angles_rad, dtype=float)
    n_p = th.size
    if n_p < 2 or not np.all(np.isfinite(th)):
        return n_p
    steps = (th - th[0]) / (2 * np.pi)
    for n in range(n_p, 2 * n_p + 1):
        x = steps * n
        if np.max(np.abs(x - np.round(x))) <= GRID_TOL_STEPS and np.unique(np.mod(np.round(x), n)).size == n_p:
            return n
    return n_p


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


def grid_design(angles_rad) -> tuple[np.ndarray, list[tuple[int, str]]]:
    """The harmonic design of :func:`harmonic_design` for a set of points: on a uniform
    grid, complete or with points missing (:func:`grid_points`), the grid's orders
    0 … ⌊N/2⌋ (with gaps: more columns than points, solved for the minimum norm); on
    points that lie on no grid, the top orders dropped until there are no more columns
    than points."""
    th = np.asarray(angles_rad, dtype=float)
    n_grid = grid_points(th)
    n_max = max_order(n_grid)
    D, names = harmonic_design(th, n_max)
    while n_grid == th.size and D.shape[1] > th.size:  # unequal spacing, no grid: drop the top order
        n_max -= 1
        D, names = harmonic_design(th, n_max)
    return D, names


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

    The orders are those of the points' grid (:func:`grid_points`), 0 … ⌊N/2⌋. With points
    missing from the grid there are more harmonics than points, and the fit is the
    minimum-norm one: the grid's harmonics are orthogonal over the whole grid, so over a
    subset their rows stay well apart and every order keeps most of its energy in its own
    group (a missing point leaks a little of it into the others, as a gap in a DFT does).
    Dropping the top orders until the system is square instead gave an interpolation on
    the irregular subset that is nearly singular (condition number 288 for 31 of 40
    points), and the orders above the cut, folded in by it, mixed every group.
    """
    H = np.asarray(H)
    n_c, n_p, n_f = H.shape
    if n_p < 3:
        raise DataFormatError(f"a circumferential decomposition needs ≥ 3 points; got {n_p}")
    D, names = grid_design(angles_rad)
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


def leakage(angles_rad) -> dict[tuple[int, int], float]:
    """How much of an order-m pattern the decomposition of :func:`decompose` puts into
    group n ≠ m, at most, against what it leaves in group m:
    {(n, m): ‖P_n D_m‖₂ / σ_min(P_m D_m)} (D_k the grid's columns of order k at the
    points, P_k the rows of order k of the minimum-norm solve: the order-k coefficients
    of a pattern D_m c are P_k D_m c). Zero (to rounding) on a complete uniform grid; with
    points missing, each order leaks into every other (31 of 40 points: up to 0.2).
    """
    D, names = grid_design(angles_rad)
    P = np.linalg.pinv(D)
    orders = sorted({n for n, _ in names})
    cols = {n: [k for k, (m, _) in enumerate(names) if m == n] for n in orders}
    out = {}
    for m in orders:
        s_min = np.linalg.svd(P[cols[m]] @ D[:, cols[m]], compute_uv=False)[-1]
        for n in orders:
            if n != m:
                out[(n, m)] = float(np.linalg.norm(P[cols[n]] @ D[:, cols[m]], 2) / s_min) if s_min > 0 else np.inf
    return out


def is_circumferential(point_angle, channel_location) -> bool:
    """True when the points go round the tread (≥ 8 distinct angles spanning > 270°) and a
    tread channel exists: the data of a tyre test."""
    a = np.mod(np.asarray(point_angle, dtype=float), 2 * np.pi)
    if a.size < 8 or "tread" not in tuple(channel_location) or not np.all(np.isfinite(a)):
        return False
    a = np.sort(a)  # the points may be stored from any origin, in either direction
    gaps = np.diff(np.concatenate([a, a[:1] + 2 * np.pi]))
    return len(np.unique(np.round(a, 9))) >= 8 and gaps.max() < np.pi / 2
