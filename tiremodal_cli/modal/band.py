"""The analysis band of the modal stage: the lines where the data support an estimate.

The coherence test (:func:`coherence_threshold`: what a line of pure noise exceeds with a
stated probability) and the hammer test's force-spectrum rule, applied over the FRFs
(:func:`default_band`); without either, every line above 0 Hz (:func:`band_or_every_line`).
"""

from __future__ import annotations

import logging

import numpy as np

from tiremodal_cli.errors import DataFormatError, ParameterError

log = logging.getLogger(__name__)

__all__ = ["COHERENCE_ALPHA", "FORCE_DROP_DB", "coherence_threshold", "default_band", "band_or_every_line",
           "order_for_lines", "no_stable_mode", "live_channels", "noise_shape", "window_noise_gain"]


#: probability that a line of pure noise passes the coherence test in one FRF
COHERENCE_ALPHA = 0.01
#: the force's autospectrum may fall this far below its peak (the hammer-test rule, e.g.
#: Ewins 2000 §3.6: 10–20 dB; the wider value, as the coherence test applies too)
FORCE_DROP_DB = 20.0


def coherence_threshold(n_averages: int, alpha: float = COHERENCE_ALPHA) -> float:
    """Ordinary coherence that a line of pure noise exceeds with probability ``alpha``.

    With n_d averages of independent noise the H1 coherence estimate is Beta(1, n_d − 1)
    distributed, P(γ² > x) = (1 − x)^(n_d − 1) (Carter, Knapp & Nuttall 1973), so the
    threshold is 1 − alpha^(1/(n_d − 1)): 0.90 for 3 hits, 0.68 for 5, 0.40 for 10.
    """
    if n_averages < 2:
        raise ParameterError("a coherence threshold needs at least 2 averages")
    return float(1.0 - alpha ** (1.0 / (n_averages - 1)))


def default_band(freq_hz, coherence=None, n_averages=None, force_autospectrum=None,
                 min_lines: int = 16) -> tuple[tuple[float, float], str]:
    """The analysis band where the data support an estimate, and why.

    A line is supported when (a) the median coherence over the live FRFs exceeds
    :func:`coherence_threshold` for the test's number of averages (what noise alone
    exceeds in 1 % of FRFs), and (b) the force's autospectrum, when given, is within
    :data:`FORCE_DROP_DB` of its peak. Runs of fewer than ``min_lines`` supported lines
    (LSCE's shortest band: it cannot hold a resolvable mode) are dropped; the band runs
    from the first kept line to the last, above 0 Hz (narrow dips inside it — an
    antiresonance, a notch of the force — are kept: they hold no mode to lose). Above
    the last such run the band goes on while one live channel's median coherence over
    its points passes (a): a response channel that measures the modes at most points
    supports the estimate whatever the others record (session 32: a 60-point receptance
    test at 4,096 Hz, whose rim and sidewall fell below the tread's level, lost 22 visible
    modes to the median over every FRF: the band 714 → 1,112 Hz). Not at the foot: below the lowest mode one
    channel's coherent line is a stiffness or rigid-body line (a free rim on its
    supports) that holds no mode, and there it biased LSCE's lowest mode (the 13.24 Hz
    rim mode −0.26 → −0.72 % with the foot at 2.75 Hz instead of 6 Hz). One average: the
    coherence is 1 by construction; without a force spectrum too, every line above 0 Hz.
    No constant depends on the sample rate: the band follows the test's noise and force.

    Parameters
    ----------
    freq_hz : (n_freq,) array, Hz
    coherence : (n_channels, n_points, n_freq) array, optional (NaN: dead channel)
    n_averages : (n_points,) array of int, optional
    force_autospectrum : (n_freq,) array, optional — mean |F|² over the hits

    Returns
    -------
    (lo, hi) in Hz, and the reason as one sentence
    """
    f = np.asarray(freq_hz, dtype=float)
    ok = f > 0
    if ok.sum() < min_lines:
        raise DataFormatError(f"fewer than {min_lines} lines above 0 Hz")
    why, every, one = [], *np.ones((2, f.size), bool)
    n_d = int(np.median(n_averages)) if n_averages is not None and np.size(n_averages) else 0
    if coherence is not None and n_d >= 2:
        every, one, thr = _coherent(np.asarray(coherence, dtype=float), f.size, n_d)
        if thr is not None:
            why.append(f"median coherence ≥ {thr:.2f} (noise alone exceeds it in {100 * COHERENCE_ALPHA:g} % "
                       f"of FRFs with {n_d} averages)")
    else:
        why.append("coherence not used (one average: it is 1 by construction)")
    if force_autospectrum is not None:
        g = np.asarray(force_autospectrum, dtype=float)
        ok &= g >= g[f > 0].max() * 10 ** (-FORCE_DROP_DB / 10)
        why.append(f"force autospectrum within {FORCE_DROP_DB:g} dB of its peak")
    if not np.any(ok & one):
        raise DataFormatError("no line of the FRFs is supported by the data (" + "; ".join(why) + ")")
    runs, wider = _runs(ok & every, min_lines), _runs(ok & one, min_lines)  # every ⊆ one
    if not wider:
        raise DataFormatError(f"no {min_lines} consecutive lines of the FRFs are supported by the data ("
                              + "; ".join(why) + ")")
    lo, hi = float(f[(runs or wider)[0][0]]), float(f[wider[-1][-1]])
    if not runs or hi > f[runs[-1][-1]]:
        why.append(f"up to {hi:g} Hz one channel's median coherence over its points")
    return (lo, hi), "lines above 0 Hz where " + "; ".join(why)


