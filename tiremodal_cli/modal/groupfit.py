"""Residues of one order group's poles, and the poles its data do not support dropped.

For each order group (:mod:`tiremodal_cli.modal.spatial`) the stable poles get residues by
LSFD (:mod:`tiremodal_cli.modal.lsfd`; with the cos and sin components as two references,
by participation); then, one at a time, the weakest mode is dropped and the rest refitted:
a mode explaining too little of the response at its frequency, one with no peak and no
phase turn in its half-power band, one whose extra sum of squares the noise explains.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING

import numpy as np
import scipy.special

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.band import window_noise_gain
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import lsfd, lsfd_participation, significance

if TYPE_CHECKING:  # for the annotation only: modes imports this module
    from tiremodal_cli.modal.modes import ModalOptions

__all__ = ["GroupData", "GroupFit", "NOISE_ALPHA", "PEAK_OVER_NOISE", "PIN_SIGMAS", "fit_clusters", "fit_group",
           "fit_group_poly", "own_peaks", "pin_limit"]


@dataclass(frozen=True)
class GroupData:
    """One order group's data and what the fit needs to judge its modes.

    freq : (K,) ndarray, Hz            the band's lines
    rows : (n_h · n_c, K) complex      the group's FRFs (harmonic-major), accelerance
    back : (n_frf, n_h · n_c) ndarray  the group's rows → physical FRFs
    H_phys : (n_frf, K) complex        the physical FRFs of the band
    form : str ; opt : ModalOptions ; group : int (−1: no spatial split)
    n_h, n_c : int                     harmonics (references) and live channels
    noise : (K,) ndarray or None       the rows' noise variance per line, relative
                                       (:func:`~tiremodal_cli.modal.band.noise_shape`; None: white)
    window : (τ s, line Hz) or None    the FRFs' exponential window
                                       (:func:`~tiremodal_cli.modal.band.window_noise_gain`)
    """

    freq: np.ndarray
    rows: np.ndarray
    back: np.ndarray
    H_phys: np.ndarray
    form: str
    opt: ModalOptions
    group: int
    n_h: int
    n_c: int
    noise: np.ndarray | None = None
    window: tuple | None = None


@dataclass(frozen=True)
class GroupFit:
    """Residues (rows, modes), synthesis (rows, K), and each mode's significance in the
    physical FRFs and its share within the group (``own``)."""

    residues: np.ndarray
    synthesis: np.ndarray
    significance: np.ndarray
    own: np.ndarray  # the share within the group


def _significances(data: GroupData, residues, s):
    """Each mode's significance in the physical FRFs, and within its group."""
    sig = np.array([significance(data.freq, data.H_phys, data.back @ residues[:, [k]], s[[k]], form=data.form)[0]
                    for k in range(s.size)])
    return sig, significance(data.freq, data.rows, residues, s, form=data.form)


def _rejection(pole, group: int, why: str) -> dict:
    f_r, z_r = poles_to_modal(pole)
    return {"frequency_hz": float(f_r), "damping_ratio": float(z_r), "group": int(group), "reason": why}


def _lsfd_synthesis(data: GroupData, poles, weight=None):
    return lsfd(data.freq, data.rows, poles, form=data.form, weight=weight).synthesis


