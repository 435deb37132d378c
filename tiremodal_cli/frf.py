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

from .errors import DataFormatError, ParameterError
from .hits import clipped_samples, double_hit
from .windows import exponential_window, force_window

log = logging.getLogger(__name__)

__all__ = ["ESTIMATORS", "FORMS", "FRFOptions", "FRFResult", "Rejection", "estimate", "h1",
           "compute_frf", "convert_form"]

ESTIMATORS = ("H1", "H2", "Hv")
FORMS = ("accelerance", "mobility", "receptance")


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
    with np.errstate(divide="ignore", invalid="ignore"):
        if Gff.ndim < Gfy.ndim:
            Gff = np.broadcast_to(Gff, Gfy.shape)
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


def _leave_one_out_residual(F, Y):
    """How well the other hits predict each hit: ``Σ|Y_i − Ĥ_{−i} F_i|² / Σ|Y_i|²``.

    Ĥ_{−i} is the H1 of all hits but i. For consistent hits this is the noise-to-signal
    energy, the same for every hit; a hit that does not belong stands out against the
    median of the hits (a channel at a node is noisy for every hit and does not).

    F : (n_hits, n_f) ; Y : (n_hits, n_channels, n_f) ; returns (n_hits, n_channels)
    """
    gfy = np.conj(F)[:, None, :] * Y
    gff = np.abs(F) ** 2
    tot_fy, tot_ff = gfy.sum(axis=0), gff.sum(axis=0)
    out = np.empty(Y.shape[:2])
    for i in range(F.shape[0]):
        with np.errstate(divide="ignore", invalid="ignore"):
            h = np.where(tot_ff > gff[i], (tot_fy - gfy[i]) / (tot_ff - gff[i]), 0)
        res = np.sum(np.abs(Y[i] - h * F[i]) ** 2, axis=-1)
        sig = np.sum(np.abs(Y[i]) ** 2, axis=-1)
        out[i] = np.where(sig > 0, res / np.where(sig > 0, sig, 1), 0.0)
    return out


def _time_checks(f, y, fs, opt, names, ip):
    """Per-hit checks on one point's records; returns rejections and per-record RMS."""
    rej = []
    n_h = f.shape[0]
    fin_f = np.isfinite(f).all(axis=-1)
    fin_y = np.isfinite(y).all(axis=-1)  # (n_h, n_c)
    rms = np.sqrt(np.mean(np.square(np.where(np.isfinite(y), y, 0.0), dtype=float), axis=-1))
    for h in range(n_h):
        if not fin_f[h]:
            rej.append(Rejection(ip, h, "non-finite force samples", "force"))
        for c in np.flatnonzero(~fin_y[h]):
            rej.append(Rejection(ip, h, "non-finite response samples", names[c]))
    if not opt.check_hits:
        return rej, rms
    ok = fin_f & fin_y.all(axis=1)
    fz = np.where(np.isfinite(f), f, 0.0)
    yz = np.where(np.isfinite(y), y, 0.0)
    clip_f = clipped_samples(fz) > 0
    clip_y = clipped_samples(yz) > 0
    dbl = double_hit(fz, fs, min_relative=opt.double_hit_relative)
    for h in range(n_h):
        if not ok[h]:
            continue
        if np.max(np.abs(fz[h])) == 0:
            rej.append(Rejection(ip, h, "zero force (no impact recorded)", "force"))
            continue
        if clip_f[h]:
            rej.append(Rejection(ip, h, "clipped (overloaded) force", "force"))
        for c in np.flatnonzero(clip_y[h]):
            rej.append(Rejection(ip, h, "clipped (overloaded) response", names[c]))
        if dbl[h]:
            rej.append(Rejection(ip, h, "double hit", "force"))
    return rej, rms


