"""FRF estimation from impact records: H1, H2, Hv, coherence, hit-quality checks.

Conventions (``docs/conventions.md``): spectra are ``numpy.fft.rfft`` of the windowed
records; the cross-spectrum is ``G_fy = Σ_hits conj(F) Y`` (conjugate of the force's FFT
times the response's FFT, as in :func:`scipy.signal.csd`); auto-spectra ``G_ff = Σ |F|²``,
``G_yy = Σ |Y|²``. Then

* H1 = G_fy / G_ff (noise on the response averages out; the default for impact tests),
* H2 = G_yy / conj(G_fy) (noise on the force averages out),
* Hv = (G_yy − G_ff + √((G_ff − G_yy)² + 4|G_fy|²)) / (2 conj(G_fy)) (total least squares),
* γ² = |G_fy|² / (G_ff G_yy).

FRFs are laid out (n_channels, n_points, n_freq). The records' native form is
accelerance (m/s²/N); mobility and receptance divide by iω and −ω² and drop the 0 Hz line.

References
----------
Bendat, J. S. & Piersol, A. G., *Random Data*, 4th ed., Wiley 2010, ch. 9.
Ewins, D. J., *Modal Testing*, 2nd ed., Research Studies Press 2000, ch. 3.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from tiremodal_cli.conventions import FRF_FORMS
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.frf.hits import clip_count, bounce_from_segments, double_hit, pulse_extent, pulse_segments
from tiremodal_cli.frf.windows import exponential_window, force_window

log = logging.getLogger(__name__)

__all__ = ["ESTIMATORS", "FORMS", "FRFOptions", "FRFResult", "Rejection", "estimate", "h1",
           "compute_frf", "convert_form"]

ESTIMATORS = ("H1", "H2", "Hv")
FORMS = FRF_FORMS


@dataclass(frozen=True)
class Rejection:
    """A rejected hit (or a whole channel when ``hit`` is None)."""

    point: int | None
    hit: int | None
    reason: str
    channel: str | None = None

    def to_dict(self):
        return {"point": self.point, "hit": self.hit, "channel": self.channel, "reason": self.reason}


@dataclass(frozen=True)
class FRFOptions:
    """Options of the FRF stage (units in the names).

    ``exp_end`` / ``exp_tau_s``: exponential window (give one, or neither for none);
    ``force_window``: apply the force window; ``force_window_s``/``taper_s``: its lengths
    (None: from the pulse). A hit is rejected as inconsistent (needs ≥ 3 hits) when, on
    some channel, the other hits' H1 leaves more than ``hit_residual_max`` of its spectral
    energy unexplained and that is more than ``hit_residual_ratio`` × the hits' median.
    """

    estimator: str = "H1"
    form: str = "accelerance"
    band_hz: tuple[float, float] | None = None
    force_window: bool = True
    force_window_s: float | None = None
    taper_s: float | None = None
    exp_end: float | None = None
    exp_tau_s: float | None = None
    check_hits: bool = True
    double_hit_relative: float = 0.2
    dead_channel_relative: float = 1e-5
    hit_residual_max: float = 0.1
    hit_residual_ratio: float = 3.0

    def check(self):
        if self.estimator not in ESTIMATORS:
            raise ParameterError(f"estimator={self.estimator!r}; allowed: {', '.join(ESTIMATORS)}")
        if self.form not in FORMS:
            raise ParameterError(f"form={self.form!r}; allowed: {', '.join(FORMS)}")
        if self.exp_end is not None and self.exp_tau_s is not None:
            raise ParameterError("give the exponential window as exp_end or exp_tau_s, not both")
        if not 0 < self.hit_residual_max:
            raise ParameterError(f"hit_residual_max={self.hit_residual_max} must be > 0")


@dataclass(frozen=True)
class FRFResult:
    """FRFs of one test.

    Attributes
    ----------
    freq_hz : (n_freq,) ndarray, Hz
    H : (n_channels, n_points, n_freq) complex ndarray      in ``form`` units per N
    coherence : (n_channels, n_points, n_freq) ndarray
    n_averages : (n_points,) ndarray of int                  accepted hits per point
    point_index : (n_points,) ndarray of int                 index of each point in the input
    point_angle : (n_points,) ndarray, rad
    channel_name, channel_location : tuple of str
    channel_angle : (n_channels,) ndarray, rad
    rejections : tuple of Rejection
    dead_channels : tuple of str                             their FRFs are NaN
    estimator, form : str
    exp_tau_s : float or None                                exponential window, s
    sample_rate : float, Hz ; n_samples : int                of the records
    meta : dict                                              windows and provenance
    """

    freq_hz: np.ndarray
    H: np.ndarray
    coherence: np.ndarray
    n_averages: np.ndarray
    point_index: np.ndarray
    point_angle: np.ndarray
    channel_name: tuple[str, ...]
    channel_location: tuple[str, ...]
    channel_angle: np.ndarray
    rejections: tuple[Rejection, ...]
    dead_channels: tuple[str, ...]
    estimator: str
    form: str
    exp_tau_s: float | None
    sample_rate: float
    n_samples: int
    meta: dict = field(default_factory=dict)


def estimate(F, Y, *, estimator: str = "H1", axis: int = 0):
    """FRF and coherence from stacks of spectra.

    Parameters
    ----------
    F : (n_avg, ..., n_freq) complex array        force spectra (broadcast against Y)
    Y : (n_avg, ..., n_freq) complex array        response spectra
    estimator : {"H1", "H2", "Hv"}
    axis : int                                    the averaging axis

    Returns
    -------
    H : complex ndarray, coherence : ndarray      averaged over ``axis``
    """
    Gff = np.sum(np.abs(F) ** 2, axis=axis)
    Gyy = np.sum(np.abs(Y) ** 2, axis=axis)
    Gfy = np.sum(np.conj(F) * Y, axis=axis)
    return _from_products(Gfy, Gff, Gyy, estimator)


def _from_products(Gfy, Gff, Gyy, estimator):
    """H1/H2/Hv and γ² from the averaged cross- and auto-spectra (in their precision)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        coh = np.abs(Gfy) ** 2 / (Gff * Gyy)
        if estimator == "H1":
            H = Gfy / Gff
        elif estimator == "H2":
            H = Gyy / np.conj(Gfy)
        elif estimator == "Hv":
            H = (Gyy - Gff + np.sqrt((Gff - Gyy) ** 2 + 4 * np.abs(Gfy) ** 2)) / (2 * np.conj(Gfy))
        else:
            raise ParameterError(f"estimator={estimator!r}; allowed: {', '.join(ESTIMATORS)}")
    return H, coh