def fit_group(data: GroupData, s, std_hz=None) -> tuple:
    """LSFD of one group's rows; drop insignificant poles and refit until settled.

    Returns (fit, poles kept, rejections, refit): ``fit`` a :class:`GroupFit` (None when no
    pole is left) and ``refit(poles)`` the group's synthesis with other poles (fresh
    residues and residual terms), for :func:`tiremodal_cli.modal.merge.swap_cost`.

    A mode is kept when it explains at least ``data.opt.min_significance`` of the response
    around its own frequency, in the physical FRFs (the reported significance) or in its
    own order group: the decomposition has taken the other orders out of the group, and a
    weak order beside a strong one of another order (the sidewall membrane's same-direction
    n = 20…30 amid the opposite branch's n = 5…12, 2–4 % of the physical response, each
    within 0.01 % of the truth) is a mode all the same. A pole fitted to the noise of a
    group that carries almost nothing fails the noise test (:func:`_above_noise`) and the
    peak test (:func:`_has_peak`) instead.
    """
    std_hz = np.full(len(s), np.inf) if std_hz is None else np.asarray(std_hz, dtype=float)
    rejected = []
    refit = partial(_lsfd_synthesis, data)
    for _ in range(s.size + 1):  # each pass drops one mode or returns
        if s.size == 0:
            return None, s, rejected, refit
        fit = lsfd(data.freq, data.rows, s, form=data.form)
        sig, own = _significances(data, fit.residues, s)
        alone = own_peaks(data, s, fit.residues, fit.synthesis, np.maximum(sig, own), std_hz)
        r, why = _weakest(data, fit.synthesis, s, np.maximum(sig, own),
                          lambda keep, weight=None: _lsfd_synthesis(data, s[keep], weight), alone)
        if r is None:
            return GroupFit(fit.residues, fit.synthesis, sig, own), s, rejected, refit
        rejected.append(_rejection(s[r], data.group, why))
        s, std_hz = np.delete(s, r), np.delete(std_hz, r)
    return GroupFit(fit.residues, fit.synthesis, sig, own), s, rejected, refit


def fit_clusters(data: GroupData, clusters) -> tuple:
    """The group's fit of a stabilization diagram's selected clusters: (their poles (rad/s),
    their participations, and :func:`fit_group_poly`'s result when every cluster has one
    (a poly-reference sweep), else :func:`fit_group`'s)."""
    s = np.array([c.representative.s for c in clusters], dtype=complex)
    parts = [c.representative.participation for c in clusters]
    std = np.array([c.frequency_std_hz for c in clusters])
    if s.size and all(pt is not None for pt in parts):
        nested = np.array([c.std_hz is not None for c in clusters])
        return s, parts, fit_group_poly(data, s, np.array(parts), std, nested)
    return s, parts, fit_group(data, s, std)


def _harmonic_major(x3, data: GroupData):
    """(channel, harmonic, …) → rows harmonic-major (n_h · n_c, …)."""
    return x3.transpose(1, 0, 2).reshape(data.n_h * data.n_c, -1)


def _poly_synthesis(data: GroupData, Y, L, poles, weight=None):
    """The group's synthesis with ``poles``, each with its participation ``L`` (``weight``:
    each line's, :func:`~tiremodal_cli.modal.lsfd.lsfd`'s)."""
    return _harmonic_major(lsfd_participation(data.freq, Y, poles, L, form=data.form, weight=weight)[1], data)


def fit_group_poly(data: GroupData, s, L, std_hz=None, nested=None) -> tuple:
    """:func:`fit_group` for a poly-reference group: residues ψ_c L_h (cos/sin as references).

    ``L`` : (n_modes, n_h) the poles' participation factors. ``nested`` (bool per pole): the
    poles :mod:`~tiremodal_cli.modal.beside` fitted beside a stronger one and supported by
    nested fits with their neighbours free — judged as own peaks however near the stronger
    mode (:func:`own_peaks`). Returns as :func:`fit_group`.
    """
    std_hz = np.full(len(s), np.inf) if std_hz is None else np.asarray(std_hz, dtype=float)
    nested = np.zeros(len(s), dtype=bool) if nested is None else np.asarray(nested, dtype=bool)
    rejected = []
    Y = data.rows.reshape(data.n_h, data.n_c, -1).transpose(1, 0, 2)  # (channel, harmonic, K)
    for _ in range(s.size + 1):  # each pass drops one mode or returns
        if s.size == 0:
            return None, s, rejected, partial(_poly_synthesis, data, Y, L)
        res3, syn3 = lsfd_participation(data.freq, Y, s, L, form=data.form)
        residues, synthesis = _harmonic_major(res3, data), _harmonic_major(syn3, data)
        sig, own = _significances(data, residues, s)
        alone = own_peaks(data, s, residues, synthesis, np.maximum(sig, own), std_hz, nested)
        r, why = _weakest(data, synthesis, s, np.maximum(sig, own),
                          lambda keep, weight=None: _poly_synthesis(data, Y, L[keep], s[keep], weight), alone)
        if r is None:
            return GroupFit(residues, synthesis, sig, own), s, rejected, partial(_poly_synthesis, data, Y, L)
        rejected.append(_rejection(s[r], data.group, why))
        s, L, std_hz, nested = np.delete(s, r), np.delete(L, r, axis=0), np.delete(std_hz, r), np.delete(nested, r)
    return GroupFit(residues, synthesis, sig, own), s, rejected, partial(_poly_synthesis, data, Y, L)


