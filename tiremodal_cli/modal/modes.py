"""The modal stage: FRFs → poles (LSCE + stabilization) → shapes (LSFD) → a modal table.

General for any structure. For a tyre (points around the tread with angles), the FRFs are
first split into circumferential orders (:mod:`tiremodal_cli.modal.spatial`) and each order is
swept on its own; the poles of all orders then get their shapes from one LSFD over the
physical FRFs. Damping is corrected for the exponential window recorded in the FRF file.
"""

from __future__ import annotations

import dataclasses
import logging
from dataclasses import dataclass, field

import numpy as np
from threadpoolctl import threadpool_limits

from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.modal.lsce import poles_to_modal, principal_responses, sweep, sweep_poly
from tiremodal_cli.modal.lsfd import FORM_POWER, lsfd, lsfd_participation, mpc, significance
from tiremodal_cli.modal.plscf import sweep_plscf
from tiremodal_cli.modal.spatial import decompose
from tiremodal_cli.modal.stabilization import StabilizationOptions, stabilize
from tiremodal_cli.frf.windows import correct_poles

log = logging.getLogger(__name__)
GROUP_MAX_ORDER = 40  # an order group holds a few modes, plus what models the band edges
SKIP = 0
POLY = True
POLY_ORDER = 30

__all__ = ["ModalOptions", "ModalResult", "coherence_threshold", "default_band", "estimate_modes", "is_circumferential",
           "modal_table_from_frf"]


@dataclass(frozen=True)
class ModalOptions:
    """Options of the modal stage.

    band_hz : analysis band (default: the FRFs' lines above 0 Hz)
    max_order : highest model order of the sweep (orders 2 … max_order)
    spatial : "auto" (split into circumferential orders when the points go round a tread),
              "on" or "off"
    method : pole estimator: "lsce", "plscf" (poly-reference LSCF, :mod:`.plscf`), or
              "both" (:func:`modal_table_from_frf` runs the two and marks the modes they
              agree on as confirmed)
    min_significance : reject a mode explaining less than this share of the response at
              its own frequency (a pole fitted to noise)
    """

    band_hz: tuple[float, float] | None = None
    max_order: int = 120
    spatial: str = "auto"
    min_significance: float = 0.05
    stabilization: StabilizationOptions = StabilizationOptions()
    rtol_svd: float = 1e-4
    method: str = "lsce"

    def check(self):
        if self.spatial not in ("auto", "on", "off"):
            raise ParameterError(f"spatial={self.spatial!r}; allowed: auto, on, off")
        if self.method not in ("lsce", "plscf", "both"):
            raise ParameterError(f"method={self.method!r}; allowed: lsce, plscf, both")
        if not 2 <= self.max_order <= 400:
            raise ParameterError(f"max_order={self.max_order} must be 2 … 400")


@dataclass(frozen=True)
class ModalResult:
    """Modes found in a set of FRFs.

    Attributes
    ----------
    freq_hz, damping_ratio : (n_modes,) ndarray     structural (window-corrected) values
    poles : (n_modes,) complex ndarray              as estimated from the FRFs, rad/s
    shapes : (n_modes, n_channels, n_points) complex ndarray   LSFD residues
    mpc, significance : (n_modes,) ndarray
    group : (n_modes,) ndarray of int               circumferential order group (−1: none)
    fit_error : (n_channels, n_points) ndarray      ‖H − Ĥ‖/‖H‖ over the band
    synthesis : (n_channels, n_points, n_band) complex ndarray
    band_freq_hz : (n_band,) ndarray
    diagrams : list of (group, Diagram)
    rejected : list of dict                         modes dropped after LSFD, with reasons
    """

    freq_hz: np.ndarray
    damping_ratio: np.ndarray
    poles: np.ndarray
    shapes: np.ndarray
    mpc: np.ndarray
    significance: np.ndarray
    group: np.ndarray
    fit_error: np.ndarray
    synthesis: np.ndarray
    band_freq_hz: np.ndarray
    diagrams: list = field(default_factory=list)
    rejected: list = field(default_factory=list)
    meta: dict = field(default_factory=dict)