def h1(force, response, fs: float, *, exp_end: float | None = None):
    """H1 and coherence of one point's hits, no windows but an optional exponential one.

    Parameters
    ----------
    force : (n_hits, n_samples) array, N
    response : (n_hits, n_channels, n_samples) array
    fs : float, Hz

    Returns
    -------
    freq_hz : (n_freq,) ndarray ; H : (n_channels, n_freq) ; coherence : (n_channels, n_freq)
    """
    force = np.asarray(force, dtype=float)
    response = np.asarray(response, dtype=float)
    n = force.shape[-1]
    w = exponential_window(n, fs, end_value=exp_end)[0] if exp_end else 1.0
    F = np.fft.rfft(force * w, axis=-1)
    Y = np.fft.rfft(response * w, axis=-1)
    H, coh = estimate(F[:, None, :], Y)
    return np.fft.rfftfreq(n, 1 / fs), H, coh


def convert_form(freq_hz, H, form: str):
    """Accelerance → ``form``.

    Returns
    -------
    keep : (n_freq,) bool ndarray    lines kept (the 0 Hz line is dropped when dividing by ω)
    H : complex ndarray              the FRFs on the kept lines
    """
    freq_hz = np.asarray(freq_hz)
    if form == "accelerance":
        return np.ones(freq_hz.size, dtype=bool), H
    keep = freq_hz > 0
    w = 2 * np.pi * freq_hz[keep]
    H = H[..., keep]
    return keep, H / (1j * w) if form == "mobility" else H / (-(w**2))


def _band(freq, band_hz, fs):
    if band_hz is None:
        return np.ones(freq.size, dtype=bool)
    lo, hi = band_hz
    nyq = fs / 2
    if not (0 <= lo < hi) or hi > nyq:
        raise ParameterError(f"band {lo:g}–{hi:g} Hz is outside the data (0–{nyq:g} Hz) or empty")
    sel = (freq >= lo) & (freq <= hi)
    if sel.sum() < 2:
        raise ParameterError(f"band {lo:g}–{hi:g} Hz holds fewer than 2 spectral lines "
                             f"(resolution {freq[1]:g} Hz)")
    return sel


