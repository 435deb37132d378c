"""FRF estimation from impact records: H1, H2, Hv, coherence, hit-quality checks.

Conventions (``docs/conventions.md``): spectra are the real FFT of the windowed records
(``scipy.fft.rfft``: the same transform as ``numpy.fft.rfft``, 2–3 × faster in single precision); the cross-spectrum is ``G_fy = Σ_hits conj(F) Y`` (conjugate of the force's FFT
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
import scipy.fft

from tiremodal_cli.conventions import FRF_FORMS
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.frf.screening import (Rejection, bounced_only_hits, inconsistent_hits, test_wide_checks,
                                         time_checks)
from tiremodal_cli.frf.windows import exponential_window, force_window

log = logging.getLogger(__name__)

__all__ = ["ESTIMATORS", "FORMS", "FRFOptions", "FRFResult", "Rejection", "estimate", "h1",
           "compute_frf", "convert_form"]

ESTIMATORS = ("H1", "H2", "Hv")
FORMS = FRF_FORMS


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
    force_autospectrum : (n_points, n_freq) ndarray or None  mean |F|² over each point's
        accepted hits on the FRF lines (the DFT of the windowed force record, N²: the
        denominator of H1 over the hits); None when not known (FRFs read from UFF 58)
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
    force_autospectrum: np.ndarray | None = None


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
    F = scipy.fft.rfft(force * w, axis=-1)
    Y = scipy.fft.rfft(response * w, axis=-1)
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


@dataclass(frozen=True)
class _Plan:
    """What every point of a test shares: sizes, the band's lines, precision, the exponential window."""

    fs: float
    ns: int
    freq: np.ndarray         # (ns // 2 + 1,) Hz, every line of the records
    sel: np.ndarray          # its lines in the band
    lo: int
    hi: int
    real: type               # np.float32 or np.float64: the records' precision
    exp_w: np.ndarray | None
    tau: float | None
    names: tuple


@dataclass(frozen=True)
class _Averages:
    """What the pass over the points gathered."""

    H: np.ndarray            # (n_channels, n_points, n_band) complex
    coh: np.ndarray
    n_avg: np.ndarray        # (n_points,) accepted hits
    peaks: np.ndarray        # (n_points, n_hits, n_channels) record peaks
    rejections: list
    not_run: list
    gff: np.ndarray          # (n_points, n_band) mean |F|² over the accepted hits
    bounced_used: list       # the double hits used for points with no other (bounced_only_hits)


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
    plan = _plan(m, opt)
    n_p, n_c = m.n_points, m.n_channels
    nf = plan.hi - plan.lo + 1
    H = np.full((n_c, n_p, nf), np.nan + 0j)
    coh = np.full((n_c, n_p, nf), np.nan)
    gff = np.zeros((n_p, nf))
    n_avg = np.zeros(n_p, dtype=int)
    rejections, peaks = [], np.zeros((n_p, m.n_hits, n_c))
    bounce, not_run = test_wide_checks(m, plan.fs, opt)
    bounced_used: list[dict] = []
    for ip in range(n_p):
        rej, n_avg[ip], peaks[ip], sums, used = _point(m, ip, plan, opt, bounce.get(ip, ()))
        rejections += rej
        bounced_used += used
        if sums is not None:
            H[:, ip], coh[:, ip] = _from_products(*sums, opt.estimator)
            gff[ip] = sums[1][0] / n_avg[ip]
        if progress:
            progress(ip + 1, n_p)
    return _result(m, plan, opt, _Averages(H, coh, n_avg, peaks, rejections, not_run, gff, bounced_used))


def _plan(m, opt: FRFOptions) -> _Plan:
    fs, ns = float(m.sample_rate), int(m.n_samples)
    freq = np.fft.rfftfreq(ns, 1 / fs)
    sel = _band(freq, opt.band_hz, fs)
    lo, hi = np.flatnonzero(sel)[[0, -1]]
    real = np.float32 if m.response.dtype == np.float32 and m.force.dtype == np.float32 else np.float64
    exp_w, tau = (exponential_window(ns, fs, end_value=opt.exp_end, tau_s=opt.exp_tau_s)
                  if (opt.exp_end or opt.exp_tau_s) else (None, None))
    if exp_w is not None:
        exp_w = exp_w.astype(real)
    return _Plan(fs, ns, freq, sel, lo, hi, real, exp_w, tau, tuple(m.channel_name))