def _weakest(data: GroupData, synthesis, s, sig, refit, own_peak):
    """The one mode to drop next (one at a time: the others may gain once it is gone), and
    why; (None, "") when every mode is significant and above the noise. ``own_peak`` (bool
    per mode, :func:`own_peaks`): the modes the share test does not judge."""
    freq, rows, form, opt = data.freq, data.rows, data.form, data.opt
    weak = np.flatnonzero((sig < opt.min_significance) & ~own_peak)
    if weak.size:
        r = weak[np.argmin(sig[weak])]
        return r, f"insignificant: explains {100 * sig[r]:.1f} % of the response at its frequency"
    peak = _has_peak(freq, rows, s)
    if not peak.all():
        r = int(np.flatnonzero(~peak)[0])
        return r, "no peak and no phase turn in its half-power band in any FRF of its group"
    above, ratio = _above_noise(freq, rows, synthesis, s, refit, form, noise=data.noise, window=data.window)
    if not above.all():
        r = int(np.argmin(ratio))
        return r, (f"not supported by the data: explains {ratio[r]:.2f} × what the noise in its half-power band "
                   f"exceeds with probability {NOISE_ALPHA:g}")
    return None, ""


#: a weak mode's peak in its group, at least this many times the residual RMS per line of
#: the row that shows it best: the visibility rule (a peak three times the noise floor; one
#: complex Gaussian row reaches it on a given line with probability e^−9 = 1.2e-4, any of
#: R rows at most R × that: 7e-4 for a tyre's two harmonics × three channels)
PEAK_OVER_NOISE = 3.0


def own_peaks(data: GroupData, s, residues, synthesis, strength, std_hz, nested=None) -> np.ndarray:
    """Which modes stand on a peak of their own, judged against the noise, not as a share.

    A mode r is judged so when (a) it lies outside the half-power band of every mode k of
    larger ``strength`` (share) in its group, and more than a line from it, |f_k − f_r| >
    max(ζ_k f_k, one line) (the merge's window, and the FRFs' resolution: inside it the
    stronger mode's own peak is there, and the data do not tell a weak pole from it — the
    same-direction crowd under the sidewall resonance; the real beam's 687.27 Hz pole,
    0.11 Hz from its 687.17 Hz mode with 1 Hz lines), (b) its peak at resonance is at
    least :data:`PEAK_OVER_NOISE` × the residual RMS per line in the row that shows it
    best (:func:`row_visibility`; until session 15 the rows' norm, ‖r‖ |s|² / |Re s|
    against the norm's RMS, which let the loud rows' noise hide a mode of a quiet one),
    and (c) its pole is pinned by the data: the scatter of its cluster over the model orders
    (``std_hz``, Hz) is at most one line spacing (the FRFs' resolution) or, for a broad
    mode, :data:`PIN_SIGMAS` × its frequency's standard error in the rows' residual (norm)
    (:func:`pin_limit`, since session 10) — a bound for a mode alone in its band, so
    applied only when its half-power band lies inside the analysis band and overlaps the
    half-power band of no stronger mode of its group, |f_k − f_r| ≥ ζ_k f_k + ζ_r f_r. Its share of the
    response is then no measure of it: in accelerance a weak mode far above strong ones
    sits on their mass lines (the ring's sidewall modes n = 46…64, 1–4 % of the response,
    each within 0.1 % of the truth), and a weak mode on a stronger one's flank shares its
    response there (the paper's sidewall same-direction n = 26 and 27, 4 % of the
    response, 8–10 Hz from a 26 × stronger opposite mode of their group, outside its
    half-power band, within 0.15 %). The modes judged so must still show a peak or phase
    turn and pass the noise test (:func:`_weakest`). A ``nested`` pole (:mod:`~tiremodal_cli.modal.beside`)
    is not held to (a): nested fits with the stronger neighbour free have told it apart.
    """
    fn, zeta = poles_to_modal(s)
    res = data.rows - synthesis
    noise = np.sqrt(np.mean(np.sum(res.real**2 + res.imag**2, axis=0)))
    peak = np.linalg.norm(residues, axis=0) * np.abs(s) ** 2 / np.abs(s.real)
    df = data.freq[1] - data.freq[0]
    std_hz, hw = np.asarray(std_hz, dtype=float), zeta * fn
    inside = (fn - hw >= data.freq[0]) & (fn + hw <= data.freq[-1])  # the bound needs both flanks
    visible = row_visibility(residues, s, res) >= PEAK_OVER_NOISE
    out = visible & (std_hz <= np.where(inside, pin_limit(hw, df, peak / noise), df))
    for r in np.flatnonzero(out & ~(np.zeros(s.size, bool) if nested is None else nested)):
        stronger = strength > strength[r]
        out[r] = not np.any(stronger & (np.abs(fn - fn[r]) <= np.maximum(hw, df)))
        if out[r] and std_hz[r] > df:  # the bound holds for a mode alone in its half-power band
            out[r] = not np.any(stronger & (np.abs(fn - fn[r]) < hw + hw[r]))
    return out


