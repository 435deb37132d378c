"""The Cramér–Rao bound of a mode's frequency under the poly-reference model: how well
*any* unbiased estimator that knows each mode's residues are rank one (one participation
vector over the channels, one shape over the points) could place it, from the test's
FRFs, its neighbours and the noise. ``benchmarks/crlb.py`` reports it beside its
unstructured and one-order bounds (``sigma_r``).

The model is the one every poly-reference estimator fits (LSCE, pLSCF): FRFs between the
fixed sensors c and the roved points p as a sum of complex-conjugate pole pairs, each
with a rank-one residue matrix,

    H_cp(ω) = w(ω) Σ_r [ l_rc ψ_rp / (iω − λ_r) + conj(l_rc ψ_rp) / (iω − conj λ_r) ],

w(ω) the FRF form's factor (−ω² for accelerance), with circular complex Gaussian noise of
variance σ_c(ω)² on each line, the same at every point of a channel. Unknowns: each pole
λ_r (2 real), its participation l_r (complex, one entry per channel, one of which is held as
the scale) and its shape ψ_r.

What an estimator may know of the shapes decides what it can resolve. Given the points'
angles, a tyre's shapes are written in the points' circumferential harmonics (an
orthonormal basis: cos kθ, sin kθ): an axisymmetric tyre's mode of order n is one
harmonic, its alias on the grid, so modes of different orders are told apart by the
circumferential decomposition whatever their frequencies (as the estimator's order groups
do). Each mode's shape is unknown on the harmonics it shows above the noise — those whose
contribution at the mode's peak, |w l_c ψ̂_k| / (ζω), reaches the noise's std σ_c there —
and held at zero on the others (a component under the noise is one no estimator sees).
Without angles every point is free (the plain poly-reference model).

The Fisher information of (poles, l) is formed with the shapes eliminated harmonic by
harmonic (their Schur complement); the target pole's Im λ keeps the information the other
parameters leave it (another Schur complement, by pseudo-inverse where some other parameter
is not identifiable: Stoica & Marzetta 2001), and its bound over Im λ_r is the relative
standard deviation of the damped frequency.

Unlike crlb.py's one-order model (residues free per channel), the participation is shared
by the channels: a weak mode of one branch beside a strong one of the other branch and the
same alias class is told apart by how tread and sidewall move together.

Only neighbours matter for a mode's bound, so each mode's bound is taken over a window:
the poles within two half-power bandwidths of it (2ζf each) are unknowns, and the lines
within two of their own bandwidths of any of them are the data. Two bandwidths hold all
but 0.6 % of a pole's frequency information (its density ∝ 1 / (1 + x²)², x the distance
from the peak in units of ζω: ∫_{|x|>4} / ∫ = 0.006). Poles outside the window are held
known, which can only make the bound smaller (more modes counted within reach); so are
those beyond the nearest :data:`MAX_WINDOW_POLES` in a crowd. Against the whole band's
lines, the window's bound is 5–6 % larger (the two close modes of
tests/test_crlb_polyref.py). Measured on the matrix's mixed-shape cases: a window of three
bandwidths moves bounds by up to 40 %, and beside a crowd the cap decides — the paper's
n = N same at 167.3 Hz, beside the crowd converging on 167.8 Hz, reads 0.02 % with 24 free
poles and 180 % with 40 — which is why this bound is a diagnostic, not the ruler's rule.

Written by hand: no library computes Fisher information of a modal model; the linear
algebra is numpy's.
"""

from __future__ import annotations

import numpy as np

__all__ = ["frequency_bounds", "harmonic_basis", "WINDOW_BANDWIDTHS", "MAX_WINDOW_POLES"]

#: Half-width of a mode's window, in its half-power bandwidths 2ζf (module docstring).
WINDOW_BANDWIDTHS = 2.0

#: Most unknown poles in one window (the nearest, in bandwidths): a compute budget, the
#: cost growing as its square. More are held known, which only lowers the bound.
MAX_WINDOW_POLES = 24


def harmonic_basis(point_angle_rad) -> np.ndarray:
    """Orthonormal circumferential harmonics on the points, (n_p, n_p): columns 1, cos θ,
    sin θ, cos 2θ, … (lowest order first), orthonormalised on the points' own angles
    (exact harmonics on an equispaced grid)."""
    th = np.asarray(point_angle_rad, dtype=float)
    cols = [np.ones_like(th)]
    k = 1
    while len(cols) < th.size:
        cols.append(np.cos(k * th))
        if len(cols) < th.size:
            cols.append(np.sin(k * th))
        k += 1
    q, r = np.linalg.qr(np.array(cols).T)
    return q * np.sign(np.diag(r))[None, :]


