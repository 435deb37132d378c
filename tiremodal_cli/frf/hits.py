"""Hit-quality checks for impact records: clipping, double hits, dead channels.

Each function looks at the records only (no FRF) and returns boolean flags or counts; the
FRF stage (:mod:`tiremodal_cli.frf.estimate`) adds the coherence check and decides what to reject.
"""

from __future__ import annotations

import numpy as np

__all__ = ["clipped_samples", "is_clipped", "double_hit", "pulse_extent", "bounce_in_pulse", "pulse_segments",
           "bounce_from_segments", "clip_count"]


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
    return clip_count(a, a.max(axis=-1), min_run=min_run, min_count=min_count, rtol=rtol)


def clip_count(a, peak, *, min_run=2, min_count=3, rtol=1e-6):
    """:func:`clipped_samples` from |x| and its peak (for callers that have them).

    Parameters
    ----------
    a : (..., n_samples) ndarray        |x|, the records' magnitudes
    peak : (...) ndarray                their peaks (``a.max(axis=-1)``)
    min_run, min_count, rtol            as for :func:`clipped_samples`

    Returns
    -------
    (...) ndarray of int                samples in runs at the peak (0: not clipped)
    """
    at = a >= (peak * (1 - rtol))[..., None]
    # count_nonzero per flat record: 3 × faster than count_nonzero(axis=-1), which sums a cast
    rows = at.reshape(-1, at.shape[-1])
    counts = np.fromiter((np.count_nonzero(r) for r in rows), dtype=int, count=rows.shape[0])
    count = np.where(peak > 0, counts.reshape(at.shape[:-1]), 0)
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


#: Most samples of a record's noise the bounce check's noise floor takes (:func:`pulse_segments`).
NOISE_SAMPLES = 1023


def bounce_in_pulse(force, fs: float, *, min_relative: float = 0.2, band_top: float | None = None,
                    false_alarm: float = 1e-3, min_hits: int = 5):
    """Double hits whose bounce overlaps the first pulse, by the force spectrum's notch.

    A bounce ``dt`` after the blow, of relative size ``a``, multiplies the force spectrum
    by ``|1 + a e^{−i2πf dt}|``: a notch to ``1 − a`` at ``f = 1/(2 dt)``, inside the band
    for every ``dt > 1/(2 band_top)`` (≥ 1.6 ms at 1,024 Hz). One hammer's clean blows
    share a spectral shape (same tip, same structure) up to their width's scatter, so each
    hit's spectrum (normalised to its own level at 0 Hz) is compared, line by line, with the
    test's median. A bounce is a line where the hit falls to at most ``(1 − a)/(1 + a)`` of
    the median — the notch of a second blow of ``a = min_relative`` of the first, the size
    :func:`double_hit` calls a second blow after the pulse — and where that dip is also
    significant: more than ``z`` robust standard deviations of that line across the hits. The comparison is of amplitudes,
    not logarithms: force noise adds to the amplitude a Gaussian of known spread, while
    the log of a noisy amplitude has a long lower tail (false notches where noise cancels). ``z`` is the Gaussian quantile of
    ``false_alarm`` (per test) shared out (Bonferroni) over the hits and the independent
    lines (the segment's length × the band); each line's deviation is also floored by the
    force noise (from the record away from the pulse) relative to that line's level.

    Parameters
    ----------
    force : (n_records, n_samples) array, N   every hit of the test
    fs : float, Hz
    band_top : highest frequency looked at, Hz (default 0.3125 fs: below a front end's
        anti-alias corner, where a single blow's spectrum is the hammer's, not the filter's)
    false_alarm : probability that a test of clean hits has one flagged
    min_relative : smallest second blow, relative to the first, that counts as a bounce
    min_hits : fewest finite, non-zero records the comparison needs (a median and a spread)

    Returns
    -------
    flags : (n_records,) bool
    notch_hz : (n_records,) float   frequency of each record's deepest dip (NaN: none)
    ran : bool   False when the test has too few usable hits (nothing flagged then)
    """
    seg, noise, ok = pulse_segments(force, fs)
    return bounce_from_segments(seg, noise, ok, fs, min_relative=min_relative, band_top=band_top,
                                false_alarm=false_alarm, min_hits=min_hits)[:3]