def row_visibility(residues, s, res) -> np.ndarray:
    """Each mode's peak over the noise floor in the row that shows it best, (n_modes,).

    residues : (n_rows, n_modes) complex ; s : (n_modes,) poles, rad/s ;
    res : (n_rows, K) complex, the rows less the fit (noise and misfit alike).

    Row i's peak at resonance is |r_i| |s|² / |Re s| and its floor the RMS of its residual
    over the band. Judged row by row, as a test engineer reads FRFs (and as the ruler's
    "visible" reads the best channel and point): the rows' noise differs by the channels'
    levels (a sensor's noise scales with its own response), and a norm over all rows puts
    the loud rows' noise under a mode that lives in a quiet one (the paper's sidewall
    same-direction n = 56 … 60: 1.8–2.9 × the norm's floor, 11–29 × its best row's). The
    floor is the band's, not the noise's level at the mode (:func:`~tiremodal_cli.modal.band.noise_shape`):
    a weak mode's floor is its group's misfit, which the force's shape does not describe
    (with the floor so scaled, session 48: the ring's sidewall-coupling n = 47 same at
    541.66 Hz, within 0.06 %, fell under the rule; session 18 lost 13 paper modes so).
    """
    floor = np.sqrt(np.mean(res.real**2 + res.imag**2, axis=1))
    peak = np.abs(residues) * (np.abs(s) ** 2 / np.abs(s.real))[None, :]
    return np.max(peak / np.maximum(floor, np.finfo(float).tiny)[:, None], axis=0)


#: a pinned pole's scatter over the model orders, at most this many times the standard
#: error its group's residual allows (:func:`pin_limit`)
PIN_SIGMAS = 3.0


def pin_limit(half_width_hz, line_hz, peak_over_noise):
    """Largest scatter over the model orders of a pole the data pin, Hz.

    The FRFs' resolution, one line, or :data:`PIN_SIGMAS` × the Cramér–Rao standard error
    of a mode's frequency in its residual, whichever is larger. A mode of peak P and
    half-power half-width γ = ζ f, r(f) = P γ e^{iφ} / (i (f − f_r) + γ), on lines of
    spacing Δf with a complex residual of RMS N per line (treated as white), with its
    complex amplitude and damping unknown too, gives σ_f = (N / P) √(2 γ Δf / π) (the
    Fisher information of f_r, π P² / (N² γ Δf) with the amplitude known, is halved by
    the phase's coupling to f_r; band ≫ γ). A broad mode's estimate moves with the misfit
    by a fraction of its half-width, not of a line: the ring's sidewall same-direction
    n = 61 … 63, γ ≈ 15 Hz = 30 lines, scatter 1.2–2.1 lines, each within 0.1 % of the
    truth. For a narrow mode (γ ≈ Δf) at the visibility limit P = 3 N the bound is under
    a line, and the line rules.

    half_width_hz, peak_over_noise : (n,) ndarray (Hz; ratio) ; line_hz : float. Returns (n,) Hz.
    """
    se = np.sqrt(2 * np.asarray(half_width_hz, float) * line_hz / np.pi) / np.maximum(peak_over_noise,
                                                                                      np.finfo(float).tiny)
    return np.maximum(line_hz, PIN_SIGMAS * se)