def _runs(ok, min_lines: int) -> list:
    """The runs of at least ``min_lines`` consecutive True lines of ``ok`` (index arrays)."""
    idx = np.flatnonzero(ok)
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1) if idx.size else []
    return [r for r in runs if r.size >= min_lines]


def _coherent(coherence, n_freq: int, n_d: int):
    """Lines where the median coherence over every live FRF, and over one live channel's
    points, passes :func:`coherence_threshold` ((n_freq,) bool each), and the threshold
    (None, and every line, when no channel is live)."""
    medians = _channel_medians(coherence, n_freq)
    if not medians.size:
        return np.ones(n_freq, bool), np.ones(n_freq, bool), None
    thr = coherence_threshold(n_d)
    c = coherence.reshape(-1, n_freq)
    c = c[np.all(np.isfinite(c), axis=1)]
    return np.median(c, axis=0) >= thr, medians.max(axis=0) >= thr, thr


def _channel_medians(coherence, n_freq: int) -> np.ndarray:
    """(n_live, n_freq): each live channel's median coherence over its points (a channel
    with a non-finite FRF anywhere is dead; a 2-D array is one channel's points)."""
    c = coherence.reshape(-1, *coherence.shape[-2:]) if coherence.ndim >= 2 else coherence[None, None, :]
    c = c.reshape(c.shape[0], -1, n_freq)
    return np.array([np.median(ch, axis=0) for ch in c if np.all(np.isfinite(ch))]).reshape(-1, n_freq)


def band_or_every_line(freq_hz, band_hz) -> tuple[float, float]:
    """``band_hz`` when given, else from the first to the last line above 0 Hz (Hz)."""
    if band_hz is not None:
        return band_hz
    pos = freq_hz[freq_hz > 0]
    if pos.size < 16:
        raise DataFormatError("fewer than 16 lines above 0 Hz")
    return (float(pos[0]), float(pos[-1]))


def order_for_lines(order: int, n_lines: int, lower: bool, n_ref: int = 1) -> int:
    """A sweep's highest model order for a band of ``n_lines`` lines: ``order`` itself; when
    that is too high, the highest allowed if ``lower`` (said in a warning: ``run`` has no
    order option), else ParameterError. One reference: at most K/2 − 1; ``n_ref``
    references (the poly-reference sweep, :func:`~tiremodal_cli.modal.lsce.sweep_poly`):
    its p + 1 lags of n_ref columns need as many rows of the K − p the K-sample impulse
    responses give, p ≤ (K − n_ref) / (n_ref + 1) (28 for 87 lines and two references)."""
    top = n_lines // 2 - 1 if n_ref == 1 else (n_lines - n_ref) // (n_ref + 1)
    if order <= top:
        return order
    if not lower or top < 2:
        raise ParameterError(f"model order {order} is too high for {n_lines} lines in the band (allowed up to "
                             f"{top}; the band's lines: longer records or a wider band give more)")
    log.warning("model order lowered from %d to %d: the band holds %d lines (short records)", order, top, n_lines)
    return top


def no_stable_mode(freq_hz, order: int) -> DataFormatError:
    """The error for a sweep that found no stable mode: the band, its lines, the orders, what helps."""
    return DataFormatError(f"no stable mode found in the band ({freq_hz[0]:g}–{freq_hz[-1]:g} Hz, {len(freq_hz)} "
                           f"lines, model orders up to {order}); allowed: a band that holds modes (widen it), a "
                           "higher --max-order (lsce), or longer records (more lines)")


