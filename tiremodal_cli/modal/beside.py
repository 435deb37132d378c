"""A weak mode beside a strong one of its order group: a pole the residual asks for, added by
variable projection and kept only where the data support it.

**Why.** LSCE (or pLSCF) spends a group's poles where its impulse responses carry their
energy. Where a weak mode lies within a bandwidth of a strong one of its group — on a
34-point test, the sidewall's same-direction aliases (ζ ≈ 3.7 %, 1 % of the response)
half a bandwidth from the tread's opposite-direction modes of their spatial order — the
sweep gives one pole for the two (biased by up to half a percent) or the strong one alone;
the group's fit then leaves the weak mode in its residual, a hump one bandwidth wide. The
rescue (:mod:`~tiremodal_cli.modal.rescue`) does not see it: its local noise level (a
101-line running median) rises with a hump that broad, and it asks for a peak outside every
kept pole's half-power band.

**The rule** (:func:`beside_poles`). In the group's residual, each row over its noise
variance (the median of its residual power over ln 2, as the noise test), the power summed
over the R rows and over a window of w = 2 h + 1 lines (h: the median half-power half-width
of the group's kept poles, in lines — a mode's own width, the matched window) is
χ²(2 R w)/2 for noise alone; a window over its 1 − α/K quantile (α =
:data:`~tiremodal_cli.modal.groupfit.NOISE_ALPHA`, Bonferroni over the K lines) proposes a
pole at its centre. The proposal is judged by nested fits in the FRFs of its window (the
lines within :data:`~tiremodal_cli.modal.refine.WINDOW_HALF_WIDTHS` half-widths): the group's
poles whose half-power bands reach the proposal refined by variable projection without a
new pole (E₀), and with one — its frequency and damping free, a free residue per row (E₁).
The new pole is kept when E₀ − E₁ exceeds the 1 − α/K quantile of χ²(2 R + 2)/2 (the noise
test's own bound for one more pole: a complex residue per row, its frequency and damping;
times the pole's gain κ_r under the FRFs' exponential window, as there),
when it ends inside its box (its frequency within :data:`SEARCH_HALF_WIDTHS` half-widths of
the proposal, its damping within a factor :data:`~tiremodal_cli.modal.refine.MAX_DAMPING_FACTOR`
of the group's), more than a line and :data:`~tiremodal_cli.modal.groupfit.PIN_SIGMAS`
standard errors of its frequency from every neighbour (else the data do not tell the two
frequencies apart), and when its shape differs from each neighbour's (:data:`MAX_MAC`). Refining the neighbours in both fits
is what makes the test about a *second* mode: a strong pole's bias leaves a dispersive
residual that moving the pole explains, and then no new pole is needed. One pole is added
at a time, the strongest window first, and the residual re-judged, at most
:data:`MAX_NEW` per group. Its participation is the rank-one part of its residues (cos/sin
references), and its frequency's standard error, from the fit's Jacobian with its
neighbours free (its scatter over model orders, had a sweep found it), goes to the
own-peak rule's pin test. The pole then joins the group's stable poles and is judged with
them by every rule of :mod:`~tiremodal_cli.modal.groupfit` — share or own peak, peak or
phase turn, noise.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.special

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.band import window_noise_gain
from tiremodal_cli.modal.groupfit import NOISE_ALPHA, PIN_SIGMAS
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import lsfd_participation
from tiremodal_cli.modal.refine import MAX_DAMPING_FACTOR, WINDOW_HALF_WIDTHS
from tiremodal_cli.modal.varpro import forward_jacobian, participation_basis, stack_references
from tiremodal_cli.modal.stabilization import Cluster, StablePole

__all__ = ["MAX_MAC", "MAX_NEW", "SEARCH_HALF_WIDTHS", "beside_poles", "proposals", "with_beside"]

#: at most this many poles added to one group (a bound on the work; each is judged alone)
MAX_NEW = 4

#: a new pole is another mode only when its shape (residues over channels and references)
#: is nearer orthogonal than parallel to each neighbour's: MAC below 1/2 (an angle over
#: 45°). Two poles of one shape at one frequency are one mode's line shape to the data —
#: measured on the paper's sidewall membrane case: the neighbours of weak aliases beside the
#: opposite branch's modes have MAC 0.009–0.10; the splits of one mode into two, 0.95–0.995
MAX_MAC = 0.5

#: the nested fits' relative tolerances on the weighted residual and on θ: the residual is
#: ≳ 10³ (one per line and row) and the test's bound ≈ 20, so 1e-5 of it is far below
#: what the test can see (scipy's default 1e-8 doubled the cost for nothing)
FTOL = 1e-5

#: a new pole's frequency may move this many half-widths from its proposal
SEARCH_HALF_WIDTHS = 1.0


def _local_maxima(T, height: float, distance: int) -> np.ndarray:
    """Indices of the local maxima of ``T`` over ``height``, none within ``distance`` lines of
    a higher one kept (as ``scipy.signal.find_peaks(T, height, distance)``; written here
    because importing scipy.signal imports scipy.stats, which ``run`` must not load: 0.4 s)."""
    i = np.flatnonzero((T[1:-1] > T[:-2]) & (T[1:-1] >= T[2:]) & (T[1:-1] > height)) + 1
    keep = []
    for k in i[np.argsort(-T[i], kind="stable")]:
        if all(abs(k - j) >= distance for j in keep):
            keep.append(k)
    return np.sort(np.array(keep, dtype=int))


def _mac(R, psi, L) -> np.ndarray:
    """MAC of residues ``R`` (n_c, n_ref) with each neighbour's ψ_c L_h ((k, n_c), (k, n_ref))."""
    v = R.ravel()
    out = []
    for p, l in zip(psi, L):
        u = np.outer(p, l).ravel()
        den = np.vdot(u, u).real * np.vdot(v, v).real
        out.append(abs(np.vdot(u, v)) ** 2 / den if den > 0 else 1.0)
    return np.array(out)