def _columns(jw, w, lam):
    """w / (iω − λ), w / (iω − λ̄) and their derivatives in λ: four (K, M) arrays."""
    d1 = jw[:, None] - lam[None, :]
    d2 = jw[:, None] - np.conj(lam)[None, :]
    a, b = w[:, None] / d1, w[:, None] / d2
    return a, b, a / d1, b / d2


def _window_fisher(jw, w, lam, L, P, S, noise):
    """Fisher information of (Re λ, Im λ, l) over one window, the shapes eliminated.

    jw, w : (K,) iω and the form's factor on the window's lines
    lam : (M,) poles; L : (M, n_ch) participations
    P : (M, n_k) shapes on the spatial coordinates; S : (M, n_k) bool, where each is unknown
    noise : (n_ch, K) noise std (> 0)

    Returns F (2M + 2M n_ch, 2M + 2M n_ch): parameters ordered Re λ (M), Im λ (M),
    Re l (M × n_ch, mode-major), Im l (same).
    """
    M, n_ch = L.shape
    used = S.any(axis=0)
    P, S = P[:, used], S[:, used]
    n_k, K = P.shape[1], jw.size
    a, b, a2, b2 = _columns(jw, w, lam)
    g = np.sqrt(2.0) / noise  # whitening: Re, Im each σ²/2

    def real(X):  # (..., n_ch, K, n) complex → (..., 2 n_ch K, n) real, whitened
        X = X * g[..., None]
        X = X.reshape(X.shape[:-3] + (n_ch * K, X.shape[-1]))
        return np.concatenate([X.real, X.imag], axis=-2)

    # shape columns ∂H_ck/∂Re ψ̂_rk, ∂/∂Im ψ̂_rk: the same on every coordinate, masked to
    # the modes unknown there
    Lt = L.T[:, None, :]  # (n_ch, 1, M)
    B = np.concatenate([Lt * a + np.conj(Lt) * b, 1j * (Lt * a - np.conj(Lt) * b)], axis=-1)
    mask = np.concatenate([S.T, S.T], axis=1)[:, None, :].astype(float)  # (n_k, 1, 2M)
    U, s, _ = np.linalg.svd(real(B)[None] * mask, full_matrices=False)
    U = U * (s > 1e-12 * s.max(axis=-1, keepdims=True))[:, None, :]
    # pole and participation columns on every coordinate: (n_k, n_ch, K, 2M + 2M n_ch)
    R = L.T[None, :, None, :] * P.T[:, None, None, :]  # (n_k, n_ch, 1, M)
    poles = np.concatenate([R * a2 + np.conj(R) * b2, 1j * (R * a2 - np.conj(R) * b2)], axis=-1)
    Pt = P.T[:, None, :]  # (n_k, 1, M)
    eye = np.eye(n_ch)[None, :, None, :, None]

    def on_own_channel(col):  # (n_k, K, M) → (n_k, n_ch, K, M n_ch), mode-major (r, c)
        x = eye * col[:, None, :, None, :]  # (n_k, n_ch, K, n_ch, M)
        return x.swapaxes(-1, -2).reshape(n_k, n_ch, K, M * n_ch)

    # ∂H_ck/∂Re l_rc = ψ̂ a + conj(ψ̂) b, ∂/∂Im l_rc = i ψ̂ a − i conj(ψ̂) b, channel c only
    l_re = on_own_channel(Pt * a[None] + np.conj(Pt) * b[None])
    l_im = on_own_channel(1j * (Pt * a[None] - np.conj(Pt) * b[None]))
    Ar = real(np.concatenate([poles, l_re, l_im], axis=-1))  # (n_k, 2 n_ch K, n_par)
    E = (Ar - U @ (U.swapaxes(-1, -2) @ Ar)).reshape(-1, Ar.shape[-1])
    return E.T @ E


def _support(lam, L, Phat, noise_at, w_at):
    """Where each mode's shape is unknown: the coordinates whose contribution at the mode's
    peak reaches the noise there (module docstring), and always its largest."""
    zw = -lam.real  # ζω_n
    amp = np.abs(w_at)[:, None, None] * np.abs(L)[:, :, None] * np.abs(Phat)[:, None, :] / zw[:, None, None]
    snr = (amp / noise_at[:, :, None]).max(axis=1)  # (G, n_k)
    S = snr >= 1.0
    S[np.arange(lam.size), np.argmax(np.abs(Phat), axis=1)] = True
    return S