def _point(m, ip: int, plan: _Plan, opt: FRFOptions, bounced):
    """One point: its checks, and the sums of the accepted hits' spectra products.

    Returns the rejections, the number of hits averaged, the (n_hits, n_channels) record
    peaks, and (Σ conj(F) Y, Σ |F|², Σ |Y|²) over the band (None: no hit accepted).
    """
    f = np.asarray(m.force[ip], dtype=plan.real)
    y = np.asarray(m.response[ip], dtype=plan.real)
    rej, bad, peaks, extent = time_checks(f, y, plan.fs, opt, plan.names, ip)
    for h, notch, _ in bounced:
        if not bad[h]:
            rej.append(Rejection(ip, h, f"double hit (a bounce within the pulse: force spectrum notch at "
                                        f"{notch:.0f} Hz)", "force"))
            bad[h] = True
    acc, used = np.flatnonzero(~bad), []
    if not acc.size and opt.check_hits:
        acc, later, used = bounced_only_hits(f, plan.fs, rej, ip, extent, {h: d for h, _, d in bounced})
        extent, rej = (*extent, *later) if acc.size else extent, [r for r in rej if r.hit not in set(acc.tolist())]
    if not acc.size:
        return rej, 0, peaks, None, used
    a, p, e = _hit_products(f, y, acc, extent, plan, opt)
    if opt.check_hits and acc.size >= 3:
        keep, more = inconsistent_hits(a, p, e, acc, opt, plan.names, ip)
        rej += more
        if not keep.all():
            a, p, e, acc = a[keep], p[keep], e[keep], acc[keep]
    if not acc.size:
        return rej, 0, peaks, None, used
    return rej, acc.size, peaks, (a.sum(axis=0), p.sum(axis=0), e.sum(axis=0)), used


def _hit_products(f, y, acc, extent, plan: _Plan, opt: FRFOptions):
    """The accepted hits windowed and transformed: per-hit conj(F) Y (n_acc, n_channels, n_band),
    |F|² (n_acc, 1, n_band) and |Y|² (n_acc, n_channels, n_band), shared by check and estimate."""
    if extent is not None and opt.force_window_s is None:
        extent = tuple(e[acc] for e in extent)  # (start, stop[, the later blows' start, stop])
    else:
        extent = None
    if acc.size < f.shape[0]:
        f, y = f[acc], y[acc]
    if opt.force_window:
        f = f * force_window(f, plan.fs, length_s=opt.force_window_s, taper_s=opt.taper_s,
                             extent=extent and extent[:2], also=(extent or ())[2:] or None)
    if plan.exp_w is not None:
        f = f * plan.exp_w
        y = y * plan.exp_w
    F = scipy.fft.rfft(f, axis=-1)[:, plan.lo:plan.hi + 1]
    Y = scipy.fft.rfft(y, axis=-1)[:, :, plan.lo:plan.hi + 1]
    a = np.conj(F)[:, None, :] * Y
    p = (F.real**2 + F.imag**2)[:, None, :]
    e = Y.real**2 + Y.imag**2
    return a, p, e


def _result(m, plan: _Plan, opt: FRFOptions, avg: _Averages) -> FRFResult:
    """Dead channels and failed points out, the form converted, the rejections sorted."""
    names, n_c, n_p, n_avg = plan.names, m.n_channels, m.n_points, avg.n_avg
    H, coh, rejections = avg.H, avg.coh, avg.rejections
    med = np.median(avg.peaks.reshape(-1, n_c), axis=0)
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
                    np.rad2deg(m.point_angle[ip]), m.n_hits)
    keep_p = n_avg > 0
    if not keep_p.all():  # (copies of H and coh only when a point is left out: 15 % of the stage)
        H, coh = H[:, keep_p], coh[:, keep_p]
    lines, Hf = convert_form(plan.freq[plan.sel], H, opt.form)
    gff = avg.gff[keep_p][:, lines]
    if not lines.all():
        coh = coh[..., lines]
    rejections.sort(key=lambda r: (r.point if r.point is not None else -1, r.hit if r.hit is not None else -1))
    return FRFResult(freq_hz=plan.freq[plan.sel][lines], H=Hf, coherence=coh, n_averages=n_avg[keep_p],
                     point_index=np.flatnonzero(keep_p), point_angle=np.asarray(m.point_angle)[keep_p],
                     channel_name=names, channel_location=tuple(m.channel_location),
                     channel_angle=np.asarray(m.channel_angle), rejections=tuple(rejections),
                     dead_channels=dead_ch, estimator=opt.estimator, form=opt.form, exp_tau_s=plan.tau,
                     sample_rate=plan.fs, n_samples=plan.ns, meta=_meta(opt, plan, failed, avg.not_run, avg.bounced_used),
                     force_autospectrum=gff)


def _meta(opt: FRFOptions, plan: _Plan, failed, not_run, bounced_used) -> dict:
    """The windows applied, the points left out, the double hits used, the precision, the checks not run."""
    return {"force_window": {"applied": opt.force_window, "length_s": opt.force_window_s,
                             "taper_s": opt.taper_s, "rule": "pulse extent ×2, ≥ 8 samples, 4-sample cosine tapers"
                             if opt.force_window_s is None else "given"},
            "exponential_window": None if plan.tau is None else {"tau_s": plan.tau, "end_value": float(plan.exp_w[-1]),
                                                                 "added_decay_rate_per_s": 1.0 / plan.tau},
            "failed_points": [int(i) for i in failed], "double_hits_used": bounced_used,
            "precision": np.dtype(plan.real).name, "checks_not_run": not_run}