#: probability that the noise alone in a mode's half-power band carries the energy the
#: mode explains there (per candidate mode)
NOISE_ALPHA = 1e-3


def _above_noise(freq, rows, synthesis, s, refit, form, alpha=NOISE_ALPHA, noise=None, window=None):
    """Which modes the data support: the extra sum of squares of each mode against the noise.

    The noise variance σ² of each row is the median of |rows − synthesis|² over the band
    divided by ln 2 (the median of a complex Gaussian's power). For each mode r the fit is
    redone without it (``refit(keep)``: the same estimator, the other poles, fresh residues
    and residual terms); the increase of the residual, ΔE_r = Σ_rows (‖res_without‖² −
    ‖res_with‖²) / σ²_row, is for a pole fitted to noise at most χ²(2 n_rows + 2)/2 (a
    complex residue per row, and the pole's frequency and damping), searched over the
    band's K lines: the mode is supported when ΔE_r exceeds the 1 − alpha/K quantile
    (Bonferroni over the lines where a noise pole could sit). With ``noise`` ((K,), the
    rows' noise variance per line, relative: :func:`~tiremodal_cli.modal.band.noise_shape`)
    every line's power is taken over its own variance, σ²_row × noise: a pole where the
    hammer's spectrum falls is judged against the noise there, not the band's median; the
    fits with and without each mode are then weighted least squares (``refit(keep,
    weight)``), as the statistic's χ² needs (an unweighted fit lets the loud lines move the
    residual terms, and a pole there takes the blame back: 2 of 40 noise poles passed).
    ``window`` ((τ s, line Hz) of the FRFs' exponential window, or None): each pole's
    threshold times κ_r (:func:`~tiremodal_cli.modal.band.window_noise_gain`): the window
    makes the noise fall over each record, and a pole — its impulse response early in the
    record — takes up κ_r times what independent lines would give it. Returns (mask,
    ΔE_r / threshold_r).
    """
    w = 1.0 if noise is None else 1.0 / np.asarray(noise, dtype=float)
    lw = None if noise is None else np.sqrt(w)
    if lw is not None:
        synthesis = refit(np.arange(len(s)), weight=lw)
    res = rows - synthesis
    var = np.median((res.real**2 + res.imag**2) * w, axis=1) / np.log(2)
    var = np.maximum(var, np.finfo(float).tiny)
    base = float(np.sum(np.sum((res.real**2 + res.imag**2) * w, axis=1) / var))
    # χ² upper quantile (scipy.stats costs 0.4 s to import)
    thr = scipy.special.chdtri(2 * rows.shape[0] + 2, alpha / freq.size) / 2 * \
        (window_noise_gain(-np.asarray(s).real, *window) if window else np.ones(len(s)))
    ratio = np.zeros(len(s))
    for r in range(len(s)):
        keep = np.delete(np.arange(len(s)), r)
        e = (refit(keep) if lw is None else refit(keep, weight=lw)) if keep.size else \
            _residual_terms_only(freq, rows, form, lw)
        d = rows - e
        ratio[r] = (float(np.sum(np.sum((d.real**2 + d.imag**2) * w, axis=1) / var)) - base) / thr[r]
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


def _residual_terms_only(freq, rows, form, weight=None):
    """Least-squares fit of the lower and upper residual terms alone (no mode; ``weight``:
    each line's, (K,))."""
    q = FORM_POWER[form]
    jw = 2j * np.pi * np.asarray(freq, dtype=float)[:, None]
    A = np.concatenate([jw ** (q - 2), jw**q], axis=1)
    Ar = np.concatenate([A.real, A.imag], axis=0)
    Y = np.concatenate([rows.real, rows.imag], axis=1).T
    if weight is not None:
        w2 = np.tile(np.asarray(weight, dtype=float), 2)[:, None]
        Ar, Y = Ar * w2, Y * w2
    x = np.linalg.lstsq(Ar, Y, rcond=None)[0]
    return (A @ x).T