def frequency_bounds(freq_hz, poles, participation, shapes, noise, *,
                     point_angle_rad=None, form: str = "accelerance", targets=None) -> np.ndarray:
    """Relative Cramér–Rao bound of each pole's damped frequency (module docstring).

    Parameters
    ----------
    freq_hz : (K,) array     the FRF lines the test has, Hz (> 0)
    poles : (G,) complex     λ = −ζω_n + iω_d, rad/s
    participation : (G, n_ch) complex   l_r
    shapes : (G, n_p) complex           ψ_r (the residue of channel c at point p is l_rc ψ_rp)
    noise : (n_ch, K) float              σ_c(f), the std of each line's complex error (in the
        form's units); a channel whose noise is not finite and positive on every line is
        left out (it records nothing: a clamped rim)
    point_angle_rad : (n_p,) array, optional, keyword-only   the points' angles: shapes
        known to be circumferential harmonics (module docstring); default every point free
    form : {"accelerance", "mobility", "receptance"}, keyword-only
    targets : iterable of int, optional   the poles to bound (default: all)

    Returns
    -------
    (G,) ndarray : std(ω_d) / ω_d; inf where the window's information is singular, nan
    for a pole not in ``targets``.
    """
    f = np.asarray(freq_hz, dtype=float)
    lam = np.asarray(poles, dtype=complex)
    L = np.asarray(participation, dtype=complex)
    P = np.asarray(shapes, dtype=complex)
    noise = np.asarray(noise, dtype=float)
    ch = np.all(np.isfinite(noise) & (noise > 0), axis=1)
    L, noise = L[:, ch], noise[ch]
    omega = 2 * np.pi * f
    w = {"accelerance": -omega**2, "mobility": 1j * omega, "receptance": np.ones_like(omega)}[form]
    fn = np.abs(lam) / (2 * np.pi)
    bw = 2 * (-lam.real) / (2 * np.pi)  # 2ζ f_n, Hz
    if point_angle_rad is None:
        Phat, S = P, np.ones(P.shape, bool)
    else:
        Phat = P @ harmonic_basis(point_angle_rad)
        at = np.clip(np.searchsorted(f, fn), 0, f.size - 1)
        S = _support(lam, L, Phat, noise[:, at].T, w[at])
    out = np.full(lam.size, np.nan)
    for i in (range(lam.size) if targets is None else targets):
        out[i] = _bound_one(i, f, omega, w, lam, L, Phat, S, noise, fn, bw)
    return out


def _bound_one(i, f, omega, w, lam, L, Phat, S, noise, fn, bw) -> float:
    """The bound of pole ``i`` over its window (module docstring)."""
    dist = np.abs(fn - fn[i]) / bw[i]
    nu = np.flatnonzero(dist <= WINDOW_BANDWIDTHS)
    nu = np.sort(nu[np.argsort(dist[nu], kind="stable")[:MAX_WINDOW_POLES]])
    near = np.abs(f[:, None] - fn[nu][None, :]) <= WINDOW_BANDWIDTHS * bw[nu][None, :]
    k = np.flatnonzero(near.any(axis=1) & (f > 0))
    M, n_ch = nu.size, L.shape[1]
    if k.size == 0 or n_ch == 0:
        return np.inf
    F = _window_fisher(1j * omega[k], w[k], lam[nu], L[nu], Phat[nu], S[nu], noise[:, k])
    # the scale of each rank-one residue is shared by l and ψ: hold each mode's largest
    # participation fixed (both its parts)
    keep = np.ones(F.shape[0], bool)
    c0 = np.argmax(np.abs(L[nu]), axis=1)
    for j in range(M):
        keep[2 * M + j * n_ch + c0[j]] = False
        keep[2 * M + M * n_ch + j * n_ch + c0[j]] = False
    keep &= np.diag(F) > 0
    idx = np.flatnonzero(keep)
    at = np.flatnonzero(idx == M + int(np.flatnonzero(nu == i)[0]))
    if at.size == 0:
        return np.inf
    Fk = F[np.ix_(idx, idx)]
    d = np.sqrt(np.diag(Fk))
    Fs = Fk / d[:, None] / d[None, :]  # Jacobi scaling: the parameters' units differ by orders
    t = at[0]
    rest = np.delete(np.arange(idx.size), t)
    # the target's information once the others are estimated too (Schur complement); a
    # pseudo-inverse where some other parameter is not identifiable (Stoica & Marzetta 2001)
    info = Fs[t, t] - Fs[t, rest] @ np.linalg.pinv(Fs[np.ix_(rest, rest)], rcond=1e-12, hermitian=True) @ Fs[rest, t]
    if not info > 1e-12:
        return np.inf
    return float(1 / (np.sqrt(info) * d[t]) / abs(lam[i].imag))