def is_circumferential(point_angle, channel_location) -> bool:
    """True when the points go round the tread (≥ 8 distinct angles spanning > 270°) and a
    tread channel exists: the data of a tyre test."""
    a = np.mod(np.asarray(point_angle, dtype=float), 2 * np.pi)
    if a.size < 8 or "tread" not in tuple(channel_location) or not np.all(np.isfinite(a)):
        return False
    a = np.sort(a)  # the points may be stored from any origin, in either direction
    gaps = np.diff(np.concatenate([a, a[:1] + 2 * np.pi]))
    return len(np.unique(np.round(a, 9))) >= 8 and gaps.max() < np.pi / 2


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
    antiresonance, a notch of the force — are kept: they hold no mode to lose). With one
    average the coherence is 1 by construction and tells nothing; without a force
    spectrum either, the band is every line above 0 Hz. No constant depends on the sample
    rate: the band follows the test's own noise and excitation.

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
    why = []
    n_d = int(np.median(n_averages)) if n_averages is not None and np.size(n_averages) else 0
    if coherence is not None and n_d >= 2:
        c = np.asarray(coherence, dtype=float).reshape(-1, f.size)
        c = c[np.all(np.isfinite(c), axis=1)]
        if c.size:
            thr = coherence_threshold(n_d)
            ok &= np.median(c, axis=0) >= thr
            why.append(f"median coherence ≥ {thr:.2f} (noise alone exceeds it in {100 * COHERENCE_ALPHA:g} % "
                       f"of FRFs with {n_d} averages)")
    else:
        why.append("coherence not used (one average: it is 1 by construction)")
    if force_autospectrum is not None:
        g = np.asarray(force_autospectrum, dtype=float)
        ok &= g >= g[f > 0].max() * 10 ** (-FORCE_DROP_DB / 10)
        why.append(f"force autospectrum within {FORCE_DROP_DB:g} dB of its peak")
    idx = np.flatnonzero(ok)
    if idx.size == 0:
        raise DataFormatError("no line of the FRFs is supported by the data (" + "; ".join(why) + ")")
    runs = np.split(idx, np.flatnonzero(np.diff(idx) > 1) + 1)
    runs = [r for r in runs if r.size >= min_lines]
    if not runs:
        raise DataFormatError(f"no {min_lines} consecutive lines of the FRFs are supported by the data ("
                              + "; ".join(why) + ")")
    lo, hi = float(f[runs[0][0]]), float(f[runs[-1][-1]])
    return (lo, hi), "lines above 0 Hz where " + "; ".join(why)


def _band(freq_hz, band_hz):
    if band_hz is not None:
        return band_hz
    pos = freq_hz[freq_hz > 0]
    if pos.size < 16:
        raise DataFormatError("fewer than 16 lines above 0 Hz")
    return (float(pos[0]), float(pos[-1]))