def pulse_segments(force, fs: float):
    """Each record's blow: 5 ms before its peak to 20 ms after (a blow and a bounce of
    ≤ 20 ms), and the robust std of the force noise away from it.

    The noise is the median absolute deviation (× 1.4826) of at most :data:`NOISE_SAMPLES`
    samples away from the blow, evenly strided over the rest of the record (from the
    segment's end round to its start). The noise samples are independent, so one record's
    estimate has a relative standard error of ≈ 1.17/√N = 3.7 % at N = 1,023 (odd: the median is a sample), and the
    notch test uses only the median over the test's hits (≥ 5): its floor is known to
    ≈ 1.25 × 3.7 %/√n_hits — 2 % at 5 hits, 0.4 % at 170 — ample for a floor on the
    spread. Two medians over a whole 32,768-sample record cost more than its FFT, and
    over 4,096 samples still 25 ms on a 170-hit test (8 × those over 1,023). Every record
    gets the same number of noise samples, so the medians are one array call per point.

    Returns seg (n_records, L), noise (n_records,), ok (n_records,) — ok False for a
    non-finite or all-zero record.
    """
    f = np.asarray(force)
    if not np.issubdtype(f.dtype, np.floating):
        f = f.astype(float)
    n, ns = f.shape
    absf = np.abs(f)  # in the records' precision: only the short segments are copied to double
    ipk = np.argmax(absf, axis=1)  # the first NaN, if the record has one
    peak = np.take_along_axis(absf, ipk[:, None], axis=1)[:, 0]
    ok = np.isfinite(peak) & (peak > 0)
    pre, post = int(np.ceil(0.005 * fs)), int(np.ceil(0.02 * fs))
    L = pre + post
    # every record's segment and noise samples are taken (argmax is defined for all), the
    # records that are not ok zeroed after: no copy of the records
    lo = (ipk - pre)[:, None]
    take = lo + np.arange(L)
    inside = (take >= 0) & (take < ns) & ok[:, None]
    seg = np.where(inside, np.take_along_axis(f, np.clip(take, 0, ns - 1), axis=1).astype(float), 0.0)
    noise = np.zeros(n)
    k = min(NOISE_SAMPLES, ns - L)
    if k > 0:  # k samples over the ns − L after the segment's end (modulo ns: never inside it)
        idx = (lo + L + (np.arange(k) * (ns - L)) // k) % ns
        away = np.take_along_axis(f, idx, axis=1).astype(float)
        mid = (k - 1) // 2  # (k odd: the median is one sample, one partition)
        dev = np.abs(away - np.partition(away, mid, axis=1)[:, mid:mid + 1])
        noise = np.where(ok, 1.4826 * np.partition(dev, mid, axis=1)[:, mid], 0.0)
    return seg, noise, ok


def bounce_from_segments(seg, noise, ok, fs: float, *, min_relative: float = 0.2, band_top: float | None = None,
                         false_alarm: float = 1e-3, min_hits: int = 5):
    """:func:`bounce_in_pulse` from :func:`pulse_segments` (gathered point by point by a
    caller that reads the records lazily). Same returns, and ``depth`` (n_records,): each
    flagged record's deepest dip below the median shape, as a ratio, over the lines where
    the median is within 20 dB of its 0 Hz level (1: not flagged) — the notch's depth
    relative to the record's own 0 Hz level, (1 − a)/(1 + a) for a bounce of size a."""
    from scipy.special import ndtri

    n, L = seg.shape
    flags = np.zeros(n, dtype=bool)
    notch = np.full(n, np.nan)
    depth_out = np.ones(n)
    if ok.sum() < min_hits:
        return flags, notch, False, depth_out
    band_top = 0.3125 * fs if band_top is None else band_top
    nfft = 1 << int(np.ceil(np.log2(8 * L)))
    freq = np.fft.rfftfreq(nfft, 1 / fs)
    sel = freq <= band_top
    S = np.abs(np.fft.rfft(seg, n=nfft, axis=1))[:, sel]
    level = S[:, 0:1].copy()
    level[level <= 0] = np.nan
    x = S / level  # each blow's spectrum shape, 1 at 0 Hz
    good = ok & np.isfinite(level[:, 0])
    med = np.median(x[good], axis=0)
    r = x - med
    spread = 1.4826 * np.median(np.abs(r[good]), axis=0)
    # additive noise moves |S| by a Gaussian of std σ √(L/2) (its component along S)
    rel_noise = np.median(noise[good] * np.sqrt(L / 2) / level[good, 0])
    s = np.maximum(spread, rel_noise)
    n_lines = max(1, int(np.ceil(L * band_top / fs)))  # independent lines of an L-sample segment
    z = float(ndtri(1 - false_alarm / (good.sum() * n_lines)))
    deep = (1 - min_relative) / (1 + min_relative)
    hit = (r < -z * s) & (x <= deep * med) & good[:, None]
    flags[:] = hit.any(axis=1)
    depth = np.where(hit, x / np.maximum(med, np.finfo(float).tiny), np.inf)
    notch[flags] = freq[sel][np.argmin(depth[flags], axis=1)]
    strong = med >= 0.1  # within 20 dB of the 0 Hz level
    if strong.any():
        depth_out[flags] = np.nanmin(x[flags][:, strong] / med[strong], axis=1)
    return flags, notch, True, depth_out
