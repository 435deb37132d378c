"""Hit-quality checks for impact records: clipping, double hits, dead channels.

Each function looks at the records only (no FRF) and returns boolean flags or counts; the
FRF stage (:mod:`tiremodal_cli.frf`) adds the coherence check and decides what to reject.
"""

from __future__ import annotations

import numpy as np

__all__ = ["clipped_samples", "is_clipped", "double_hit", "pulse_extent"]


def clipped_samples(x, *, axis=-1, min_run: int = 2, min_count: int = 3, rtol: float = 1e-6) -> np.ndarray:
    """Samples stuck at the record's extreme value, counted per record.

    An ADC (or a charge amplifier) in overload holds its full-scale value, so a clipped
    record has several samples at exactly its maximum absolute value: a run of
    ``min_run`` adjacent ones, or ``min_count`` anywhere (a response that swings through
    the limit several times between samples). Unclipped records almost never tie at
    their peak. A flat record (every sample at its peak) counts too; the FRF stage calls
    it dead. Records that are not clipped count 0.

    Parameters
    ----------
    x : (..., n_samples) array, finite
    Returns
    -------
    count : (...) ndarray of int   samples at the limit in clipped records, else 0
    """
    a = np.abs(np.moveaxis(np.asarray(x), axis, -1))
    return _clip_count(a, a.max(axis=-1), min_run=min_run, min_count=min_count, rtol=rtol)


def _clip_count(a, peak, *, min_run=2, min_count=3, rtol=1e-6):
    """:func:`clipped_samples` from |x| and its peak (for callers that have them)."""
    at = a >= (peak * (1 - rtol))[..., None]
    count = np.where(peak > 0, np.count_nonzero(at, axis=-1), 0)
    run = np.zeros(count.shape, dtype=bool)
    few = (count >= 2) & (count < min_count)  # only these need the adjacency test
    if few.any():
        sub = at[few]
        win = np.lib.stride_tricks.sliding_window_view(sub, min_run, axis=-1).all(axis=-1)
        run[few] = win.any(axis=-1)
    return np.where(run | (count >= min_count), count, 0)


def is_clipped(x, *, axis=-1) -> np.ndarray:
    """True for records that :func:`clipped_samples` finds clipped."""
    return clipped_samples(x, axis=axis) > 0


def pulse_extent(force, fs: float, *, threshold: float = 0.05, max_s: float = 0.05, peak_index=None):
    """Start and end sample of the main pulse of each force record.

    The pulse spans the samples around the peak where |f| stays above ``threshold`` ×
    peak, searched within ``max_s`` of the peak (a hammer pulse lasts milliseconds).
    ``peak_index`` (…,) may give the peak's sample when the caller has it.

    Returns
    -------
    start, stop : (...) ndarray of int     stop is exclusive
    """
    f = np.asarray(force)
    flat = f.reshape(-1, f.shape[-1])
    n = flat.shape[-1]
    reach = max(2, int(max_s * fs))
    start = np.zeros(flat.shape[0], dtype=int)
    stop = np.zeros(flat.shape[0], dtype=int)
    ipks = (np.argmax(np.abs(flat), axis=-1) if peak_index is None
            else np.asarray(peak_index).reshape(-1))
    for i, rec in enumerate(flat):  # a local search per record: a few samples, not the record
        ipk = int(ipks[i])
        lim = threshold * abs(rec[ipk])
        lo = max(0, ipk - reach)
        seg = np.abs(rec[lo:min(n, ipk + reach)]) < lim
        k = ipk - lo
        before = np.flatnonzero(seg[:k])
        after = np.flatnonzero(seg[k:])
        start[i] = lo + (before[-1] + 1 if before.size else 0)
        stop[i] = lo + k + (after[0] if after.size else seg.size - k)
    return start.reshape(f.shape[:-1]), stop.reshape(f.shape[:-1])


def double_hit(force, fs: float, *, min_relative: float = 0.2, extent=None) -> np.ndarray:
    """True for force records with a second blow.

    After the main pulse has ended (:func:`pulse_extent`), a later sample of the blow's
    sign reaching ``min_relative`` of the main peak is a second impact: the hammer
    bounced. Only the blow's sign counts: a hammer
    pushes, while the anti-alias filter's ringing after a short pulse swings both ways
    (an 8th-order Butterworth at 0.4 fs rings to about +7 % after a 1 ms pulse at 2 kHz).

    Parameters
    ----------
    force : (..., n_samples) array, N
    fs : float, Hz
    extent : (start, stop), optional       :func:`pulse_extent` of the records, if known
    """
    f = np.asarray(force)
    flat = f.reshape(-1, f.shape[-1])
    out = np.zeros(flat.shape[0], dtype=bool)
    start, stop = pulse_extent(flat, fs) if extent is None else (np.ravel(extent[0]), np.ravel(extent[1]))
    for i, rec in enumerate(flat):
        seg = rec[start[i]:stop[i]]
        if seg.size == 0 or stop[i] >= rec.size:
            continue
        ipk = start[i] + int(np.argmax(np.abs(seg)))
        pk = abs(float(rec[ipk]))
        if pk == 0:
            continue
        # the highest later sample of the blow's sign: any such maximum is a peak of the tail
        tail = rec[stop[i]:]
        later = tail.max() if rec[ipk] > 0 else -tail.min()
        out[i] = later >= min_relative * pk
    return out.reshape(f.shape[:-1])
