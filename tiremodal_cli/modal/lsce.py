"""Least-squares complex exponential (LSCE) poles over a band, for every model order.

Method (Brown, Allemang, Zimmerman & Mergeay 1979), in the band-limited complex form:

1. **Principal response functions.** The band's FRFs ``H (n_frf, K)`` are reduced by an
   SVD to the few combinations that carry their energy, ``H ≈ U P`` with ``U`` orthonormal
   (n_frf × r). Poles are common to all FRFs, so they are common to ``P``; the reduction
   removes noise and makes the sweep cheap. Shapes found in the reduced space map back
   through ``U``, and MAC values are the same in both spaces.
2. **Impulse responses of the band.** ``h = ifft(P)`` over the K lines of the band
   [f_lo, f_lo + K df): a complex signal with sample interval ``dt = 1/(K df)`` (not
   1/(2 f_max): the band is a zoom), in which each mode in the band is one damped
   exponential ``z_r^m`` with ``z_r = exp((s_r − i2π f_lo) dt)``.
3. **Autoregression, all orders at once.** For order p, ``h[k+p] + Σ_m α_m h[k+m] = 0``
   over all k and all PRFs. The normal matrix ``R = XᴴX`` of the Hankel rows
   ``[h[k], …, h[k+p_max]]`` is built once; every order's normal equations are its
   leading block, ``R[:p,:p] α = −R[:p,p]``, so the sweep costs one matrix product and
   small solves, instead of a stacked least squares rebuilt per order.
4. **Poles** are the roots z of ``z^p + Σ α_m z^m``; ``s = ln z / dt`` with the imaginary
   part placed in the band: ``f = f_lo + (Im(ln z) / (2π dt) mod K df)``.

References
----------
Brown, D. L., Allemang, R. J., Zimmerman, R. & Mergeay, M. (1979). Parameter estimation
techniques for modal analysis. SAE Technical Paper 790221.
Maia, N. M. M. & Silva, J. M. M. (eds.) (1997). *Theoretical and Experimental Modal
Analysis*, ch. 4.
"""

from __future__ import annotations

import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from tiremodal_cli.errors import DataFormatError, ParameterError

__all__ = ["Band", "band_lines", "bridge", "principal_responses", "normal_matrix", "sweep", "sweep_poly", "OrderPoles",
           "poles_to_modal"]


@dataclass(frozen=True)
class Band:
    """The analysis band: lines, impulse responses and their time base.

    Attributes
    ----------
    freq_hz : (K,) ndarray        the band's lines
    f_lo : float, Hz              first line
    width_hz : float              (K + G) × df, the impulse responses' period: the zoomed
                                  band's span and its guard's G lines (none: G = 0)
    dt : float, s                 1 / width_hz
    U : (n_frf, r) ndarray        principal directions (orthonormal)
    prf : (r, K) complex ndarray  the principal response functions (H ≈ U @ prf)
    irf : (r, K) complex ndarray  their impulse responses
    singular_values : (min(n_frf, K),) ndarray
    """

    freq_hz: np.ndarray
    f_lo: float
    width_hz: float
    dt: float
    U: np.ndarray
    prf: np.ndarray
    irf: np.ndarray
    singular_values: np.ndarray


def band_lines(freq_hz, band_hz) -> np.ndarray:
    """Boolean mask of the lines in ``band_hz``; ParameterError when outside the data."""
    freq_hz = np.asarray(freq_hz, dtype=float)
    if freq_hz.ndim != 1 or freq_hz.size < 4:
        raise DataFormatError(f"need at least 4 frequency lines; got {freq_hz.size}")
    df = np.diff(freq_hz)
    if not np.allclose(df, df[0], rtol=1e-6, atol=1e-9):
        raise DataFormatError("frequency lines are not evenly spaced")
    lo, hi = (freq_hz[0], freq_hz[-1]) if band_hz is None else map(float, band_hz)
    if not (lo < hi) or lo < freq_hz[0] - 1e-9 * abs(df[0]) or hi > freq_hz[-1] + 1e-9 * abs(df[0]):
        raise ParameterError(f"band {lo:g}–{hi:g} Hz is outside the data "
                             f"({freq_hz[0]:g}–{freq_hz[-1]:g} Hz) or empty")
    sel = (freq_hz >= lo - 1e-9 * df[0]) & (freq_hz <= hi + 1e-9 * df[0])
    if sel.sum() < 16:
        raise ParameterError(f"band {lo:g}–{hi:g} Hz holds {sel.sum()} lines; LSCE needs at least 16")
    return sel


