"""Order groups of a grid with missing points, read with the other orders' leaks taken out.

With points missing from a uniform grid the minimum-norm decomposition
(:func:`~tiremodal_cli.modal.spatial.decompose`) is underdetermined at each line (19 points,
24 harmonics): every order leaks into every other (:func:`~tiremodal_cli.modal.spatial.leakage`,
0.2–0.4), and each group's sweep sees the modes of all the others at once — the paper's
opposite branch above 450 Hz, a dozen modes of different orders within a bandwidth of each
other, was lost or biased by 0.3–0.5 %. A modal model removes the indeterminacy: a mode of
order m has the pattern D_m a (the grid's two columns of order m at the points) at every
line, so the modes found once fix a few unknowns each, over all lines.

:func:`order_lsfd` fits the physical FRFs with the modes found, each mode's residues held
to the span of the grid's columns of the orders it was found in (one LSFD over all points,
free residual terms per FRF); :func:`cleaned_groups` then gives each group its own modes'
coefficients at full size plus the minimum-norm decomposition of what the model leaves
(the modes not found yet, the noise): the found modes' leaks are gone, and the group's
sweep sees its own modes and the rest's residual leaks only. On a complete grid the
decomposition is exact and this is not used.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.special

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.band import window_noise_gain
from tiremodal_cli.modal.groupfit import NOISE_ALPHA
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import pole_basis, synthesize
from tiremodal_cli.modal.spatial import decompose, grid_design

__all__ = ["order_lsfd", "order_design", "min_norm_solve", "cleaned_groups", "weak_in_frfs"]


def order_lsfd(freq_hz, Hb, angles_rad, poles, orders, form: str = "accelerance") -> np.ndarray:
    """Residues of the modes on the grid's harmonic coefficients, fitted over every point.

    Model of the FRF of channel c at point p (as :func:`~tiremodal_cli.modal.lsfd.lsfd`):
    H_cp(ω) = (iω)^q Σ_r [R_cpr / (iω − s_r) + c.c.] + LR_cp (iω)^(q−2) + UR_cp (iω)^q with
    R_cpr = Σ_k D[p, k] X_rkc over the grid's columns k of the orders of mode r
    (:func:`~tiremodal_cli.modal.spatial.grid_design`). The lines are reduced once by a QR
    factorisation of the pole basis (‖Y − A x‖² = ‖Qᵀ Y − R x‖² + const), so the
    constrained least squares is over n_points × n_basis rows.

    Parameters
    ----------
    freq_hz : (K,) Hz ; Hb : (n_channels, n_points, K) complex ; angles_rad : (n_points,)
    poles : (n_modes,) complex, rad/s ; orders : list of sets of int, each mode's orders

    Returns
    -------
    X : (n_modes, n_cols, n_channels) complex — the residue of each mode on each of the
        grid's columns (zero on the columns of orders it does not hold)
    """
    D, names = grid_design(angles_rad)
    n_c, n_p, K = Hb.shape
    s = np.asarray(poles, dtype=complex)
    M = s.size
    A = pole_basis(freq_hz, s, FORM_POWER[form], True, True)  # (K, 2M + 2)
    Ar = np.concatenate([A.real, A.imag], axis=0)
    scale = np.linalg.norm(Ar, axis=0)
    scale[scale == 0] = 1
    Q, R = np.linalg.qr(Ar / scale)  # (2K, nb), (nb, nb)
    Y = np.concatenate([Hb.real, Hb.imag], axis=2).reshape(n_c * n_p, 2 * K)
    Z = (Y @ Q).reshape(n_c, n_p, -1).transpose(1, 2, 0)  # (n_p, nb, n_c)
    G, units = order_design(D, [[k for k, (n, _) in enumerate(names) if n in orders[r]] for r in range(M)], R, M)
    x = min_norm_solve(G, Z.reshape(-1, n_c))
    nu = len(units)
    X = np.zeros((M, len(names), n_c), dtype=complex)
    for u, (r, k) in enumerate(units):
        X[r, k] = x[u] / scale[r] + 1j * x[nu + u] / scale[M + r]
    return X


def min_norm_solve(G, Z) -> np.ndarray:
    """The minimum-norm least-squares solution of G x ≈ Z at G's numerical rank (singular
    values under eps · max(G.shape) of the largest dropped, numpy's default rank rule; SVD).

    The order-held design is exactly rank-deficient when a mode holds more of the grid's
    columns than there are points (a mode merged from many order groups: 21 columns on 19
    of 24 points gave four singular values at 1e-16 of the largest, the next at 5e-3); the
    pivoted QR of LAPACK's gelsy kept those directions and returned residues 10¹⁴ × the
    data's, which cancel in the FRFs but not in the order groups (session 14: every mode of
    the paper's failed-points combination lost, "no stable mode", at two of the
    five other seeds tried).
    """
    return scipy.linalg.lstsq(G, Z, cond=np.finfo(float).eps * max(G.shape), lapack_driver="gelsd",
                              check_finite=False)[0]


def order_design(D, cols, R, M: int) -> tuple:
    """The design of the order-held LSFD on the lines reduced by the pole basis's QR factor.

    D : (n_p, n_cols) the grid's columns at the points ; cols : per pole, its columns ; R :
    (nb, nb) the triangular factor of the scaled pole basis (the M poles' Re and Im columns,
    then the lower and upper residual terms) ; M : the number of poles.

    Returns G : (n_p · nb, 2 n_u + 2 n_p) real (each unit's Re and Im residue, then each
    point's residual terms) and the units [(pole, column)].
    """
    n_p, nb = D.shape[0], R.shape[0]
    units = [(r, k) for r in range(M) for k in cols[r]]
    nu = len(units)
    G = np.zeros((n_p, nb, 2 * nu + 2 * n_p))
    for u, (r, k) in enumerate(units):
        G[:, :, u] = D[:, k, None] * R[None, :, r]
        G[:, :, nu + u] = D[:, k, None] * R[None, :, M + r]
    for p in range(n_p):
        G[p, :, 2 * nu + 2 * p:2 * nu + 2 * p + 2] = R[:, 2 * M:2 * M + 2]
    return G.reshape(n_p * nb, -1), units


def cleaned_groups(freq_hz, Hb, angles_rad, poles, orders, form: str = "accelerance") -> dict:
    """Order groups as :func:`~tiremodal_cli.modal.spatial.decompose` gives them, with the
    modes found read out of the leaks.

    Group n's rows are its own modes' coefficients (:func:`order_lsfd`) plus group n of
    the minimum-norm decomposition of the FRFs less every mode found: rows_n = X_n +
    [D⁺(H − Σ_m D_m X_m)]_n. The sum over the groups of ``back_n @ rows_n`` is still the
    FRFs (D D⁺ = I on points of a grid). Arguments as :func:`order_lsfd`.

    Returns
    -------
    {n: (rows, back)} as :func:`~tiremodal_cli.modal.spatial.decompose`
    """
    n_c, n_p, K = Hb.shape
    D, names = grid_design(angles_rad)
    X = order_lsfd(freq_hz, Hb, angles_rad, poles, orders, form)
    # each grid column's modal coefficient of every channel: (n_cols · n_c, K)
    own = synthesize(freq_hz, X.transpose(1, 2, 0).reshape(-1, X.shape[0]), poles, form=form)
    own = own.reshape(len(names), n_c, K)
    model = np.einsum("pk,kcf->cpf", D, own)
    groups = decompose(Hb - model, angles_rad)
    out = {}
    for n, (rows, back) in groups.items():
        ks = [k for k, (m, _) in enumerate(names) if m == n]
        out[n] = (rows + own[ks].reshape(len(ks) * n_c, K), back)
    return out


def weak_in_frfs(modes, min_significance: float, freq_hz, angles_rad, residual,
                 alpha: float = NOISE_ALPHA, window=None) -> tuple[list, list]:
    """Drop the modes that explain under ``min_significance`` of the physical FRFs around
    their frequency, whatever their share within their order group, or no more there
    than a fit of their unknowns to the noise would.

    On a complete grid a group's rows are the data of one order, and a weak order beside a
    strong one of another order is kept by its share within its group
    (:func:`~tiremodal_cli.modal.groupfit.fit_group`). With points missing a group's rows
    are a construction — the grid has more harmonics than there are points, and group n
    holds the minimum-norm share of whatever the modal model leaves (the modes not found,
    the found ones' misfit) — so a share within it is no evidence of a mode; the physical
    FRFs are.

    The noise test: the mode's own response in its significance window (the lines within
    max(ζf, 2 lines), every FRF), E = Σ_frf ‖Ĥ_r‖² / σ²_frf (σ²: the median of
    ``residual``'s power / ln 2), is for p complex residues (its group's n_h columns × the
    channels) fitted to noise alone χ²(2p)/2 (least squares projects the noise on p complex
    dimensions); a mode must exceed its 1 − ``alpha``/K quantile (the band's K lines, as
    the group fit's noise test), times the pole's window gain κ_r (``window``, τ s and line
    Hz: :func:`~tiremodal_cli.modal.band.window_noise_gain`). Where the response is weak the
    rows of a grid with gaps hold poles fitted to the noise (the ring's 1,024 Hz combination:
    45.60 Hz, E at 0.65 × the quantile); a weak mode beside a strong one is far above it (its
    cavity n = 3, 7 % of its window, at 100 ×; docs/lsce.md, "Tyres: circumferential orders first").

    Parameters
    ----------
    modes : list of :class:`~tiremodal_cli.modal.merge.MergedMode`
    min_significance : float ; freq_hz : (K,) Hz, the band's lines ; angles_rad : (n_points,)
    residual : (n_frf, K) complex, the FRFs less the modal model (accelerance) ; alpha : float
    window : (τ s, line Hz) or None

    Returns
    -------
    kept : list ; dropped : list of dict (frequency, damping, group, reason)
    """
    _, names = grid_design(angles_rad)
    n_h = {n: sum(1 for m, _ in names if m == n) for n, _ in names}
    freq_hz = np.asarray(freq_hz, dtype=float)
    df = freq_hz[1] - freq_hz[0]
    var = np.maximum(np.median(np.abs(residual) ** 2, axis=1) / np.log(2), np.finfo(float).tiny)
    n_c = residual.shape[0] // len(angles_rad)
    kept, dropped = [], []
    for m in modes:
        f, z = poles_to_modal(m.pole)
        win = np.abs(freq_hz - f) <= max(z * f, 2 * df)
        p = n_h[m.group] * n_c
        e = float(np.sum(np.sum(np.abs(synthesize(freq_hz[win], m.residues[:, None], [m.pole])) ** 2, axis=1) / var))
        gain = float(window_noise_gain(-np.real(m.pole), *window)[0]) if window else 1.0
        ratio = e / (scipy.special.chdtri(2 * p, alpha / freq_hz.size) / 2 * gain)
        if m.significance >= min_significance and ratio > 1:
            kept.append(m)
            continue
        why = (f"{100 * m.significance:.1f} % of the response at its frequency" if m.significance < min_significance
               else f"{ratio:.2f} × what a fit of its {p} residues to the noise exceeds with probability {alpha:g}")
        dropped.append({"frequency_hz": float(f), "damping_ratio": float(z), "group": int(m.group),
                        "reason": f"insignificant in the FRFs of a grid with missing points: explains {why} "
                                  f"(its share within its group, {100 * m.significance_in_group:.1f} %, is no "
                                  f"evidence there)"})
    return kept, dropped
