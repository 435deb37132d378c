"""Poly-reference least-squares complex-frequency (pLSCF, "PolyMAX") poles, every model order.

Method (Guillaume et al. 2003; Peeters et al. 2004): a right matrix-fraction model of the
FRFs from n_i references to each output o,

    H_o(ω) ≈ N_o(ω) D(ω)⁻¹,   N_o = Σ_r Ω_r β_or (1 × n_i),   D = Σ_r Ω_r α_r (n_i × n_i),

with the z-domain basis Ω_r = z^r, z = exp(iω Δt), Δt = 1/(2 f_hi) (f_hi: the band's top
line). The equation error N_o − H_o D is linear in the coefficients; eliminating every
output's numerator leaves the *reduced normal equations*

    M = 2 Σ_o (T_o − S_oᵀ R_o⁻¹ S_o),   R_o = Re(XᴴX), S_o = Re(XᴴY_o), T_o = Re(Y_oᴴY_o),

X = [Ω_0 … Ω_p] (n_f × (p+1)), Y_o = −X ⊗ H_o (n_f × (p+1) n_i); with α_p = I (the
lower-right constraint), α_0 … α_{p−1} solve M[:pn_i, :pn_i] α = −M[:pn_i, pn_i:]. The poles
are the eigenvalues z of the block companion matrix of D, s = ln z / Δt, and the
eigenvectors' first block gives the participation factors.

Written here rather than taken from sdypy-EMA: its LSCF (0.31) returns poles with the
sign of σ reversed and one reference only; this one is poly-reference, shares the order
sweep's structure and the stabilization's inputs (:class:`.lsce.OrderPoles`).

References
----------
Guillaume, P., Verboven, P., Vanlanduit, S., Van der Auweraer, H. & Peeters, B. (2003). A
poly-reference implementation of the least-squares complex frequency-domain estimator.
Proc. IMAC XXI.
Peeters, B., Van der Auweraer, H., Guillaume, P. & Leuridan, J. (2004). The PolyMAX
frequency-domain method: a new standard for modal parameter estimation? Shock and
Vibration 11, 395–409.
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.modal.lsce import OrderPoles, poles_to_modal

__all__ = ["confirmed", "sweep_plscf"]


def sweep_plscf(freq_hz, H, orders) -> list[OrderPoles]:
    """pLSCF poles for every model order of ``orders``.

    Parameters
    ----------
    freq_hz : (K,) array, Hz — the band's lines
    H : (n_out, n_ref, K) complex array — FRFs (any form; accelerance recommended)
    orders : iterable of int ≥ 1 — polynomial orders p (p · n_ref poles each)

    Returns
    -------
    list of OrderPoles (with participation factors), one per order, ascending
    """
    f = np.asarray(freq_hz, dtype=float)
    H = np.asarray(H)
    if H.ndim != 3 or H.shape[-1] != f.size:
        raise ParameterError(f"pLSCF needs FRFs (n_out, n_ref, n_freq={f.size}); got {H.shape}")
    n_out, n_ref, K = H.shape
    orders = sorted({int(p) for p in orders})
    if not orders or orders[0] < 1:
        raise ParameterError(f"model orders must be ≥ 1; got {orders[:3]}")
    p_max = orders[-1]
    if (p_max + 1) * n_ref > K:
        raise ParameterError(f"model order {p_max} is too high for {K} lines and {n_ref} reference(s)")
    dt = 1.0 / (2.0 * f[-1])
    R, S, T = _reduced_blocks(f, H, p_max, dt)
    return [_order_poles(R, S, T, p, n_ref, dt) for p in orders]


def _reduced_blocks(f, H, p_max: int, dt: float):
    """R (p+1, p+1), S_o (n_out, p+1, m), T_o (n_out, m, m) of the reduced normal equations,
    once for the highest order (m = (p_max + 1) n_ref); an order p uses their leading blocks
    (the basis of order p is the first p + 1 columns)."""
    n_out, n_ref, K = H.shape
    X = np.exp(1j * 2 * np.pi * f[:, None] * dt * np.arange(p_max + 1)[None, :])  # (K, p+1)
    # scale each output so that none dominates the sum of the reduced equations
    w = 1.0 / np.maximum(np.sqrt(np.mean(np.abs(H) ** 2, axis=(1, 2))), np.finfo(float).tiny)
    m = (p_max + 1) * n_ref
    R = np.real(X.conj().T @ X)
    S = np.empty((n_out, p_max + 1, m))
    T = np.empty((n_out, m, m))
    for o in range(n_out):
        Y = -(X[:, :, None] * (w[o] * H[o].T)[:, None, :]).reshape(K, m)  # columns (r, ref)
        S[o] = np.real(X.conj().T @ Y)
        T[o] = np.real(Y.conj().T @ Y)
    return R, S, T


def _order_poles(R, S, T, p: int, n_ref: int, dt: float) -> OrderPoles:
    """The poles of order p: the numerator eliminated on the leading blocks (small:
    (p+1) n_ref square), the denominator's coefficients, its companion matrix's roots."""
    n_out = S.shape[0]
    a, b = p * n_ref, (p + 1) * n_ref
    Sp = S[:, :p + 1, :b]
    G = np.linalg.solve(R[:p + 1, :p + 1], Sp.transpose(1, 0, 2).reshape(p + 1, -1)).reshape(p + 1, n_out, b)
    Mp = T[:, :b, :b].sum(axis=0) - np.einsum("okc,kod->cd", Sp, G)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        try:
            alpha = scipy.linalg.solve(Mp[:a, :a], -Mp[:a, a:b], assume_a="sym")
        except (scipy.linalg.LinAlgError, ValueError):
            alpha = scipy.linalg.lstsq(Mp[:a, :a], -Mp[:a, a:b], lapack_driver="gelsy")[0]
    A = [alpha[r * n_ref:(r + 1) * n_ref] for r in range(p)]  # α_r (n_ref × n_ref): Σ z^r α_r v = 0
    C = np.zeros((a, a), dtype=complex)
    if p > 1:
        C[:-n_ref, n_ref:] = np.eye(a - n_ref)
    for r in range(p):
        C[-n_ref:, r * n_ref:(r + 1) * n_ref] = -A[r]
    z, V = np.linalg.eig(C)
    keep = np.abs(z) > 0
    z, V = z[keep], V[:, keep]
    s = np.log(z) / dt
    up = s.imag > 0  # real coefficients: roots in conjugate pairs, one of each kept
    z, V, s = z[up], V[:, up], s[up]
    part = V[:n_ref].T
    part = part / np.maximum(np.linalg.norm(part, axis=1, keepdims=True), np.finfo(float).tiny)
    fn, zeta = poles_to_modal(s)
    return OrderPoles(p, s, z, fn, zeta, part)


def confirmed(a, b) -> np.ndarray:
    """Which modes of ``a`` (a :class:`~tiremodal_cli.modal.modes.ModalResult`) the estimate
    ``b`` (another, of the other method) confirms: a mode of b within a quarter of
    a's half-power half-width (|Δf| ≤ ζ f / 4 — two modes that close cannot be told
    apart, so the two estimators saw one mode) and with a damping ratio within 30 %."""
    out = np.zeros(a.freq_hz.size, dtype=bool)
    for i, (f, z) in enumerate(zip(a.freq_hz, a.damping_ratio)):
        near = np.abs(b.freq_hz - f) <= 0.25 * z * f
        out[i] = bool(np.any(near & (np.abs(b.damping_ratio - z) <= 0.3 * z)))
    return out
