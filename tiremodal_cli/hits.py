"""Hit-quality checks for impact records: clipping, double hits, dead channels.

Each function looks at the records only (no FRF) and returns boolean flags or counts; the
FRF stage (:mod:`tiremodal_cli.frf`) adds the coherence check and decides what to reject.
"""

from __future__ import annotations

import numpy as np
import scipy.signal

__all__ = ["clipped_samples", "is_clipped", "double_hit", "dead", "pulse_extent"]


def clipped_samples(x, *, axis=-1, min_run: int = 2, min_count: int = 3, rtol: float = 1e-6) -> np.ndarray:
    """Samples stuck at the record's extreme value, counted per record.

    An ADC (or a charge amplifier) in overload holds its full-scale value, so a clipped
    record has several samples at exactly its maximum absolute value: a run of
    ``min_run`` adjacent ones, or ``min_count`` anywhere (a response that swings through
    the limit several times between samples). Unclipped records almost never tie at
    their peak. Records that are not clipped count 0.

    Parameters
    ----------
    x : (..., n_samples) array
    Returns
    -------
    count : (...) ndarray of int   samples at the limit in clipped records, else 0
    """
    x = np.moveaxis(np.asarray(x), axis, -1)
    a = np.abs(x)
    peak = np.max(a, axis=-1, keepdims=True)
    at = (a >= peak * (1 - rtol)) & (peak > 0)
    count = at.sum(axis=-1)
    run = np.zeros(count.shape, dtype=bool)
    maybe = count >= 2
    if maybe.any():
        sub = at[maybe]
        win = np.lib.stride_tricks.sliding_window_view(sub, min_run, axis=-1).all(axis=-1)
        run[maybe] = win.any(axis=-1)
    return np.where(run | (count >= min_count), count, 0)


def is_clipped(x, *, axis=-1) -> np.ndarray:
    """True for records that :func:`clipped_samples` finds clipped."""
    return clipped_samples(x, axis=axis) > 0


def pulse_extent(force, fs: float, *, threshold: float = 0.05):
    """Start and end sample of the main pulse of each force record.

    The pulse spans the samples around the peak where |f| stays above ``threshold`` × peak.

    Returns
    -------
    start, stop : (...) ndarray of int     stop is exclusive
    """
    f = np.asarray(force, dtype=float)
    a = np.abs(f)
    ipk = np.argmax(a, axis=-1)
    pk = np.take_along_axis(a, ipk[..., None], -1)
    above = a >= threshold * pk
    n = f.shape[-1]
    idx = np.arange(n)
    below_before = np.where(~above & (idx <= ipk[..., None]), idx, -1).max(axis=-1)
    below_after = np.where(~above & (idx >= ipk[..., None]), idx, n).min(axis=-1)
    return below_before + 1, below_after


def double_hit(force, fs: float, *, min_relative: float = 0.2, min_gap_s: float = 1.0e-3) -> np.ndarray:
    """True for force records with a second blow.

    After the main pulse has ended, a later positive peak of at least ``min_relative`` of
    the main peak (found with :func:`scipy.signal.find_peaks`, at least ``min_gap_s``
    apart) is a second impact: the hammer bounced. Only positive peaks count: a hammer
    pushes, while the anti-alias filter's ringing after a short pulse swings both ways
    (an 8th-order Butterworth at 0.4 fs rings to about +7 % after a 1 ms pulse at 2 kHz).

    Parameters
    ----------
    force : (..., n_samples) array, N
    fs : float, Hz
    """
    f = np.asarray(force, dtype=float)
    flat = f.reshape(-1, f.shape[-1])
    out = np.zeros(flat.shape[0], dtype=bool)
    start, stop = pulse_extent(flat, fs)
    gap = max(1, int(round(min_gap_s * fs)))
    for i, rec in enumerate(flat):
        pk = np.max(np.abs(rec))
        if pk == 0:
            continue
        tail = rec[stop[i]:] * np.sign(rec[np.argmax(np.abs(rec))])
        peaks, _ = scipy.signal.find_peaks(tail, height=min_relative * pk, distance=gap)
        out[i] = peaks.size > 0
    return out.reshape(f.shape[:-1])


def dead(x, *, axis=-1, relative: float = 1e-3) -> np.ndarray:
    """True for records whose RMS is below ``relative`` × the median RMS of their channel.

    Parameters
    ----------
    x : (n_points, n_hits, n_channels, n_samples) array
        Response records; the median is taken per channel over points and hits.
    """
    x = np.asarray(x)
    rms = np.sqrt(np.mean(np.square(x, dtype=float), axis=axis))
    ref = np.median(rms.reshape(-1, rms.shape[-1]), axis=0)
    return rms < relative * ref