def compute_frf(m, opt: FRFOptions = FRFOptions(), *, progress=None) -> FRFResult:
    """The FRF stage: checks, windows, spectra and averaging over the accepted hits.

    Works point by point, so ``m.force``/``m.response`` may be lazy (h5py datasets) and
    memory stays at a few points' records.

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
        Every hit of every point rejected, or zero force at a point.
    """
    opt.check()
    fs, ns = float(m.sample_rate), int(m.n_samples)
    freq = np.fft.rfftfreq(ns, 1 / fs)
    sel = _band(freq, opt.band_hz, fs)
    names = tuple(m.channel_name)
    n_p, n_h, n_c = m.n_points, m.n_hits, m.n_channels
    exp_w, tau = (exponential_window(ns, fs, end_value=opt.exp_end, tau_s=opt.exp_tau_s)
                  if (opt.exp_end or opt.exp_tau_s) else (None, None))
    total = 2 * n_p
    # pass 1: time-domain checks and record RMS (for dead records and channels)
    rejections, rms, spread = [], np.zeros((n_p, n_h, n_c)), np.zeros((n_p, n_h, n_c))
    for ip in range(n_p):
        y = np.asarray(m.response[ip])
        r, rms[ip] = _time_checks(np.asarray(m.force[ip]), y, fs, opt, names, ip)
        spread[ip] = np.ptp(np.where(np.isfinite(y), y, 0.0), axis=-1)
        rejections += r
        if progress:
            progress(ip + 1, total)
    med = np.median(rms.reshape(-1, n_c), axis=0)
    dead_ch = tuple(names[c] for c in range(n_c)
                    if med[c] <= opt.dead_channel_relative * med.max() or np.all(spread[..., c] == 0))
    for name in dead_ch:
        rejections.append(Rejection(None, None, "dead channel (no signal in any hit)", name))
    live = np.array([n not in dead_ch for n in names])
    if opt.check_hits:
        # a record that does not move at all is a dead sensor or cable in that hit; a small
        # one is not (a sensor at a node of the response records noise, and that is data)
        for ip, h, c in zip(*np.nonzero((spread == 0) & live)):
            rejections.append(Rejection(int(ip), int(h), "dead record (constant samples)", names[c]))
    bad = np.zeros((n_p, n_h), dtype=bool)
    for r in rejections:
        if r.hit is not None:
            bad[r.point, r.hit] = True
    # pass 2: spectra, hit-consistency check, averaging
    nf = int(sel.sum())
    H = np.full((n_c, n_p, nf), np.nan + 0j)
    coh = np.full((n_c, n_p, nf), np.nan)
    n_avg = np.zeros(n_p, dtype=int)
    for ip in range(n_p):
        acc = np.flatnonzero(~bad[ip])
        if acc.size:
            f = np.asarray(m.force[ip][acc], dtype=float)
            y = np.asarray(m.response[ip][acc], dtype=float)
            if opt.force_window:
                f = f * force_window(f, fs, length_s=opt.force_window_s, taper_s=opt.taper_s)
            if exp_w is not None:
                f = f * exp_w
                y = y * exp_w
            F = np.fft.rfft(f, axis=-1)[:, sel]
            Y = np.fft.rfft(y, axis=-1)[:, :, sel]
            if opt.check_hits and acc.size >= 3:
                d = _leave_one_out_residual(F, Y[:, live])
                ratio = d / np.median(d, axis=0, keepdims=True)
                flag = (d > opt.hit_residual_max) & (ratio > opt.hit_residual_ratio)
                for k in np.flatnonzero(flag.any(axis=1)):
                    c = np.flatnonzero(live)[np.argmax(np.where(flag[k], ratio[k], -np.inf))]
                    rejections.append(Rejection(ip, int(acc[k]), "poor consistency with the other hits "
                                                f"(residual {d[k, list(np.flatnonzero(live)).index(c)]:.2f} of its "
                                                f"energy, {ratio[k].max():.1f}× the hits' median)", names[c]))
                keep = ~flag.any(axis=1)
                F, Y, acc = F[keep], Y[keep], acc[keep]
            if acc.size:
                H[:, ip], coh[:, ip] = estimate(F[:, None, :], Y, estimator=opt.estimator)
        n_avg[ip] = acc.size
        if progress:
            progress(n_p + ip + 1, total)
    H[~live] = np.nan
    coh[~live] = np.nan
    failed = np.flatnonzero(n_avg == 0)
    if failed.size == n_p:
        reasons = sorted({r.reason for r in rejections if r.hit is not None})
        raise DataFormatError(f"every hit of every point was rejected ({'; '.join(reasons)})")
    for ip in failed:
        log.warning("point %d (%.1f°): all %d hits rejected; the point is left out", ip,
                    np.rad2deg(m.point_angle[ip]), n_h)
    keep_p = n_avg > 0
    lines, Hf = convert_form(freq[sel], H[:, keep_p], opt.form)
    fq, coh = freq[sel][lines], coh[:, keep_p][..., lines]
    rejections.sort(key=lambda r: (r.point if r.point is not None else -1, r.hit if r.hit is not None else -1))
    meta = {"force_window": {"applied": opt.force_window, "length_s": opt.force_window_s,
                             "taper_s": opt.taper_s, "rule": "pulse extent ×2, ≥ 8 samples, 4-sample cosine tapers"
                             if opt.force_window_s is None else "given"},
            "exponential_window": None if tau is None else {"tau_s": tau, "end_value": float(exp_w[-1]),
                                                            "added_decay_rate_per_s": 1.0 / tau},
            "failed_points": [int(i) for i in failed]}
    return FRFResult(freq_hz=fq, H=Hf, coherence=coh, n_averages=n_avg[keep_p],
                     point_index=np.flatnonzero(keep_p), point_angle=np.asarray(m.point_angle)[keep_p],
                     channel_name=names, channel_location=tuple(m.channel_location),
                     channel_angle=np.asarray(m.channel_angle), rejections=tuple(rejections),
                     dead_channels=dead_ch, estimator=opt.estimator, form=opt.form, exp_tau_s=tau,
                     sample_rate=fs, n_samples=ns, meta=meta)
