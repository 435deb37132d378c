"""Which hits go into the average: every check of the FRF stage, each rejection with its reason.

Per hit (:func:`time_checks`): non-finite samples, no impact, a clipped force or response,
a dead record, a double hit. Over the test (:func:`test_wide_checks`): a bounce within the
pulse, read from the force spectra of all hits. Per point, after the windows
(:func:`inconsistent_hits`): a hit that the other hits' H1 does not predict
(:func:`leave_one_out_residual`). The signal tests themselves are :mod:`tiremodal_cli.frf.hits`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import scipy.fft

from tiremodal_cli.frf.hits import bounce_from_segments, clip_count, double_hit, pulse_extent, pulse_segments
from tiremodal_cli.frf.windows import force_window

log = logging.getLogger(__name__)

__all__ = ["Rejection", "time_checks", "test_wide_checks", "inconsistent_hits", "leave_one_out_residual",
           "bounced_only_hits", "BOUNCE_NOTCH_DB"]

#: deepest notch a bounce may cut in a hit's force spectrum, over the lines where that hit's
#: first blow is within this much of its peak, for the hit to stand in for a point that has
#: no other (the hammer-test rule of the band, Ewins 2000 §3.6: the force may fall 10–20 dB;
#: :data:`tiremodal_cli.modal.band.FORCE_DROP_DB`, the same value)
BOUNCE_NOTCH_DB = 20.0


@dataclass(frozen=True)
class Rejection:
    """A rejected hit (or a whole channel when ``hit`` is None)."""

    point: int | None
    hit: int | None
    reason: str
    channel: str | None = None

    def to_dict(self):
        return {"point": self.point, "hit": self.hit, "channel": self.channel, "reason": self.reason}


def leave_one_out_residual(a, p, e):
    """How well the other hits predict each hit: ``Σ|Y_i − Ĥ_{−i} F_i|² / Σ|Y_i|²``.

    Ĥ_{−i} = (Σ_j a_j − a_i) / (Σ_j p_j − p_i) is the H1 of all hits but i. For consistent
    hits this is the noise-to-signal energy, about the same for every hit; a hit that does
    not belong stands out against the median of the hits (a channel at a node is noisy
    for every hit and does not). Expanded, |Y − hF|² = e − 2 Re(conj(h) a) + |h|² p, so it
    needs only the per-hit spectra products the estimate uses anyway.

    a : (n_hits, n_channels, n_f) complex   conj(F) Y per hit
    p : (n_hits, 1, n_f) real               |F|² per hit
    e : (n_hits, n_channels, n_f) real      |Y|² per hit
    returns (n_hits, n_channels)
    """
    A, P = a.sum(axis=0), p.sum(axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = P - p
        h = np.where(den > 0, (A - a) / np.where(den > 0, den, 1), 0)
    res = np.sum(e - 2 * (h.real * a.real + h.imag * a.imag) + (h.real**2 + h.imag**2) * p, axis=-1)
    sig = np.sum(e, axis=-1)
    return np.where(sig > 0, np.clip(res, 0, None) / np.where(sig > 0, sig, 1), 0.0)


def time_checks(f, y, fs, opt, names, ip):
    """Per-hit checks on one point's records: non-finite, zero or clipped force, dead or
    clipped responses, double hits (:mod:`tiremodal_cli.frf.hits`).

    Parameters
    ----------
    f : (n_hits, n_samples) ndarray, N ; y : (n_hits, n_channels, n_samples) ndarray
    fs : float, Hz
    opt : FRFOptions          ``check_hits``, ``double_hit_relative``
    names : tuple of str      the channels' names ; ip : int   the point's index

    Returns
    -------
    The rejections, a (n_hits,) mask of rejected hits, the (n_hits, n_channels) record
    peaks (for the dead-channel test) and the force pulses' extent (None: not checked).
    """
    rej = []
    n_h = f.shape[0]
    af, ay = np.abs(f), np.abs(y)
    pk_f, pk_y = af.max(axis=-1), ay.max(axis=-1)  # NaN and inf propagate: finiteness for free
    fin_f, fin_y = np.isfinite(pk_f), np.isfinite(pk_y)
    if not (fin_f.all() and fin_y.all()):
        f = np.where(np.isfinite(f), f, 0)
        y = np.where(np.isfinite(y), y, 0)
        af, ay = np.abs(f), np.abs(y)
        pk_f, pk_y = af.max(axis=-1), ay.max(axis=-1)
    for h in range(n_h):
        if not fin_f[h]:
            rej.append(Rejection(ip, h, "non-finite force samples", "force"))
        for c in np.flatnonzero(~fin_y[h]):
            rej.append(Rejection(ip, h, "non-finite response samples", names[c]))
    bad = ~(fin_f & fin_y.all(axis=1))
    if not opt.check_hits:
        return rej, bad, pk_y, None
    extent = pulse_extent(f, fs, peak_index=np.argmax(af, axis=-1))
    clip_f = clip_count(af, pk_f) > 0
    n_at = clip_count(ay, pk_y)
    clip_y = n_at > 0
    const_y = n_at == y.shape[-1]  # every sample at the peak: a flat line
    dbl = double_hit(f, fs, min_relative=opt.double_hit_relative, extent=extent)
    for h in range(n_h):
        if bad[h]:
            continue
        if pk_f[h] == 0:
            rej.append(Rejection(ip, h, "zero force (no impact recorded)", "force"))
            bad[h] = True
            continue
        reasons = []
        if clip_f[h]:
            reasons.append(Rejection(ip, h, "clipped (overloaded) force", "force"))
        for c in np.flatnonzero(const_y[h]):
            reasons.append(Rejection(ip, h, "dead record (constant samples)", names[c]))
        for c in np.flatnonzero(clip_y[h] & ~const_y[h]):
            reasons.append(Rejection(ip, h, "clipped (overloaded) response", names[c]))
        if dbl[h]:
            reasons.append(Rejection(ip, h, "double hit", "force"))
        rej += reasons
        bad[h] = bool(reasons)
    return rej, bad, pk_y, extent


def test_wide_checks(m, fs, opt):
    """Checks over every hit of the test: a bounce within the pulse
    (:func:`tiremodal_cli.frf.hits.bounce_in_pulse` over all the force records; read a point
    at a time, kept as 25 ms segments). ``m`` is the Measurement, ``opt`` the FRFOptions.

    Returns {point: [(hit, notch_hz, depth), ...]} (``depth``: the notch's, as a ratio; see
    :func:`~tiremodal_cli.frf.hits.bounce_from_segments`) and the checks that could not run, each said once
    (a warning, and ``meta["checks_not_run"]``): the bounce check with fewer than 5 usable
    hits in the test, the consistency check with fewer than 3 hits per point.
    """
    out, not_run = {}, []
    if not opt.check_hits:
        return out, not_run
    n_p, n_h = m.n_points, m.n_hits
    parts = [pulse_segments(np.asarray(m.force[ip]), fs) for ip in range(n_p)]  # one point at a time
    seg, noise, ok = (np.concatenate([p[k] for p in parts]) for k in range(3))
    flags, notch, ran, depth = bounce_from_segments(seg, noise, ok, fs, min_relative=opt.double_hit_relative)
    if not ran:
        not_run.append(f"double hits within the pulse (force spectrum): needs at least 5 usable hits in the test "
                       f"(finite, non-zero force), it has {int(ok.sum())} of {n_p * n_h}")
    for k in np.flatnonzero(flags):
        out.setdefault(int(k) // n_h, []).append((int(k) % n_h, float(notch[k]), float(depth[k])))
    if n_h < 3:
        not_run.append(f"consistency of the hits: needs at least 3 hits per point, the test has {n_h}")
    for what in not_run:
        log.warning("hit check not run: %s", what)
    return out, not_run


def inconsistent_hits(a, p, e, acc, opt, names, ip) -> tuple[np.ndarray, list[Rejection]]:
    """The hits that the other hits' H1 does not predict (needs ≥ 3 hits; the caller checks).

    A hit is rejected when, on some channel, its :func:`leave_one_out_residual` exceeds
    ``opt.hit_residual_max`` and is more than ``opt.hit_residual_ratio`` × the hits' median;
    the rejection names the channel where it stands out most.

    Parameters
    ----------
    a, p, e : per-hit spectra products, as for :func:`leave_one_out_residual`
    acc : (n_hits,) ndarray of int     the hits' indices in the point's records
    opt : FRFOptions ; names : tuple of str ; ip : int

    Returns
    -------
    keep : (n_hits,) bool ndarray ; the rejections
    """
    # a statistic, not an estimate: every k-th line (≤ 1024 of them) tells as much
    k = max(1, a.shape[-1] // 1024)
    # (contiguous copies of the strided lines: the dozen array operations on them run 2 × faster)
    d = leave_one_out_residual(*(np.ascontiguousarray(x[..., ::k]) for x in (a, p, e)))
    ratio = d / np.maximum(np.median(d, axis=0, keepdims=True), np.finfo(float).tiny)
    flag = (d > opt.hit_residual_max) & (ratio > opt.hit_residual_ratio)
    rejections = []
    for i in np.flatnonzero(flag.any(axis=1)):
        c = int(np.argmax(np.where(flag[i], ratio[i], -np.inf)))
        rejections.append(Rejection(ip, int(acc[i]), "poor consistency with the other hits "
                                    f"(residual {d[i, c]:.2f} of its energy, {ratio[i, c]:.1f}× the "
                                    "hits' median)", names[c]))
    return ~flag.any(axis=1), rejections


def bounced_only_hits(f, fs: float, rej: list, ip: int, extent, within: dict | None = None, *,
                      threshold: float = 0.05, max_notch_db: float = BOUNCE_NOTCH_DB):
    """The double hits of a point that has no other hit, usable with the force window over every blow.

    A second blow of relative size a after Δt notches the force spectrum, |F| = |F₁| |1 + a
    e^{−2πifΔt}|: H1 loses precision there (noise × 1/|1 − a| at worst), not accuracy — the
    structure is linear, H1 = Y/F holds for any force the window keeps whole. A point whose
    every hit bounced would be lost, a gap that leaks every order into the others
    (docs/frf.md). Its hits, each rejected for a bounce and nothing else, are used when the
    notch is no deeper than ``max_notch_db``:

    * a bounce after the pulse (:func:`~tiremodal_cli.frf.hits.double_hit`): below the first
      blow's own spectrum (the record windowed to it alone), over the lines where that blow
      is within ``max_notch_db`` of its peak (the band the hit excites); the force window
      then adds a window of the later blow (the same rule, from its onset above the pulse
      threshold to its end, × 2): the noise between the blows stays out;
    * a bounce within the pulse (:func:`test_wide_checks`, ``within``: hit → depth): the
      notch below the test's median blow, (1 − a)/(1 + a), deeper than 1 − a: the stricter;
      the pulse's extent (and so the window) already spans that bounce.

    Parameters
    ----------
    f : (n_hits, n_samples) ndarray, N        the point's force records
    fs : float, Hz
    rej : list of Rejection                   the point's rejections so far
    ip : int                                  the point's index
    extent : (start, stop) of (n_hits,) int   the first blows' :func:`pulse_extent`
    within : dict, optional                   hit → notch depth (a ratio) of the bounces within the pulse

    Returns
    -------
    use : (k,) ndarray of int                  the hits to use (empty: none)
    later : (start, stop) of (n_hits,) int     each hit's later blow, for the force window's ``also``
    notes : list of dict                       point, hit, kind, notch_db (and delay_s, relative_size)
    """
    within, reasons = within or {}, {}
    for r in (r for r in rej if r.point == ip and r.hit is not None):
        reasons.setdefault(r.hit, []).append(r.reason)
    after = [h for h, why in reasons.items() if why == ["double hit"]]
    inside = [h for h, why in reasons.items() if h in within and len(why) == 1 and why[0].startswith("double hit (")]
    if extent is None or len(reasons) < f.shape[0] or not (after or inside):
        return np.zeros(0, dtype=int), None, []
    start, stop = (np.asarray(x) for x in extent)
    later = (start.copy(), stop.copy())  # each hit's later blow (its first again: none)
    use, notes = [], []
    for h in sorted(after + inside):
        note = _bounce_after(np.asarray(f[h], dtype=float), fs, int(start[h]), int(stop[h]), threshold,
                             max_notch_db)
        if h in inside:  # its depth from the test's blows; the window still to any tail of its sign
            note = {"kind": "within the pulse", "notch_db": float(20 * np.log10(max(within[h], 1e-12))),
                    **({"blow": note["blow"]} if note else {})}
        if note is None or note["notch_db"] < -max_notch_db:
            continue
        note.update(point=int(ip), hit=int(h))
        later[0][h], later[1][h] = note.pop("blow", (start[h], stop[h]))
        use.append(h)
        notes.append(note)
        log.warning("point %d: its only hit %d bounced %s (force notch %.1f dB); used, the force window over "
                    "every blow", ip + 1, h + 1, note["kind"], note["notch_db"])
    return np.asarray(use, dtype=int), later, notes


def _bounce_after(rec, fs: float, start: int, stop: int, threshold: float, max_notch_db: float) -> dict | None:
    """A bounce after the pulse read from the record: its delay, size and notch, and where the last blow ends."""
    ipk = start + int(np.argmax(np.abs(rec[start:stop])))
    sign, lim = np.sign(rec[ipk]), threshold * abs(rec[ipk])
    tail = np.flatnonzero(sign * rec[stop:] >= lim)
    if not tail.size:
        return None
    onset, last = stop + int(tail[0]), stop + int(tail[-1]) + 1
    quiet = np.flatnonzero(np.abs(rec[last:]) < lim)
    end = last + (int(quiet[0]) if quiet.size else 0)
    second = stop + int(np.argmax(sign * rec[stop:end]))
    alone = min(2 * (stop - start), onset - start + 1) / fs  # the first blow alone
    one = np.abs(scipy.fft.rfft(rec * force_window(rec[None], fs, length_s=alone,
                                                   extent=(np.array([start]), np.array([stop])))[0]))
    both = np.abs(scipy.fft.rfft(rec * force_window(rec[None], fs, extent=(np.array([start]), np.array([stop])),
                                                    also=(np.array([onset]), np.array([end])))[0]))
    lines = one >= one.max() * 10 ** (-max_notch_db / 20)
    return {"kind": f"after the pulse ({sign * rec[second] / abs(rec[ipk]):.2f} of it, {1e3 * (second - ipk) / fs:.1f} "
                    "ms later)", "delay_s": float((second - ipk) / fs),
            "relative_size": float(sign * rec[second] / abs(rec[ipk])),
            "notch_db": float(20 * np.log10(np.min(both[lines] / one[lines]))), "blow": (onset, end)}