def live_channels(freq_hz, H) -> np.ndarray:
    """(n_channels,) bool: the channels with FRFs (a dead one is NaN throughout, as ``tiremodal
    frf`` marks it); NaN anywhere else is bad data."""
    if H.ndim != 3 or H.shape[-1] != freq_hz.size:
        raise DataFormatError(f"FRFs must be (n_channels, n_points, n_freq={freq_hz.size}); got {H.shape}")
    live = ~np.array([np.all(np.isnan(H[c])) for c in range(H.shape[0])])
    if not live.any():
        raise DataFormatError("no channel has finite FRFs")
    bad = ~np.isfinite(H[live])
    if bad.any():
        c, p, k = np.argwhere(bad)[0]
        raise DataFormatError(f"FRF of channel {np.flatnonzero(live)[c] + 1}, point {p + 1} has a non-finite "
                              f"value at {freq_hz[k]:g} Hz")
    return live


def noise_shape(force_autospectrum, n_averages=None) -> np.ndarray | None:
    """How the FRFs' noise variance varies over the lines, relative: (n_freq,) or None.

    A response sensor's noise floor N (white: an accelerometer's, and the simulator's)
    reaches the H1 estimate Σ X F* / Σ |F|² of a point as an error of variance
    σ_N² / (n_d G_FF(f)), G_FF the mean force autospectrum over the point's n_d hits: where
    the hammer's spectrum falls (towards the band's top, at a double hit's notches) the FRF
    is noisier in proportion. An order group's rows are the points' FRFs combined with
    weights of one modulus over the grid (the spatial DFT), so each row's noise variance
    at a line is proportional to the mean over the points of 1 / (n_d G_FF). The value is
    relative (the noise tests scale it by each row's residual level); None without a force
    spectrum (FRFs read from UFF 58): the noise is then taken as white over the band.

    force_autospectrum : (n_points, n_freq) array, N², or None ; n_averages : (n_points,)
    """
    if force_autospectrum is None:
        return None
    g = np.asarray(force_autospectrum, dtype=float).reshape(-1, np.shape(force_autospectrum)[-1])
    n_d = np.ones(g.shape[0]) if n_averages is None else np.maximum(np.asarray(n_averages, float).ravel(), 1)
    if n_d.size != g.shape[0] or not np.all(np.isfinite(g)) or g.max(initial=0) <= 0:
        return None
    g = np.maximum(g, g.max() * 1e-12)  # an exact zero of the force (a notch): noise without bound, held finite
    return np.mean(1.0 / (n_d[:, None] * g), axis=0)


def window_noise_gain(sigma, exp_tau_s, line_hz: float):
    """How much more of the FRFs' noise a pole takes up under the exponential window than on
    independent lines: κ_r ≥ 1 for each pole's decay rate ``sigma`` (1/s, > 0), or ones.

    A response record's white sensor noise, windowed by w(t) = e^{−t/τ} over T = 1 / line_hz,
    has variance ∝ w(t)² in time; each line's variance is its mean over the record,
    (τ / 2T)(1 − e^{−2T/τ}). A pole's column over the lines is, in time, its impulse response
    e^{−σt} (σ as fitted to the windowed FRFs: the structure's and the window's decay), so the
    noise it takes up has the variance w² weighted by e^{−2σt}: σ / (σ + 1/τ). Their ratio,
    κ_r = [σ / (σ + 1/τ)] / [(τ / 2T)(1 − e^{−2T/τ})], is 3–6 for a window ending at 5 %
    (T / τ = ln 20) and 1 without a window. Measured (tests/test_noise_shape.py): a pole's
    column at 200 Hz takes up 4.24 × (ζ 0.5 %) and 5.20 × (ζ 2 %) of seeded windowed noise what
    independent lines would give it (the formula: 4.07 and 5.37); the pole a search fits to
    such noise passed the unscaled noise test in 20 of 20 trials, none scaled.
    """
    sigma = np.atleast_1d(np.asarray(sigma, dtype=float))
    if exp_tau_s is None or not exp_tau_s > 0 or not line_hz > 0:
        return np.ones_like(sigma)
    x = 1.0 / (line_hz * exp_tau_s)  # T / τ
    mean_w2 = (1.0 - np.exp(-2.0 * x)) / (2.0 * x)
    return np.maximum(sigma / (sigma + 1.0 / exp_tau_s) / mean_w2, 1.0)
