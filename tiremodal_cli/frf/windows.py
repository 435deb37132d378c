"""Impact-testing windows and the damping correction of the exponential window.

Force window: rectangular over the hammer pulse with a short cosine taper on each side,
zero elsewhere (removes the force channel's noise outside the pulse).
Exponential window ``w(t) = exp(−t/τ)`` on the responses *and* the force: because
``exp(−t/τ) = exp(−(t−s)/τ) exp(−s/τ)``, windowing both sides of a convolution leaves an
exact FRF of the same structure with every pole moved left by 1/τ. So the window adds a
known decay rate σ_w = 1/τ (rad/s) and the structure's own is σ = σ_est − 1/τ.
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.frf.hits import pulse_extent

__all__ = ["force_window", "exponential_window", "correct_damping", "correct_poles"]


def force_window(force, fs: float, *, length_s: float | None = None, taper_s: float | None = None,
                 threshold: float = 0.05, extent=None, also=None) -> np.ndarray:
    """Force windows for a stack of records.

    Parameters
    ----------
    force : (..., n_samples) array, N
    fs : float, Hz
    length_s : float, optional, keyword-only
        Length of the flat part, s, from one sample before the pulse. Default: from the
        pulse itself, its extent above ``threshold`` × peak doubled (room for the
        anti-alias filter's ringing), and at least 8 samples.
    taper_s : float, optional, keyword-only
        Length of each cosine taper, s (default: 4 samples).
    extent : (start, stop), optional
        :func:`~tiremodal_cli.frf.hits.pulse_extent` of the records, if the caller has it.
    also : (start, stop), optional
        A later blow of each record (a bounce kept, :func:`~tiremodal_cli.frf.screening.bounced_only_hits`):
        its own window, by the same rule, is added (the union of the two; the samples between
        the blows, noise only, stay out).

    Returns
    -------
    w : (..., n_samples) ndarray, same leading shape as ``force``
    """
    f = np.asarray(force)
    n = f.shape[-1]
    start, stop = pulse_extent(f, fs, threshold=threshold) if extent is None else extent
    if length_s is None:
        length = np.maximum(2 * (stop - start), 8)
    else:
        if not length_s > 0:
            raise ParameterError(f"force window length_s={length_s} must be > 0 s")
        length = np.full(start.shape, int(round(length_s * fs)))
    taper = 4 if taper_s is None else max(1, int(round(taper_s * fs)))
    rise = 0.5 * (1 - np.cos(np.pi * np.arange(taper) / taper))
    fall = rise[::-1]
    w = np.zeros(f.shape, dtype=f.dtype if f.dtype.kind == "f" else float)
    flat = w.reshape(-1, n)
    for i, (a, ln) in enumerate(zip((start - 1).ravel(), length.ravel())):
        a, b = max(int(a), 0), min(int(a + ln), n)  # the window is short: fill it, leave zeros
        flat[i, a:b] = 1.0
        lo = max(a - taper, 0)
        flat[i, lo:a] = rise[taper - (a - lo):]
        hi = min(b + taper, n)
        flat[i, b:hi] = fall[:hi - b]
    if also is not None:
        w = np.maximum(w, force_window(f, fs, length_s=length_s, taper_s=taper_s, threshold=threshold, extent=also))
    return w


def exponential_window(n_samples: int, fs: float, *, end_value: float | None = None,
                       tau_s: float | None = None) -> tuple[np.ndarray, float]:
    """Exponential window over a record, from 1 at t = 0.

    Give ``end_value`` (the window's value at the last sample, 0 < end < 1) or ``tau_s``.

    Returns
    -------
    w : (n_samples,) ndarray
    tau_s : float, s
    """
    if (end_value is None) == (tau_s is None):
        raise ParameterError("give exactly one of end_value and tau_s for the exponential window")
    t = np.arange(n_samples) / fs
    if end_value is not None:
        if not 0 < end_value < 1:
            raise ParameterError(f"exponential window end_value={end_value} must be in (0, 1)")
        tau_s = -t[-1] / np.log(end_value)
    elif not tau_s > 0:
        raise ParameterError(f"exponential window tau_s={tau_s} must be > 0 s")
    return np.exp(-t / tau_s), float(tau_s)


def correct_poles(poles, tau_s: float | None):
    """Remove the exponential window's decay from continuous-time poles λ = −σ + iω_d (rad/s)."""
    poles = np.asarray(poles, dtype=complex)
    if tau_s is None:
        return poles
    return poles + 1.0 / tau_s


def correct_damping(freq_hz, damping_ratio, tau_s: float | None):
    """Structural natural frequency and damping ratio from windowed estimates.

    Parameters
    ----------
    freq_hz, damping_ratio : array-like      estimates from windowed FRFs (undamped f, ζ)
    tau_s : float or None                    the window's time constant

    Returns
    -------
    freq_hz, damping_ratio : ndarray         with σ = ζω − 1/τ and ω_d kept
    """
    f = np.asarray(freq_hz, dtype=float)
    z = np.asarray(damping_ratio, dtype=float)
    if tau_s is None:
        return f, z
    w = 2 * np.pi * f
    lam = -z * w + 1j * w * np.sqrt(np.clip(1 - z**2, 0, None))
    lam = correct_poles(lam, tau_s)
    wn = np.abs(lam)
    return wn / (2 * np.pi), -lam.real / wn