def principal_responses(freq_hz, H, band_hz=None, *, rtol: float = 1e-4, max_components: int | None = None,
                        guard: int = 0) -> Band:
    """Reduce the band's FRFs to principal response functions and their impulse responses.

    Parameters
    ----------
    freq_hz : (n_freq,) array, Hz
    H : (n_frf, n_freq) complex array       any form (receptance, mobility, accelerance)
    band_hz : (lo, hi), optional
    rtol : float                            keep singular values ≥ rtol × the largest, and
                                            (with ≥ 8 of them) above 3 × the median of
                                            the lower half: the noise plateau
    max_components : int, optional
    guard : int                             guard lines after the band's top in the impulse
                                            responses (:func:`bridge`; :mod:`.guard`)

    Returns
    -------
    Band (``width_hz`` and ``dt`` those of the K + guard lines: the impulse responses' period)
    """
    H = np.asarray(H)
    if H.ndim != 2:
        raise DataFormatError(f"FRFs must be (n_frf, n_freq); got shape {H.shape}")
    sel = band_lines(freq_hz, band_hz)
    Hb = H[:, sel]
    if not np.all(np.isfinite(Hb)):
        bad = np.argwhere(~np.isfinite(Hb))[0]
        raise DataFormatError(f"FRF {bad[0]} has a non-finite value at {freq_hz[sel][bad[1]]:g} Hz in the band")
    f = np.asarray(freq_hz, dtype=float)[sel]
    K = f.size
    df = (f[-1] - f[0]) / (K - 1)
    U, s, Vh = scipy.linalg.svd(Hb, full_matrices=False)
    if s[0] == 0:
        raise DataFormatError("every FRF is zero in the band")
    r = int(np.sum(s >= rtol * s[0]))
    if s.size >= 8:
        # keep the signal subspace: above 3 × the noise plateau (median of the lower half)
        floor = 3.0 * np.median(s[s.size // 2:])
        r = max(1, min(r, int(np.sum(s > floor))))
    if max_components is not None:
        r = min(r, max_components)
    P = s[:r, None] * Vh[:r]
    irf = np.fft.ifft(bridge(P, guard), axis=-1)
    width = (K + max(guard, 0)) * df
    return Band(freq_hz=f, f_lo=float(f[0]), width_hz=width, dt=1.0 / width, U=U[:, :r], prf=P, irf=irf,
                singular_values=s)


def bridge(P, n_guard: int) -> np.ndarray:
    """The band's lines followed by ``n_guard`` guard lines bridging the top to the foot.

    Parameters
    ----------
    P : (..., K) complex ndarray     the band's lines (any leading shape: FRFs, PRFs)
    n_guard : int                    guard lines G ≥ 0

    Returns
    -------
    (..., K + G) complex ndarray: P, then the values on the straight line from P[..., -1]
    to P[..., 0] at the G points strictly between them (periodic data continuous).
    """
    P = np.asarray(P)
    if n_guard <= 0:
        return P
    t = np.arange(1, n_guard + 1) / (n_guard + 1.0)
    fill = P[..., -1:] * (1.0 - t) + P[..., :1] * t
    return np.concatenate([P, fill], axis=-1)


def normal_matrix(irf, p_max: int, *, skip: int = 0, stop: int | None = None) -> np.ndarray:
    """Normal matrix ``R = XᴴX`` of the Hankel rows ``[h[k], …, h[k+p_max]]``.

    Rows k = skip … L − 1 − p_max (or ``stop``) of every impulse response. R is
    (p_max+1) × (p_max+1) Hermitian; any order p ≤ p_max uses its leading block.
    """
    h = np.asarray(irf)
    L = h.shape[-1]
    last = (L - 1 - p_max) if stop is None else min(stop, L - 1 - p_max)
    if last - skip + 1 < p_max + 1:
        raise ParameterError(f"model order {p_max} is too high for {L} impulse-response samples per FRF "
                             f"(allowed up to {max(2, (L - skip) // 2 - 1)})")
    n_rows = last - skip + 1
    # X for all rows of all responses, as a strided view (no copy): (r, n_rows, p_max+1)
    X = np.lib.stride_tricks.sliding_window_view(h, p_max + 1, axis=-1)[:, skip:skip + n_rows]
    X = X.reshape(-1, p_max + 1)
    return X.conj().T @ X


@dataclass(frozen=True)
class OrderPoles:
    """Poles of one model order (all roots, before any selection).

    ``s`` continuous-time poles (rad/s) with the band's frequency offset restored,
    ``freq_hz`` and ``damping_ratio`` from them, ``z`` the discrete roots.
    """

    order: int
    s: np.ndarray
    z: np.ndarray
    freq_hz: np.ndarray
    damping_ratio: np.ndarray
    participation: np.ndarray | None = None  # (n_poles, n_ref), poly-reference only


def poles_to_modal(s):
    """Natural frequency (Hz) and damping ratio of continuous-time poles λ = −σ + iω_d."""
    s = np.asarray(s, dtype=complex)
    wn = np.abs(s)
    with np.errstate(divide="ignore", invalid="ignore"):
        zeta = np.where(wn > 0, -s.real / wn, 0.0)
    return wn / (2 * np.pi), zeta


def sweep(band: Band, orders, *, skip: int = 0, max_rows: int | None = None) -> list[OrderPoles]:
    """Poles for every model order of ``orders`` (each ≥ 1).

    ``max_rows`` limits the autoregression to the first samples of the impulse responses
    (default: 8 × the highest order, at least 1,024): the decaying responses' early part
    carries the signal, the late part mostly noise, and the cost grows with the rows.

    Returns
    -------
    list of OrderPoles, one per order, in the order given
    """
    orders = sorted({int(p) for p in orders})
    if not orders or orders[0] < 1:
        raise ParameterError(f"model orders must be ≥ 1; got {orders[:3]}")
    rows = max(8 * orders[-1], 1024) if max_rows is None else max_rows
    R = normal_matrix(band.irf, orders[-1], skip=skip, stop=skip + rows)
    out = []
    for p in orders:
        with warnings.catch_warnings():
            # orders above the data's rank (clean data) are ill-conditioned; their extra
            # roots are computational and the stabilization sorts them out
            warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
            try:
                alpha = scipy.linalg.solve(R[:p, :p], -R[:p, p], assume_a="her")
            except (scipy.linalg.LinAlgError, ValueError):
                alpha = scipy.linalg.lstsq(R[:p, :p], -R[:p, p], lapack_driver="gelsy")[0]
        # roots of z^p + α_{p-1} z^{p-1} + … + α_0: eigenvalues of the companion matrix
        z = np.linalg.eigvals(_companion(alpha))
        z = z[np.abs(z) > 0]
        lnz = np.log(z)
        f_off = np.mod(lnz.imag / (2 * np.pi * band.dt), band.width_hz)
        s = lnz.real / band.dt + 1j * 2 * np.pi * (band.f_lo + f_off)
        fn, zeta = poles_to_modal(s)
        out.append(OrderPoles(p, s, z, fn, zeta))
    return out


def _companion(alpha):
    p = alpha.size
    C = np.zeros((p, p), dtype=complex)
    C[0, :] = -alpha[::-1]
    if p > 1:
        C[1:, :-1] = np.eye(p - 1)
    return C


def sweep_poly(irf, orders, dt: float, f_lo: float, width_hz: float, *, max_rows: int | None = None,
               workers: int = 1) -> list[OrderPoles]:
    """Poly-reference LSCE (Vold et al. 1982): matrix autoregression over several references.

    ``irf`` (n_out, n_ref, L): impulse responses from every reference to every output.
    The model ``h_o(m+p) + Σ_k h_o(m+k) W_k = 0`` (rows h_o(m) over the references, W_k
    n_ref × n_ref) shares the W_k over outputs; a mode is ``h_o(m) = a_o z^m L`` with its
    participation L, so p orders give p·n_ref poles and a root of multiplicity up to n_ref
    — the two members of a split pair — is resolved. As in :func:`sweep`, the normal
    matrix is built once for the highest order and each order uses its leading block.

    ``workers`` > 1 solves the orders in that many threads (LAPACK releases the GIL; each
    order is computed exactly as alone, so the poles are the same to the bit).
    """
    h = np.asarray(irf)
    n_out, n_ref, L = h.shape
    orders = sorted({int(p) for p in orders})
    p_max = orders[-1]
    rows = max(8 * p_max * n_ref, 1024) if max_rows is None else max_rows
    last = min(L - 1 - p_max, rows - 1)
    if last + 1 < (p_max + 1) * n_ref:
        raise ParameterError(f"model order {p_max} is too high for {L} impulse-response samples")
    # X rows: (output, m) ; columns: (k, ref) for k = 0 … p_max
    win = np.lib.stride_tricks.sliding_window_view(h, p_max + 1, axis=-1)[:, :, :last + 1]  # (o, r, m, k)
    X = win.transpose(0, 2, 3, 1).reshape(n_out * (last + 1), (p_max + 1) * n_ref)
    R = X.conj().T @ X

    def one(p):
        return _poly_order(R, p, n_ref, dt, f_lo, width_hz)

    with warnings.catch_warnings():
        # orders above the data's rank are ill-conditioned (the filter is process-wide, so
        # it covers the worker threads, which all finish inside this block)
        warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)
        if workers > 1 and len(orders) > 1:
            with ThreadPoolExecutor(workers) as ex:
                return list(ex.map(one, orders))
        return [one(p) for p in orders]


def _poly_order(R, p: int, n_ref: int, dt: float, f_lo: float, width_hz: float) -> OrderPoles:
    """The poles and participation factors of order ``p`` from the normal matrix ``R``."""
    a, b = p * n_ref, (p + 1) * n_ref
    try:
        W = scipy.linalg.solve(R[:a, :a], -R[:a, a:b], assume_a="her")
    except (scipy.linalg.LinAlgError, ValueError):
        W = scipy.linalg.lstsq(R[:a, :a], -R[:a, a:b], lapack_driver="gelsy")[0]
    # L (z^p I + Σ z^k W_k) = 0: eigenvalues of the block companion of A_k = W_kᵀ
    A = np.stack([W[k * n_ref:(k + 1) * n_ref].T for k in range(p)])
    C = np.zeros((a, a), dtype=complex)
    for k in range(p):
        C[:n_ref, k * n_ref:(k + 1) * n_ref] = -A[p - 1 - k]
    if p > 1:
        C[n_ref:, :-n_ref] = np.eye(a - n_ref)
    z = scipy.linalg.eigvals(C, overwrite_a=True, check_finite=False)
    z = z[np.abs(z) > 0]
    part = _participation(A, z)
    lnz = np.log(z)
    f_off = np.mod(lnz.imag / (2 * np.pi * dt), width_hz)
    s = lnz.real / dt + 1j * 2 * np.pi * (f_lo + f_off)
    fn, zeta = poles_to_modal(s)
    return OrderPoles(p, s, z, fn, zeta, part)


def _participation(A, z):
    """(n_poles, n_ref) unit participation factors: the null vector of the matrix polynomial
    P(z) = z^p I + Σ_k A_k z^k at each pole (``A`` (p, n_ref, n_ref)).

    The block companion's eigenvector is [z^(p-1) L; …; z L; L], so its last block L is
    P(z)'s right null vector; taking it from a batched SVD of the n_ref × n_ref matrices
    instead of the companion's eigenvectors halves the sweep's eigen-solution (the
    eigenvalues alone). A root of multiplicity n_ref (a split pair) has a null space of its
    dimension, in which any unit vector is a participation.
    """
    n_ref = A.shape[1]
    P = np.broadcast_to(np.eye(n_ref, dtype=complex), (z.size, n_ref, n_ref)).copy()
    for k in range(A.shape[0] - 1, -1, -1):  # Horner
        P = P * z[:, None, None] + A[k]
    return np.linalg.svd(P)[2][:, -1, :].conj()
