"""Least-squares frequency-domain (LSFD) residues, re-synthesis, MPC.

Given poles s_r (Im s_r > 0), every FRF of the band is fitted, in its own form (q = 0
receptance, 1 mobility, 2 accelerance), by

    H_j(ω) = (iω)^q Σ_r [R_jr / (iω − s_r) + R̄_jr / (iω − s̄_r)] + LR_j (iω)^(q−2) + UR_j (iω)^q

with complex residues R_jr and real lower and upper residual terms (the modes below and
above the band: a mass line and a stiffness line in receptance). The basis depends on
the poles only, so one real least-squares factorisation serves all FRFs.

References
----------
Maia & Silva (1997), *Theoretical and Experimental Modal Analysis*, §4.5.
Pappa, Elliott & Schenk (1993), Consistent-mode indicator for the eigensystem
realization algorithm, J. Guidance 16(5) — the modal phase collinearity (MPC).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from tiremodal_cli.conventions import FORM_POWER

__all__ = ["FORM_POWER", "LSFDResult", "lsfd", "pole_basis", "synthesize", "mpc", "significance"]



@dataclass(frozen=True)
class LSFDResult:
    """Residues and residual terms of every FRF.

    residues : (n_frf, n_modes) complex ; lower, upper : (n_frf,) real
    synthesis : (n_frf, K) complex     the re-synthesised FRFs on the band's lines
    error : (n_frf,) ndarray           ‖H − Ĥ‖ / ‖H‖ per FRF over the band
    """

    residues: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    synthesis: np.ndarray
    error: np.ndarray


def pole_basis(freq_hz, s, q, lower, upper):
    """The LSFD columns of poles ``s`` on ``freq_hz`` in form power ``q``: (K, 2 n_modes [+ 1 + 1])
    complex — Re R and Im R of every mode, then the lower and upper residual terms."""
    jw = 2j * np.pi * np.asarray(freq_hz, dtype=float)[:, None]
    s = np.asarray(s, dtype=complex)[None, :]
    a, b = 1 / (jw - s), 1 / (jw - np.conj(s))
    cols = [jw**q * (a + b), jw**q * 1j * (a - b)]  # Re R and Im R
    if lower:
        cols.append(jw ** (q - 2))
    if upper:
        cols.append(jw**q)
    return np.concatenate(cols, axis=1)


def synthesize(freq_hz, residues, s, *, form="accelerance", lower=None, upper=None):
    """FRFs of a modal model on ``freq_hz``: (n_frf, n_freq) complex."""
    q = FORM_POWER[form]
    jw = 2j * np.pi * np.asarray(freq_hz, dtype=float)[None, None, :]
    R = np.asarray(residues)[:, :, None]
    s = np.asarray(s)[None, :, None]
    H = (jw**q * (R / (jw - s) + np.conj(R) / (jw - np.conj(s)))).sum(axis=1)
    if lower is not None:
        H = H + np.asarray(lower)[:, None] * jw[0] ** (q - 2)
    if upper is not None:
        H = H + np.asarray(upper)[:, None] * jw[0] ** q
    return H


def lsfd(freq_hz, H, s, *, form: str = "accelerance", lower: bool = True, upper: bool = True,
         fast: bool = False, weight=None) -> LSFDResult:
    """Fit residues and residual terms of all FRFs for the poles ``s``.

    Parameters
    ----------
    freq_hz : (K,) array, Hz (all > 0 when a lower residual is fitted in receptance form)
    H : (n_frf, K) complex array
    s : (n_modes,) complex array, rad/s, Im > 0
    form : {"receptance", "mobility", "accelerance"}
    fast : bool
        Solve the normal equations (Cholesky) and skip the re-synthesis: for the many small
        fits of a stabilization sweep, where only the shapes' MAC matters.
    weight : (K,) array, optional
        Each line's weight (1 / its noise's RMS): weighted least squares; the synthesis
        and fit error are of the unweighted FRFs.
    """
    q = FORM_POWER[form]
    freq_hz = np.asarray(freq_hz, dtype=float)
    H = np.asarray(H)
    n_m = len(s)
    A = pole_basis(freq_hz, s, q, lower, upper)
    Ar = np.concatenate([A.real, A.imag], axis=0)
    Y = np.concatenate([H.real, H.imag], axis=1).T  # (2K, n_frf)
    if weight is not None:
        w2 = np.tile(np.asarray(weight, dtype=float), 2)[:, None]
        Ar, Y = Ar * w2, Y * w2
    scale = np.linalg.norm(Ar, axis=0)
    scale[scale == 0] = 1
    As = Ar / scale
    x = None
    if fast:
        try:
            x = scipy.linalg.solve(As.T @ As, As.T @ Y, assume_a="pos") / scale[:, None]
        except (scipy.linalg.LinAlgError, ValueError):
            x = None
    if x is None:
        x = scipy.linalg.lstsq(As, Y, lapack_driver="gelsy")[0] / scale[:, None]
    R = (x[:n_m] + 1j * x[n_m:2 * n_m]).T
    k = 2 * n_m
    LR = x[k] if lower else np.zeros(H.shape[0])
    UR = x[k + int(lower)] if upper else np.zeros(H.shape[0])
    if fast:
        return LSFDResult(R, LR, UR, np.empty((0, 0)), np.empty(0))
    Hs = (A @ x).T
    err = np.linalg.norm(H - Hs, axis=1) / np.maximum(np.linalg.norm(H, axis=1), np.finfo(float).tiny)
    return LSFDResult(R, LR, UR, Hs, err)


def mpc(shape) -> float:
    """Modal phase collinearity of a complex shape (1: a real, normal mode; 0: no phase order).

    From the eigenvalues of the 2 × 2 covariance of the real and imaginary parts:
    MPC = ((λ₁ − λ₂) / (λ₁ + λ₂))².
    """
    v = np.ravel(shape)
    v = v[np.isfinite(v)]
    C = np.cov(np.vstack([v.real, v.imag]), bias=True) + np.outer([v.real.mean(), v.imag.mean()],
                                                                    [v.real.mean(), v.imag.mean()])
    lam = np.linalg.eigvalsh(C)
    tot = lam.sum()
    return float(((lam[1] - lam[0]) / tot) ** 2) if tot > 0 else 0.0


def significance(freq_hz, H, residues, s, *, form="accelerance") -> np.ndarray:
    """Share of the measured response near each mode that the mode itself explains.

    For mode r: ‖Ĥ_r‖ / ‖H‖ over the lines within its half-power band (at least ±2
    lines), summed over all FRFs. Near 1 for a mode that makes its own peak; small for a
    pole fitted to noise.
    """
    freq_hz = np.asarray(freq_hz, dtype=float)
    df = freq_hz[1] - freq_hz[0]
    fn = np.abs(s) / (2 * np.pi)
    zeta = -np.real(s) / np.abs(s)
    out = np.zeros(len(s))
    for r in range(len(s)):
        half = max(zeta[r] * fn[r], 2 * df)
        sel = np.abs(freq_hz - fn[r]) <= half
        if not sel.any():
            continue
        Hr = synthesize(freq_hz[sel], residues[:, [r]], [s[r]], form=form)
        den = np.linalg.norm(H[:, sel])
        out[r] = np.linalg.norm(Hr) / den if den > 0 else 0.0
    return out


def lsfd_participation(freq_hz, Y, s, L, *, form: str = "accelerance", weight=None):
    """LSFD with known participation factors (poly-reference).

    ``Y`` (n_out, n_ref, K): FRFs from every reference to every output; mode r has
    residues ψ_or L_r (L from the estimator, (n_modes, n_ref)), so each output has one
    complex unknown per mode plus real lower/upper residuals per reference. Two close
    poles with different participation stay apart, where a free residue per FRF would
    trade them off against each other. ``weight`` ((K,), optional): each line's weight,
    as :func:`lsfd`'s.

    Returns
    -------
    residues : (n_out, n_ref, n_modes) complex ; synthesis : (n_out, n_ref, K) complex
    """
    q = FORM_POWER[form]
    jw = 2j * np.pi * np.asarray(freq_hz, dtype=float)[:, None]
    s = np.asarray(s, dtype=complex)[None, :]
    L = np.asarray(L, dtype=complex)
    n_out, n_ref, K = Y.shape
    B, Bc = jw**q / (jw - s), jw**q / (jw - np.conj(s))  # (K, m)
    cols = []
    for h in range(n_ref):  # rows of reference h: Re ψ and Im ψ columns of every mode
        c1 = L[:, h][None, :] * B + np.conj(L[:, h])[None, :] * Bc
        c2 = 1j * (L[:, h][None, :] * B - np.conj(L[:, h])[None, :] * Bc)
        cols.append(np.concatenate([c1, c2], axis=1))
    A_modes = np.concatenate(cols, axis=0)  # (n_ref K, 2m)
    resid = np.zeros((n_ref * K, 2 * n_ref), dtype=complex)
    for h in range(n_ref):
        resid[h * K:(h + 1) * K, 2 * h] = jw[:, 0] ** (q - 2)
        resid[h * K:(h + 1) * K, 2 * h + 1] = jw[:, 0] ** q
    A = np.concatenate([A_modes, resid], axis=1)
    Ar = np.concatenate([A.real, A.imag], axis=0)
    Yc = Y.reshape(n_out, n_ref * K).T  # (n_ref K, n_out)
    Yr = np.concatenate([Yc.real, Yc.imag], axis=0)
    if weight is not None:
        w2 = np.tile(np.asarray(weight, dtype=float), 2 * n_ref)[:, None]
        Ar, Yr = Ar * w2, Yr * w2
    scale = np.linalg.norm(Ar, axis=0)
    scale[scale == 0] = 1
    x = scipy.linalg.lstsq(Ar / scale, Yr, lapack_driver="gelsy")[0] / scale[:, None]
    m = s.shape[1]
    psi = (x[:m] + 1j * x[m:2 * m]).T  # (n_out, m)
    residues = psi[:, None, :] * L.T[None, :, :]  # (n_out, n_ref, m)
    synth = (A @ x).T.reshape(n_out, n_ref, K)
    return residues, synth