def estimate_modes(freq_hz, H, **kwargs) -> "ModalResult":
    """Modal parameters of a set of FRFs (see :func:`_estimate_modes` for the parameters).

    The sweep is thousands of small solves and eigenproblems; OpenBLAS's threads cost more
    than they give at that size (measured: 2 × slower on 2 cores), so BLAS runs on one
    thread here (threadpoolctl), whatever the caller's setting.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _estimate_modes(freq_hz, H, **kwargs)


def _estimate_modes(freq_hz, H, *, point_angle=None, channel_location=(), form="accelerance",
                   exp_tau_s=None, opt: ModalOptions = ModalOptions(), progress=None) -> ModalResult:
    """Modal parameters of a set of FRFs.

    Parameters
    ----------
    freq_hz : (n_freq,) array, Hz
    H : (n_channels, n_points, n_freq) complex array
    point_angle : (n_points,) array, rad, optional
    channel_location : sequence of str, optional
    form : FRF form of H
    exp_tau_s : float, optional — exponential window to correct the damping for
    opt : ModalOptions
    progress : callable(done, total), optional

    Returns
    -------
    ModalResult
    """
    opt.check()
    freq_hz = np.asarray(freq_hz, dtype=float)
    H = np.asarray(H)
    if H.ndim != 3 or H.shape[-1] != freq_hz.size:
        raise DataFormatError(f"FRFs must be (n_channels, n_points, n_freq={freq_hz.size}); got {H.shape}")
    # a dead channel is NaN throughout (``tiremodal frf`` marks it so); NaN elsewhere is bad data
    live = ~np.array([np.all(np.isnan(H[c])) for c in range(H.shape[0])])
    if not live.any():
        raise DataFormatError("no channel has finite FRFs")
    bad = ~np.isfinite(H[live])
    if bad.any():
        c, p, k = np.argwhere(bad)[0]
        raise DataFormatError(f"FRF of channel {np.flatnonzero(live)[c] + 1}, point {p + 1} has a non-finite "
                              f"value at {freq_hz[k]:g} Hz")
    band = _band(freq_hz, opt.band_hz)
    sel = principal_responses(freq_hz, H[live].reshape(-1, freq_hz.size), band, rtol=opt.rtol_svd)
    lines = (freq_hz >= sel.freq_hz[0] - 1e-9) & (freq_hz <= sel.freq_hz[-1] + 1e-9)
    k_lines = freq_hz[lines]
    # one internal form: accelerance. The estimate then weighs the lines alike whatever
    # form the FRFs come in (receptance's 1/ω² would let the low lines dominate and turn
    # the high band's noise into stable poles); the residues mean the same in every form
    # (the LSFD basis carries (iω)^q), and the synthesis goes back to the given form.
    if form not in FORM_POWER:
        raise ParameterError(f"form={form!r}; allowed: {', '.join(FORM_POWER)}")
    if FORM_POWER[form] != 2 and k_lines[0] <= 0:
        raise ParameterError(f"the band of {form} FRFs must start above 0 Hz (got {k_lines[0]:g} Hz)")
    to_acc = (2j * np.pi * k_lines) ** (2 - FORM_POWER[form])
    form = "accelerance"
    Hb = H[live][:, :, lines] * to_acc
    n_live, n_p = Hb.shape[:2]
    spatial = opt.spatial == "on" or (opt.spatial == "auto" and point_angle is not None
                                      and is_circumferential(point_angle, channel_location))
    if spatial:
        groups = decompose(Hb, point_angle)
        group_max = min(opt.max_order, GROUP_MAX_ORDER)
    else:
        groups = {-1: (Hb.reshape(-1, lines.sum()), np.eye(n_live * n_p))}
        group_max = opt.max_order
    if group_max + 1 > lines.sum() // 2:
        raise ParameterError(f"model order {group_max} is too high for {lines.sum()} lines in the band "
                             f"(allowed up to {lines.sum() // 2 - 1})")
    diagrams, found, rejected = [], [], []
    Hflat = Hb.reshape(-1, lines.sum())
    synth = np.zeros((n_live * n_p, lines.sum()), dtype=complex)
    for i, (g, (rows, back)) in enumerate(sorted(groups.items())):
        b = principal_responses(k_lines, rows, None, rtol=opt.rtol_svd)
        n_h = rows.shape[0] // n_live
        if opt.method == "plscf":
            poly = spatial and POLY and n_h == 2
            Y3 = rows.reshape(n_h, n_live, -1).transpose(1, 0, 2) if poly else rows[:, None, :]
            poles = sweep_plscf(k_lines, Y3, range(1, (POLY_ORDER if poly else group_max) + 1))
            if not poly:  # one reference: no participation to compare, shapes from the band
                poles = [dataclasses.replace(op, participation=None) for op in poles]
        elif spatial and POLY and n_h == 2:
            # the cos and sin components as two references: split pairs resolve
            irf = np.fft.ifft(rows.reshape(n_h, n_live, -1).transpose(1, 0, 2), axis=-1)
            poles = sweep_poly(irf, range(1, POLY_ORDER + 1), b.dt, b.f_lo, b.width_hz)
        else:
            poles = sweep(b, range(2, group_max + 1), skip=SKIP)
        d = stabilize(b, poles, opt.stabilization)
        diagrams.append((g, d))
        s = np.array([c.representative.s for c in d.selected()], dtype=complex)
        parts = [c.representative.participation for c in d.selected()]
        if s.size and all(pt is not None for pt in parts):
            fit, s, rej, refit = _fit_group_poly(k_lines, rows, n_h, n_live, back, Hflat, s, np.array(parts), form,
                                                 opt, g)
        else:
            fit, s, rej, refit = _fit_group(k_lines, rows, back, Hflat, s, form, opt, g)
        rejected += rej
        scatter = {c.representative.s: float(np.std([m.freq_hz for m in c.members])) for c in d.selected()}
        if fit is not None:
            synth += back @ fit.synthesis
            for k in range(s.size):
                phys = back @ fit.residues[:, k]
                found.append((s[k], g, phys, float(fit.significance[k]), scatter.get(complex(s[k]), 0.0),
                              _swap_cost(rows, fit.synthesis, s, k, refit), float(fit.own[k])))
        if progress:
            progress(i + 1, len(groups))
    if not found:
        raise DataFormatError("no stable mode found in the band; widen the band or raise --max-order")
    modes = _merge(found, opt)
    modes, edge = _off_edges(modes, k_lines[0], k_lines[-1], exp_tau_s)
    rejected += edge
    if not modes:
        raise DataFormatError("no stable mode found inside the band; widen the band or raise --max-order")
    s = np.array([m[0] for m in modes])
    shapes = np.full((s.size, H.shape[0], n_p), np.nan + 0j)
    shapes[:, live] = np.array([m[2] for m in modes]).reshape(s.size, n_live, n_p)
    err = np.full((H.shape[0], n_p), np.nan)
    Hflat, synth = Hflat / to_acc, synth / to_acc  # back to the given form
    err[live] = (np.linalg.norm(Hflat - synth, axis=1) /
                 np.maximum(np.linalg.norm(Hflat, axis=1), np.finfo(float).tiny)).reshape(n_live, n_p)
    syn = np.full((H.shape[0], n_p, lines.sum()), np.nan + 0j)
    syn[live] = synth.reshape(n_live, n_p, -1)
    f_true, z_true = poles_to_modal(correct_poles(s, exp_tau_s))
    return ModalResult(freq_hz=f_true, damping_ratio=z_true, poles=s, shapes=shapes,
                       mpc=np.array([mpc(m[2]) for m in modes]),
                       significance=np.array([m[3] for m in modes]),
                       group=np.array([m[1] for m in modes]), fit_error=err, synthesis=syn,
                       band_freq_hz=k_lines, diagrams=diagrams, rejected=rejected,
                       meta={"band_hz": [float(k_lines[0]), float(k_lines[-1])], "spatial": bool(spatial),
                             "max_order": int(group_max), "exp_tau_s": exp_tau_s,
                             "order_energy": [m[4] for m in modes],
                             "significance_in_group": [m[5] for m in modes]})


@dataclass(frozen=True)
class _GroupFit:
    residues: np.ndarray
    synthesis: np.ndarray
    significance: np.ndarray
    own: np.ndarray  # the share within the group


def _fit_group(freq, rows, back, H_phys, s, form, opt, g):
    """LSFD of one group's rows; drop insignificant poles and refit until settled.

    A mode is kept when it explains at least ``opt.min_significance`` of the response
    around its own frequency, in the physical FRFs (the reported significance) or in its
    own order group: the decomposition has taken the other orders out of the group, and a
    weak order beside a strong one of another order (the sidewall membrane's same-direction
    n = 20…30 amid the opposite branch's n = 5…12, 2–4 % of the physical response, each
    within 0.01 % of the truth) is a mode all the same. A pole fitted to the noise of a
    group that carries almost nothing fails the noise test (:func:`_above_noise`) and the
    peak test (:func:`_has_peak`) instead.
    """
    rejected = []

    def refit(poles):
        return lsfd(freq, rows, poles, form=form).synthesis

    for _ in range(s.size + 1):  # each pass drops one mode or returns
        if s.size == 0:
            return None, s, rejected, refit
        fit = lsfd(freq, rows, s, form=form)
        sig = np.array([significance(freq, H_phys, back @ fit.residues[:, [k]], s[[k]], form=form)[0]
                        for k in range(s.size)])
        own = significance(freq, rows, fit.residues, s, form=form)
        r, why = _weakest(freq, rows, fit.synthesis, s, np.maximum(sig, own), form, opt,
                          lambda keep: lsfd(freq, rows, s[keep], form=form).synthesis)
        if r is None:
            return _GroupFit(fit.residues, fit.synthesis, sig, own), s, rejected, refit
        f_r, z_r = poles_to_modal(s[r])
        rejected.append({"frequency_hz": float(f_r), "damping_ratio": float(z_r), "group": int(g), "reason": why})
        s = np.delete(s, r)
    return _GroupFit(fit.residues, fit.synthesis, sig, own), s, rejected, refit


#: probability that the noise alone in a mode's half-power band carries the energy the
#: mode explains there (per candidate mode)
NOISE_ALPHA = 1e-3


def _above_noise(freq, rows, synthesis, s, refit, form, alpha=NOISE_ALPHA):
    """Which modes the data support: the extra sum of squares of each mode against the noise.

    The noise variance σ² of each row is the median of |rows − synthesis|² over the band
    divided by ln 2 (the median of a complex Gaussian's power). For each mode r the fit is
    redone without it (``refit(keep)``: the same estimator, the other poles, fresh residues
    and residual terms); the increase of the residual, ΔE_r = Σ_rows (‖res_without‖² −
    ‖res_with‖²) / σ²_row, is for a pole fitted to noise at most χ²(2 n_rows + 2)/2 (a
    complex residue per row, and the pole's frequency and damping), searched over the
    band's K lines: the mode is supported when ΔE_r exceeds the 1 − alpha/K quantile
    (Bonferroni over the lines where a noise pole could sit). Returns (mask, ΔE_r / threshold).
    """
    from scipy.stats import chi2

    res = rows - synthesis
    var = np.median(res.real**2 + res.imag**2, axis=1) / np.log(2)
    var = np.maximum(var, np.finfo(float).tiny)
    base = float(np.sum(np.sum(res.real**2 + res.imag**2, axis=1) / var))
    thr = chi2.ppf(1 - alpha / freq.size, 2 * rows.shape[0] + 2) / 2
    ratio = np.zeros(len(s))
    for r in range(len(s)):
        keep = np.delete(np.arange(len(s)), r)
        e = refit(keep) if keep.size else _residual_terms_only(freq, rows, form)
        d = rows - e
        ratio[r] = (float(np.sum(np.sum(d.real**2 + d.imag**2, axis=1) / var)) - base) / thr
    return ratio >= 1, ratio


def _has_peak(freq, rows, s):
    """Whether the data show each mode: a peak or a phase turn in its half-power band.

    Within f_r ± max(ζ_r f_r, one line), some row (or the rows' summed power) has a local
    maximum (a line above both neighbours), or the phase of some row turns by ≥ π/4 (a
    mode alone turns it by π/2 between its half-power points; half of that allows for a
    neighbour or a residual that dilutes it). A pole on the smooth flank of another mode's
    peak, fitted to the model's misfit, has neither (the real beam's 55 and 480 Hz
    candidates); a heavily damped mode beside a stronger one shows at least the turn.
    """
    P = rows.real**2 + rows.imag**2
    P = np.vstack([P, P.sum(axis=0)])
    loc = np.zeros(freq.size, dtype=bool)
    loc[1:-1] = np.any((P[:, 1:-1] > P[:, :-2]) & (P[:, 1:-1] >= P[:, 2:]), axis=0)
    df = freq[1] - freq[0]
    fn, zeta = poles_to_modal(s)
    out = np.zeros(len(s), dtype=bool)
    for r in range(len(s)):
        w = np.abs(freq - fn[r]) <= max(zeta[r] * fn[r], df)
        if np.any(loc[w]):
            out[r] = True
            continue
        ph = np.unwrap(np.angle(rows[:, w]), axis=1)
        out[r] = bool(w.sum() > 1 and np.any(np.ptp(ph, axis=1) >= np.pi / 4))
    return out


def _residual_terms_only(freq, rows, form):
    """Least-squares fit of the lower and upper residual terms alone (no mode)."""
    from tiremodal_cli.modal.lsfd import FORM_POWER

    q = FORM_POWER[form]
    jw = 2j * np.pi * np.asarray(freq, dtype=float)[:, None]
    A = np.concatenate([jw ** (q - 2), jw**q], axis=1)
    Ar = np.concatenate([A.real, A.imag], axis=0)
    Y = np.concatenate([rows.real, rows.imag], axis=1).T
    x = np.linalg.lstsq(Ar, Y, rcond=None)[0]
    return (A @ x).T


def _fit_group_poly(freq, rows, n_h, n_c, back, H_phys, s, L, form, opt, g):
    """:func:`_fit_group` for a poly-reference group: residues ψ_c L_h (cos/sin as references)."""
    rejected = []
    Y = rows.reshape(n_h, n_c, -1).transpose(1, 0, 2)  # (channel, harmonic, K)
    holder = {}

    def refit(poles):  # the poles of the final fit (one swapped), each with its participation
        return (lsfd_participation(freq, Y, poles, holder["L"], form=form)[1]
                .transpose(1, 0, 2).reshape(n_h * n_c, -1))

    for _ in range(s.size + 1):  # each pass drops one mode or returns
        holder["L"] = L
        if s.size == 0:
            return None, s, rejected, refit
        res3, syn3 = lsfd_participation(freq, Y, s, L, form=form)
        residues = res3.transpose(1, 0, 2).reshape(n_h * n_c, -1)  # rows harmonic-major
        synthesis = syn3.transpose(1, 0, 2).reshape(n_h * n_c, -1)
        sig = np.array([significance(freq, H_phys, back @ residues[:, [k]], s[[k]], form=form)[0]
                        for k in range(s.size)])
        own = significance(freq, rows, residues, s, form=form)
        r, why = _weakest(freq, rows, synthesis, s, np.maximum(sig, own), form, opt,
                          lambda keep: lsfd_participation(freq, Y, s[keep], L[keep], form=form)[1]
                          .transpose(1, 0, 2).reshape(n_h * n_c, -1))
        if r is None:
            return _GroupFit(residues, synthesis, sig, own), s, rejected, refit
        f_r, z_r = poles_to_modal(s[r])
        rejected.append({"frequency_hz": float(f_r), "damping_ratio": float(z_r), "group": int(g), "reason": why})
        s, L = np.delete(s, r), np.delete(L, r, axis=0)
    holder["L"] = L
    return _GroupFit(residues, synthesis, sig, own), s, rejected, refit


def _weakest(freq, rows, synthesis, s, sig, form, opt, refit):
    """The one mode to drop next (one at a time: the others may gain once it is gone), and
    why; (None, "") when every mode is significant and above the noise."""
    weak = np.flatnonzero(sig < opt.min_significance)
    if weak.size:
        r = weak[np.argmin(sig[weak])]
        return r, f"insignificant: explains {100 * sig[r]:.1f} % of the response at its frequency"
    peak = _has_peak(freq, rows, s)
    if not peak.all():
        r = int(np.flatnonzero(~peak)[0])
        return r, "no peak and no phase turn in its half-power band in any FRF of its group"
    above, ratio = _above_noise(freq, rows, synthesis, s, refit, form)
    if not above.all():
        r = int(np.argmin(ratio))
        return r, (f"not supported by the data: explains {ratio[r]:.2f} × what the noise in its half-power band "
                   f"exceeds with probability {NOISE_ALPHA:g}")
    return None, ""


def _off_edges(modes, f_lo, f_hi, exp_tau_s):
    """Drop modes whose half-power band (f ± ζ f) reaches past an edge of the analysis band.

    Such a pole is fitted to one flank of a peak, usually a mode just outside the band
    leaking in (seen: the 308 Hz mode of a 40–300 Hz band returned at 299.5 Hz with a
    third of its damping); its frequency cannot be trusted. The lowest band line of a
    band starting at 0 Hz is no edge.
    """
    kept, rejected = [], []
    f, z = poles_to_modal(correct_poles(np.array([m[0] for m in modes]), exp_tau_s))
    for m, fi, zi in zip(modes, f, z):
        hw = zi * fi
        if fi + hw > f_hi or (f_lo > 0 and fi - hw < f_lo):
            rejected.append({"frequency_hz": float(fi), "damping_ratio": float(zi), "group": int(m[1]),
                             "reason": f"at the band edge: its half-power band {fi - hw:.1f}–{fi + hw:.1f} Hz "
                                       f"crosses the analysis band {f_lo:.1f}–{f_hi:.1f} Hz"})
        else:
            kept.append(m)
    return kept, rejected


#: probability that one pole seen in two order groups is taken for two modes: the swap test
#: of :func:`_merge` (χ² with 2 degrees of freedom, the pole's frequency and damping)
SAME_POLE_ALPHA = 1e-3
#: two poles of different groups closer than this share of the half-power bandwidth 2ζf
#: are one pole whatever the swap test says: the estimator's own bias, which a test at high
#: SNR reads as two poles. Measured on the validation matrix (docs/validation.md,
#: datasheet): |f̂ − f| / 2ζf of the modes found has a median of 0.0002 and is below 0.01
#: for 92–93 % of them; the rest are left to the swap test (the matrix's surplus — one
#: mode reported twice — is under 1 % of the modes adopted)
SAME_POLE_FLOOR_BW = 0.01


def _swap_cost(rows, synthesis, s, k, refit):
    """How much worse a group's data are fitted when its pole k is replaced by another.

    Returns a function of the new pole giving ΔE = Σ_rows (‖rows − Ĥ_swapped‖² −
    ‖rows − Ĥ‖²) / σ²_row, with σ² each row's residual mean square (its residual power
    over the band's lines: noise and the model's misfit alike, as in the extra-sum-of-
    squares F-test) and the other poles, their participation and the residual terms
    refitted. Under the hypothesis that the new pole is the group's own (one physical pole
    estimated twice), 2ΔE is at most χ²(2) (two real parameters fixed; the F(2, 2K − p)
    statistic with the band's thousand-odd lines is χ²(2)/2).
    """
    res = rows - synthesis
    var = np.maximum(np.mean(res.real**2 + res.imag**2, axis=1), np.finfo(float).tiny)
    base = float(np.sum(np.sum(res.real**2 + res.imag**2, axis=1) / var))

    def cost(s_new):
        poles = np.array(s, dtype=complex)
        poles[k] = s_new
        d = rows - refit(poles)
        return float(np.sum(np.sum(d.real**2 + d.imag**2, axis=1) / var)) - base

    return cost


def _merge(found, opt, alpha=SAME_POLE_ALPHA):
    """One mode per physical pole.

    Candidates: poles of other order groups within the dominant pole's half-power
    half-width (|Δf| ≤ ζ f) — one pole seen in several groups (leakage of a grid with
    missing points, or a mode whose shape holds several orders when the symmetry is
    broken). A candidate is the same pole when its group's data accept the dominant pole
    in place of its own, or the dominant group's data accept the candidate's pole
    (:func:`_swap_cost`: 2ΔE below the χ²(2) quantile 1 − ``alpha``; either way one pole
    serves both groups — with a broken symmetry the weaker copy is at times the better
    estimate),
    or lies within :data:`SAME_POLE_FLOOR_BW` of a bandwidth (the estimator's bias) —
    and adding its share does not turn a normal mode (MPC ≥ 0.5) into none;
    two modes of neighbouring orders (the opposite branch's n = 0 and 1 lie 0.15 % apart,
    a twentieth of a bandwidth) are rejected by their own data, however close. The merged
    mode's shape is the sum of the groups' shares, its pole the dominant group's.

    Returns list of (s, group, physical residues, significance, {group: energy share},
    significance in its own group).
    """
    from scipy.stats import chi2

    thr = chi2.ppf(1 - alpha, 2) / 2
    fn, zeta = poles_to_modal(np.array([f[0] for f in found]))
    energy = np.array([np.linalg.norm(f[2]) ** 2 for f in found])
    used = np.zeros(len(found), dtype=bool)
    out = []
    for i in np.argsort(-energy):
        if used[i]:
            continue
        # one pole found twice in its own group (two clusters): a twin, not a split pair
        for j in range(len(found)):
            if (j != i and not used[j] and found[j][1] == found[i][1] and abs(fn[j] - fn[i]) <= 5e-4 * fn[i]
                    and abs(zeta[j] - zeta[i]) <= 0.05 * zeta[i]):
                used[j] = True
        groups_seen = {found[i][1]: i}
        near = sorted((j for j in range(len(found)) if not used[j] and found[j][1] != found[i][1]
                       and abs(fn[j] - fn[i]) <= zeta[i] * fn[i]), key=lambda j: abs(fn[j] - fn[i]))
        for j in near:
            if found[j][1] not in groups_seen and (abs(fn[j] - fn[i]) <= SAME_POLE_FLOOR_BW * 2 * zeta[i] * fn[i]
                                                   or found[j][5](found[i][0]) <= thr
                                                   or found[i][5](found[j][0]) <= thr):
                # one normal mode seen twice: its shares add up in phase; a share that would
                # turn a normal mode (MPC ≥ 0.5, identify's gate) into none is not its own
                now = sum(found[q][2] for q in groups_seen.values())
                if not (mpc(now) >= 0.5 > mpc(now + found[j][2])):
                    groups_seen[found[j][1]] = j
        phys = sum(found[j][2] for j in groups_seen.values())
        tot = sum(energy[j] for j in groups_seen.values())
        for j in groups_seen.values():
            used[j] = True
        out.append((found[i][0], found[i][1], phys, found[i][3],
                    {int(found[j][1]): float(energy[j] / tot) for j in groups_seen.values()}, found[i][6]))
    out.sort(key=lambda m: abs(m[0]))
    return out


def confirmed(a: "ModalResult", b: "ModalResult") -> np.ndarray:
    """Which modes of ``a`` the estimate ``b`` confirms: a mode of b within a quarter of
    a's half-power half-width (|Δf| ≤ ζ f / 4 — two modes that close cannot be told
    apart, so the two estimators saw one mode) and with a damping ratio within 30 %."""
    out = np.zeros(a.freq_hz.size, dtype=bool)
    for i, (f, z) in enumerate(zip(a.freq_hz, a.damping_ratio)):
        near = np.abs(b.freq_hz - f) <= 0.25 * z * f
        out[i] = bool(np.any(near & (np.abs(b.damping_ratio - z) <= 0.3 * z)))
    return out


def modal_table_from_frf(r, opt: ModalOptions = ModalOptions(), *, progress=None, force_autospectrum=None):
    """The whole modal stage on an FRFResult: modes, and the tyre classification when the
    points go round a tread.

    Without ``opt.band_hz`` the band is :func:`default_band` of the FRFs' coherence (and
    ``force_autospectrum``, (n_freq,) on ``r.freq_hz``, when given); its reason is in
    ``table.meta["band_reason"]``.

    Returns
    -------
    table : ModalTable ; result : ModalResult
    """
    from dataclasses import replace

    from tiremodal_cli.modal.classify import classify
    from tiremodal_cli.io.modalfile import table_from_result

    if opt.band_hz is None:
        band, why = default_band(r.freq_hz, r.coherence, r.n_averages, force_autospectrum)
        opt = replace(opt, band_hz=band)
    else:
        why = "given"
    if opt.method == "both":
        table, res = modal_table_from_frf(r, replace(opt, method="lsce"), progress=progress)
        other, res2 = modal_table_from_frf(r, replace(opt, method="plscf"), progress=progress)
        table.meta["band_reason"] = why
        table.meta["method"] = "both"
        table.meta["confirmed"] = confirmed(res, res2).tolist()
        return table, res

    res = estimate_modes(r.freq_hz, r.H, point_angle=r.point_angle, channel_location=r.channel_location,
                         form=r.form, exp_tau_s=r.exp_tau_s, opt=opt, progress=progress)
    res.meta["band_reason"] = why
    res.meta["method"] = opt.method
    classes = None
    if res.meta["spatial"]:
        live = [i for i, n in enumerate(r.channel_name) if n not in r.dead_channels]
        locs = [r.channel_location[i] for i in live]
        if "tread" in locs:
            classes = classify(res.freq_hz, res.shapes[:, live], r.point_angle, locs, res.significance,
                               res.damping_ratio, res.meta.get("significance_in_group"))
            res.meta["crowds"] = [{"frequency_hz": float(res.freq_hz[i]), "n_spatial": c.n_spatial,
                                   "n_candidates": list(c.n_candidates),
                                   "reason": "orders aliasing onto one spatial order lie within one half-power "
                                             "bandwidth by the branch's dispersion: the order cannot be told"}
                                  for i, c in enumerate(classes) if c.crowd]
    table = table_from_result(res, classes, point_angle=r.point_angle, point_index=r.point_index,
                              channel_name=r.channel_name, channel_location=r.channel_location,
                              channel_angle=r.channel_angle, form=r.form)
    return table, res