def _weights(rows, synthesis, n_ref):
    """Each channel's 1/σ (the median of its rows' residual power over ln 2, averaged over
    the references, which share the channel's basis)."""
    res = rows - synthesis
    var = np.median(res.real**2 + res.imag**2, axis=1) / np.log(2)
    return 1 / np.sqrt(np.maximum(var.reshape(n_ref, -1).mean(axis=0), np.finfo(float).tiny))


def proposals(freq, rows, synthesis, weight, half_lines: int, alpha: float = NOISE_ALPHA) -> np.ndarray:
    """Indices of the lines where the matched-window residual power exceeds its noise bound
    (module doc), strongest first.

    freq : (K,) Hz ; rows, synthesis : (R, K) complex, reference-major ; weight : (n_c,)
    1/σ per channel ; half_lines : h, the window's half width in lines.
    """
    R, K = rows.shape
    res = (rows - synthesis) * np.tile(weight, R // weight.size)[:, None]
    E = np.sum(res.real**2 + res.imag**2, axis=0)
    w = 2 * half_lines + 1
    if K < w:
        return np.zeros(0, dtype=int)
    T = np.convolve(E, np.ones(w), mode="same")
    thr = scipy.special.chdtri(2 * R * w, alpha / K) / 2
    peaks = _local_maxima(T, thr, max(half_lines, 1))
    peaks = peaks[(peaks >= half_lines) & (peaks < K - half_lines)]  # a whole window inside the band
    return peaks[np.argsort(-T[peaks])]


def _fitter(jw, Y, s, L, sets, q):
    """The weighted residual of the poles ``s`` with the index ``sets`` moved, each set as one
    pole (θ: each set's Δω / half-width, then each set's ln σ/σ₀), and the linear
    coefficients: fun(θ) → (residual (flattened), coefficients (n_cols, n_c), the poles)."""
    m = len(sets)
    first = np.array([st[0] for st in sets], dtype=int)
    hw, base = -s[first].real, s[first]

    def poles(theta):
        out = s.copy()
        moved = -hw * np.exp(theta[m:]) + 1j * (base.imag + hw * theta[:m])
        for k, st in enumerate(sets):
            out[st] = moved[k]
        return out

    def fun(theta):
        p = poles(theta)
        A = participation_basis(jw, p, L, q)
        Ar = np.concatenate([A.real, A.imag], axis=0)
        scale = np.linalg.norm(Ar, axis=0)
        scale[scale == 0] = 1
        x = scipy.linalg.lstsq(Ar / scale, Y, lapack_driver="gelsy", check_finite=False)[0]
        return (Y - (Ar / scale) @ x).ravel(), x / scale[:, None], p

    return fun


def _minimum(fun, lim):
    """(weighted residual power, θ, Jacobian) at the least-squares minimum in the box ±lim."""
    if lim.size == 0:
        r = fun(np.zeros(0))[0]
        return float(r @ r), np.zeros(0), np.zeros((r.size, 0))
    f = lambda th: fun(th)[0]  # noqa: E731
    sol = scipy.optimize.least_squares(f, np.zeros(lim.size), jac=lambda th: forward_jacobian(f, th),
                                       bounds=(-lim, lim), x_scale=0.1, max_nfev=20 * lim.size,
                                       ftol=FTOL, xtol=FTOL)
    r = f(sol.x)
    return float(r @ r), sol.x, forward_jacobian(f, sol.x)


def _try(freq, rows, weight, s, L, f_c, zeta_ref, q, thr, window=None):
    """The nested test of a proposal at ``f_c`` Hz (module doc): (new pole, its participation
    (n_ref,), its frequency's standard error, Hz) or None. The fit with the new pole and the
    checks on it come first, the fit without it (E₀) only for a pole that passes them: the
    same decision, at less cost."""
    n_ref = L.shape[1]
    fn, zeta = poles_to_modal(s)
    hw, hw_c = zeta * fn, zeta_ref * f_c
    near = np.flatnonzero(np.abs(fn - f_c) < hw + hw_c)
    if near.size == 0:  # a peak away from every kept pole is the rescue's (modal.rescue)
        return None
    at, width = np.concatenate([[f_c], fn[near]]), np.concatenate([[hw_c], hw[near]])
    w = (freq >= np.min(at - WINDOW_HALF_WIDTHS * width)) & (freq <= np.max(at + WINDOW_HALF_WIDTHS * width))
    if 2 * n_ref * w.sum() <= 2 * (s.size + 2 * n_ref) + 2 * (near.size + 1):
        return None
    jw = 2j * np.pi * freq[w]
    Yc = stack_references(rows[:, w], n_ref) * weight[None, :]
    Y = np.concatenate([Yc.real, Yc.imag], axis=0)
    sets0 = [np.array([i]) for i in near]
    s_c = complex(-2 * np.pi * hw_c, 2 * np.pi * f_c * np.sqrt(1 - zeta_ref**2))
    s1, L1 = np.concatenate([s, np.full(n_ref, s_c)]), np.concatenate([L, np.eye(n_ref)])
    new = np.arange(s.size, s.size + n_ref)  # one pole, a free residue per reference
    lim = np.concatenate([np.full(near.size, 1.0), [SEARCH_HALF_WIDTHS],
                          np.full(near.size + 1, np.log(MAX_DAMPING_FACTOR))])
    fun = _fitter(jw, Y, s1, L1, sets0 + [new], q)
    E1, th, J = _minimum(fun, lim)
    got = None if np.any(np.abs(th) >= 0.98 * lim) else _checked(fun(th), J, near, new, s.size, L, weight,
                                                                freq[1] - freq[0], hw_c)
    if got is None:
        return None
    E0 = _minimum(_fitter(jw, Y, s, L, sets0, q), np.delete(lim, [near.size, lim.size - 1]))[0]
    gain = float(window_noise_gain(-got[0].real, *window)[0]) if window else 1.0
    return got if E0 - E1 >= thr * gain else None


def _checked(fitted, J, near, new, m0, L, weight, line_hz, hw_c):
    """The new pole of a fit with it, when it is another mode than its neighbours (module
    doc): more than a line and PIN_SIGMAS standard errors from each, of another shape.
    Returns (pole, participation, standard error of its frequency, Hz) or None."""
    _, x, p = fitted
    s_new = p[new[0]]
    f_new = poles_to_modal(np.array([s_new]))[0][0]
    if np.any(np.abs(poles_to_modal(p[:m0])[0] - f_new) <= line_hz):
        return None
    n_all = p.size  # residue of channel c, reference h: the Re and Im columns of copy h
    R = (x[new] + 1j * x[n_all + new]) / weight[None, :]  # (n_ref, n_c)
    Rn = (x[near] + 1j * x[n_all + near]) / weight[None, :]  # the near poles' ψ_c, (near, n_c)
    if np.any(_mac(R.T, Rn, L[near]) >= MAX_MAC):
        return None  # the same shape as a neighbour: one mode's line shape, not two modes
    k = near.size  # θ of the new pole's frequency
    cov = np.linalg.pinv(J.T @ J) / 2  # each real component of the weighted residual has variance 1/2
    sigma_hz = float(np.sqrt(max(cov[k, k], 0.0)) * hw_c)
    if np.any(np.abs(poles_to_modal(p[near])[0] - f_new) <= PIN_SIGMAS * sigma_hz):
        return None  # the data do not tell its frequency from its neighbour's
    return s_new, np.linalg.svd(R.T)[2][0], sigma_hz


def beside_poles(freq, rows, synthesis, s, L, *, form: str = "accelerance", alpha: float = NOISE_ALPHA,
                 window=None):
    """Poles the group's residual asks for beside its kept ones (module doc).

    Parameters
    ----------
    freq : (K,) ndarray, Hz            the band's lines (uniform)
    rows : (n_ref · n_c, K) complex    the group's FRFs, reference-major
    synthesis : (n_ref · n_c, K) complex   the group's fit with the poles ``s``
    s : (m,) complex, rad/s ; L : (m, n_ref) complex   the kept poles and participations
    window : (τ s, line Hz) or None    the FRFs' exponential window: the nested test's bound
                                       times the new pole's gain κ_r
                                       (:func:`~tiremodal_cli.modal.band.window_noise_gain`)

    Returns
    -------
    list of (pole (complex, rad/s), participation (n_ref,) complex, frequency's standard
    error (Hz)) — at most :data:`MAX_NEW`.
    """
    s, L = np.asarray(s, dtype=complex), np.asarray(L, dtype=complex)
    if s.size == 0:
        return []
    q, n_ref = FORM_POWER[form], L.shape[1]
    df, K = freq[1] - freq[0], freq.size
    fn, zeta = poles_to_modal(s)
    zeta_ref = float(np.median(zeta))
    half = max(1, int(round(np.median(zeta * fn) / df)))
    thr = scipy.special.chdtri(2 * rows.shape[0] + 2, alpha / K) / 2
    Y = rows.reshape(n_ref, -1, K).transpose(1, 0, 2)  # (channel, reference, K)
    out, tried = [], set()
    for _ in range(MAX_NEW):
        weight = _weights(rows, synthesis, n_ref)
        got = None
        for i in proposals(freq, rows, synthesis, weight, half, alpha):
            if i in tried:
                continue
            tried.add(i)
            got = _try(freq, rows, weight, s, L, float(freq[i]), zeta_ref, q, thr, window)
            if got is not None:
                break
        if got is None:
            return out
        out.append(got)
        s, L = np.append(s, got[0]), np.vstack([L, got[1][None, :]])
        syn3 = lsfd_participation(freq, Y, s, L, form=form)[1]
        synthesis = syn3.transpose(1, 0, 2).reshape(rows.shape)
    return out


def with_beside(data, diagram, s0, parts, s, synthesis):
    """``diagram`` with a cluster for each pole :func:`beside_poles` adds to a poly-reference
    group's fit; None when it adds none (or the group has no participations).

    data : GroupData ; s0, parts : the selected clusters' poles and participations ;
    s : (m,) the poles the group's fit kept ; synthesis : (R, K) its fit.
    """
    if s.size == 0 or any(pt is None for pt in parts):
        return None
    L = np.array([parts[list(s0).index(p)] for p in s])
    new = beside_poles(data.freq, data.rows, synthesis, s, L, form=data.form, window=data.window)
    if not new:
        return None
    extra = []
    for p, part, sigma in new:
        f, z = poles_to_modal(np.array([p]))
        pole = StablePole(0, complex(p), float(f[0]), float(z[0]), np.zeros(0, dtype=complex), "stable", part)
        extra.append(Cluster([pole], {0}, True, f"fitted beside the group's poles where its residual held a "
                             f"peak no pole stood for (σ_f {sigma:.3g} Hz)", pole, sigma))
    return replace(diagram, clusters=diagram.clusters + extra, poles=diagram.poles + [c.representative for c in extra])