def _leave_one_out_residual(a, p, e):
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


def _time_checks(f, y, fs, opt, names, ip):
    """Per-hit checks on one point's records.

    Returns the rejections, a (n_hits,) mask of rejected hits and the (n_hits, n_channels)
    record peaks (for the dead-channel test).
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


def _test_wide_checks(m, fs, opt):
    """Checks over every hit of the test: a bounce within the pulse (:func:`bounce_in_pulse`
    over all the force records; read a point at a time, kept as 25 ms segments).

    Returns {point: [(hit, notch_hz), ...]} and the checks that could not run, each said once
    (a warning, and ``meta["checks_not_run"]``): the bounce check with fewer than 5 usable
    hits in the test, the consistency check with fewer than 3 hits per point.
    """
    out, not_run = {}, []
    if not opt.check_hits:
        return out, not_run
    n_p, n_h = m.n_points, m.n_hits
    parts = [pulse_segments(np.asarray(m.force[ip], dtype=float), fs) for ip in range(n_p)]  # one point at a time
    seg, noise, ok = (np.concatenate([p[k] for p in parts]) for k in range(3))
    flags, notch, ran = bounce_from_segments(seg, noise, ok, fs, min_relative=opt.double_hit_relative)
    if not ran:
        not_run.append(f"double hits within the pulse (force spectrum): needs at least 5 usable hits in the test, "
                       f"it has {n_p * n_h}")
    for k in np.flatnonzero(flags):
        out.setdefault(int(k) // n_h, []).append((int(k) % n_h, float(notch[k])))
    if n_h < 3:
        not_run.append(f"consistency of the hits: needs at least 3 hits per point, the test has {n_h}")
    for what in not_run:
        log.warning("hit check not run: %s", what)
    return out, not_run


def compute_frf(m, opt: FRFOptions = FRFOptions(), *, progress=None) -> FRFResult:
    """The FRF stage: checks, windows, spectra and averaging over the accepted hits.

    One pass, point by point, so ``m.force``/``m.response`` may be lazy (h5py datasets)
    and memory stays at one point's records. float32 records are transformed in single
    precision (as recorded), float64 ones in double.

    Parameters
    ----------
    m : Measurement
    opt : FRFOptions
    progress : callable(done, total), optional

    Returns
    -------
    FRFResult

    Raises
    ------
    DataFormatError
        Every hit of every point rejected (zero or non-finite force, all clipped, ...).
    """
    opt.check()
    fs, ns = float(m.sample_rate), int(m.n_samples)
    freq = np.fft.rfftfreq(ns, 1 / fs)
    sel = _band(freq, opt.band_hz, fs)
    lo, hi = np.flatnonzero(sel)[[0, -1]]
    names = tuple(m.channel_name)
    n_p, n_h, n_c = m.n_points, m.n_hits, m.n_channels
    real = np.float32 if m.response.dtype == np.float32 and m.force.dtype == np.float32 else np.float64
    exp_w, tau = (exponential_window(ns, fs, end_value=opt.exp_end, tau_s=opt.exp_tau_s)
                  if (opt.exp_end or opt.exp_tau_s) else (None, None))
    if exp_w is not None:
        exp_w = exp_w.astype(real)
    nf = hi - lo + 1
    H = np.full((n_c, n_p, nf), np.nan + 0j)
    coh = np.full((n_c, n_p, nf), np.nan)
    n_avg = np.zeros(n_p, dtype=int)
    rejections, peaks = [], np.zeros((n_p, n_h, n_c))
    bounce, not_run = _test_wide_checks(m, fs, opt)
    for ip in range(n_p):
        f = np.asarray(m.force[ip], dtype=real)
        y = np.asarray(m.response[ip], dtype=real)
        rej, bad, peaks[ip], extent = _time_checks(f, y, fs, opt, names, ip)
        for h, notch in bounce.get(ip, ()):
            if not bad[h]:
                rej.append(Rejection(ip, h, f"double hit (a bounce within the pulse: force spectrum notch at "
                                            f"{notch:.0f} Hz)", "force"))
                bad[h] = True
        rejections += rej
        acc = np.flatnonzero(~bad)
        if acc.size:
            if extent is not None and opt.force_window_s is None:
                extent = (extent[0][acc], extent[1][acc])
            else:
                extent = None
            if acc.size < n_h:
                f, y = f[acc], y[acc]
            if opt.force_window:
                f = f * force_window(f, fs, length_s=opt.force_window_s, taper_s=opt.taper_s, extent=extent)
            if exp_w is not None:
                f = f * exp_w
                y = y * exp_w
            F = np.fft.rfft(f, axis=-1)[:, lo:hi + 1]
            Y = np.fft.rfft(y, axis=-1)[:, :, lo:hi + 1]
            a = np.conj(F)[:, None, :] * Y  # per-hit products, shared by check and estimate
            p = (F.real**2 + F.imag**2)[:, None, :]
            e = Y.real**2 + Y.imag**2
            if opt.check_hits and acc.size >= 3:
                # a statistic, not an estimate: every k-th line (≤ 1024 of them) tells as much
                k = max(1, a.shape[-1] // 1024)
                d = _leave_one_out_residual(a[..., ::k], p[..., ::k], e[..., ::k])
                ratio = d / np.maximum(np.median(d, axis=0, keepdims=True), np.finfo(float).tiny)
                flag = (d > opt.hit_residual_max) & (ratio > opt.hit_residual_ratio)
                for i in np.flatnonzero(flag.any(axis=1)):
                    c = int(np.argmax(np.where(flag[i], ratio[i], -np.inf)))
                    rejections.append(Rejection(ip, int(acc[i]), "poor consistency with the other hits "
                                                f"(residual {d[i, c]:.2f} of its energy, {ratio[i, c]:.1f}× the "
                                                "hits' median)", names[c]))
                keep = ~flag.any(axis=1)
                if not keep.all():
                    a, p, e, acc = a[keep], p[keep], e[keep], acc[keep]
            if acc.size:
                H[:, ip], coh[:, ip] = _from_products(a.sum(axis=0), p.sum(axis=0), e.sum(axis=0),
                                                      opt.estimator)
        n_avg[ip] = acc.size
        if progress:
            progress(ip + 1, n_p)
    med = np.median(peaks.reshape(-1, n_c), axis=0)
    dead_ch = tuple(names[c] for c in range(n_c) if med[c] <= opt.dead_channel_relative * med.max())
    for name in dead_ch:
        rejections.append(Rejection(None, None, "dead channel (no signal in any hit)", name))
    live = np.array([n not in dead_ch for n in names])
    H[~live] = np.nan
    coh[~live] = np.nan
    failed = np.flatnonzero(n_avg == 0)
    if failed.size == n_p:
        reasons = sorted({r.reason for r in rejections if r.hit is not None})
        raise DataFormatError(f"every hit of every point was rejected ({'; '.join(reasons)})")
    for ip in failed:
        log.warning("point %d (%.1f°): all %d hits rejected; the point is left out", ip + 1,
                    np.rad2deg(m.point_angle[ip]), n_h)
    keep_p = n_avg > 0
    if not keep_p.all():  # (copies of H and coh only when a point is left out: 15 % of the stage)
        H, coh = H[:, keep_p], coh[:, keep_p]
    lines, Hf = convert_form(freq[sel], H, opt.form)
    fq = freq[sel][lines]
    if not lines.all():
        coh = coh[..., lines]
    rejections.sort(key=lambda r: (r.point if r.point is not None else -1, r.hit if r.hit is not None else -1))
    meta = {"force_window": {"applied": opt.force_window, "length_s": opt.force_window_s,
                             "taper_s": opt.taper_s, "rule": "pulse extent ×2, ≥ 8 samples, 4-sample cosine tapers"
                             if opt.force_window_s is None else "given"},
            "exponential_window": None if tau is None else {"tau_s": tau, "end_value": float(exp_w[-1]),
                                                            "added_decay_rate_per_s": 1.0 / tau},
            "failed_points": [int(i) for i in failed], "precision": np.dtype(real).name,
            "checks_not_run": not_run}
    return FRFResult(freq_hz=fq, H=Hf, coherence=coh, n_averages=n_avg[keep_p],
                     point_index=np.flatnonzero(keep_p), point_angle=np.asarray(m.point_angle)[keep_p],
                     channel_name=names, channel_location=tuple(m.channel_location),
                     channel_angle=np.asarray(m.channel_angle), rejections=tuple(rejections),
                     dead_channels=dead_ch, estimator=opt.estimator, form=opt.form, exp_tau_s=tau,
                     sample_rate=fs, n_samples=ns, meta=meta)
