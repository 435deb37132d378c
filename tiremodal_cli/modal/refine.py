"""A final refinement of one order group's adopted poles against the group's FRFs.

Each pole comes from a stabilization cluster of one sweep (LSCE or pLSCF: linear least
squares in the impulse responses or a rational fraction, not in the FRFs), so it carries
the estimator's bias. Here the poles are refined by nonlinear least squares in the FRFs
themselves, by variable projection (Golub & Pereyra 1973): for given poles the residues
and the lower and upper residual terms are linear and are eliminated by least squares
(the LSFD basis, :mod:`tiremodal_cli.modal.lsfd`, with the participation factors of a
poly-reference group held fixed), and ``scipy.optimize.least_squares`` moves only the
frequencies and damping ratios.

A pole is refined jointly with the poles of its group whose half-power bands overlap its
own (a chain of overlapping bands is one set), over the lines within
:data:`WINDOW_HALF_WIDTHS` half-power half-widths of any of them. All the group's other
poles keep their values but get residues in the window (leaving a neighbour out, even one
whose band does not reach the window, let the set's poles absorb its flank: measured, the
paper's Timoshenko case's modes at 0.002 % moved to 0.1–0.9 %), and the lower and upper
residual terms stand for the modes outside the band, as in LSFD. The sets are swept
:data:`PASSES` times (each refined with its neighbours' refined poles: two modes 1.5
bandwidths apart, each started 0.3 half-widths off, came to 0.03–0.045 half-widths in one
pass and to 0.005 in two). Each channel's rows are weighted by their noise (the median of
the group fit's residual power / ln 2, as :func:`~tiremodal_cli.modal.groupfit._above_noise`
has it, averaged over the references, which share the channel's basis).

A refined set is kept only when it lowers the weighted residual, when every pole stays
inside the box it may move in — its frequency within its half-power half-width ζ f of the
original (:data:`MAX_SHIFT_HALF_WIDTHS`; ends on the box's edge: the minimum lies
elsewhere, on another mode), its damping within a factor :data:`MAX_DAMPING_FACTOR` — and
when the group's poles keep their order and stay more than one line apart (no swap, no
merge). Otherwise the set keeps its original poles. The solver's Jacobian is taken by
forward differences with an absolute step (:func:`forward_jacobian`; scipy's relative step is
√ε at θ = 0, below the projection's rounding noise, and the solver stopped where it
started: the refinement measured in session 10 had moved almost nothing).

Which poles (:func:`refine_adopted`): those within :data:`EDGE_HALF_WIDTHS` half-power
half-widths of a band edge, where LSCE's band-limited model errs, and (session 12) the weak
ones — under ``min_significance`` of the response, kept by the own-peak rule — refined with
the poles their group's fit dropped held in the basis (:func:`dropped_poles`: a weak pole's
bias is what its group's fit leaves out, above all its group's other aliases of its branch,
dropped as weak themselves); since session 35 in every group, not only one whose fit dropped
a pole (a weak pole on a strong one's flank carries LSCE's own bias too: the paper's
sidewall n = 45 at 298.91 Hz, +0.32 %, in a group that dropped nothing); where a group's rows
are not the whole data of its orders (an added mass mixes them, points are missing) a moved
pole is kept only where it also fits the physical FRFs better (every adopted pole near it in
the basis, and for a weak pole every group's dropped poles, a free residue per FRF). Since
session 33 the modal stage refines before its edge check (:func:`~tiremodal_cli.modal.merge.off_edges`
judges the refined pole), and an edge pole the FRFs do not locate is dropped. Since session 42,
where the groups are a complete model (``complete``: a full grid symmetric about its sensors,
orders unmixed) a strong pole alone in its window (:func:`_alone`; no dropped pole of its group
there) is refined too, kept where the refined window is at the noise (:func:`_window_at_noise`):
LSCE's fit of noisy impulse responses is biased where a mode spans 1–2 lines in its half-width
(docs/lsce.md, "Session 42": the 1 s held-out ring's n = 2 and 3, 0.3–0.5 % off, to 0.02 %).

References
----------
Golub & Pereyra (1973), The differentiation of pseudo-inverses and nonlinear least
squares problems whose variables separate, SIAM J. Numer. Anal. 10(2).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.optimize
import scipy.special

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.groupfit import NOISE_ALPHA
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import mpc
from tiremodal_cli.modal.varpro import (forward_jacobian, moved_poles, participation_basis, projection_residual,
                                        stack_references)

__all__ = ["MAX_DAMPING_FACTOR", "MAX_SHIFT_HALF_WIDTHS", "WINDOW_HALF_WIDTHS", "dropped_poles", "refine_poles",
           "refine_adopted"]

#: the window: lines within this many half-power half-widths of a refined pole (its
#: half-power band and as much again on each flank, where the phase still turns)
WINDOW_HALF_WIDTHS = 4.0
#: a refined frequency stays within this many half-power half-widths of the original
#: (its half-power band: beyond it the data are another mode's)
MAX_SHIFT_HALF_WIDTHS = 1.0
#: passes over the sets (Gauss-Seidel: a set refined with its neighbours' refined poles)
PASSES = 2
#: a refined damping ratio stays within this factor of the original either way
MAX_DAMPING_FACTOR = 2.0
#: only the poles within this many half-power half-widths of a band edge are refined:
#: there LSCE's band-limited model (a finite sum of exponentials in the zoom band's impulse
#: responses; a mode's flank cut at the band edge is not one) errs. Measured on the
#: validation matrix (main at c803a2c, 3,063 modes adopted): the median |f̂ − f| / ζf is
#: 0.017 at 1–2 half-widths from an edge, 0.0039 at 2–3, 0.0015 at 3–4, 0.0013 at 4–6 and
#: 0.0005–0.0010 beyond 6 (twice the interior's median up to 6). Elsewhere a group's rows
#: are not always a complete modal model (an added mass's split pairs and leaked orders),
#: and the refinement moved right modes off (docs/lsce.md, "Pole refinement")
EDGE_HALF_WIDTHS = 6.0
#: a window that reaches within a half-width of the band's top is fitted with one more
#: pole beyond the top (free from the top to this many half-widths above it, its damping
#: within :data:`MAX_DAMPING_FACTOR` of its group's modes' median ζ, the half-width's
#: measure; first the set's, which let a broad stray's be as broad): a mode just above the band,
#: whose flank the two residual terms cannot hold (one farther is smooth in the window and
#: theirs). Session 33: the 2,560 Hz paper test's opposite n = 32 at 878.87 Hz, its group's
#: next alias n = 36 at 1,020 Hz above the 1,000 Hz top, refined to 882.02 Hz without it
#: and to 878.870 Hz with it (its pole beyond at 1,018.6 Hz, ζ 0.036)
BEYOND_TOP_HALF_WIDTHS = 4.0


def overlapping_sets(fn, hw) -> list:
    """Indices of the poles in sets whose half-power bands overlap (chains joined).

    fn, hw : (m,) ndarray, Hz — frequencies and half-power half-widths ζ f.
    Returns a list of (k,) int arrays, each sorted by frequency.
    """
    order = np.argsort(fn)
    sets, cur = [], [order[0]] if order.size else []
    for a, b in zip(order[:-1], order[1:]):
        if fn[b] - fn[a] < hw[a] + hw[b]:
            cur.append(b)
        else:
            sets.append(np.array(cur))
            cur = [b]
    if cur:
        sets.append(np.array(cur))
    return sets


def _set_residual(jw, Y, s_use, L_use, m, q, top, hw):
    """The weighted residual of a set's window as a function of θ — its ``m`` poles' moves
    (:func:`moved_poles`), then, with a half-width ``hw`` (rad/s; None: none), the pole
    beyond the band's top ``top`` (rad/s; its frequency above the top in ``hw`` and its ln
    damping about ``hw``: one pole per reference, any participation) — and of which of the
    set's poles ``keep``."""
    n_ref, beyond = L_use.shape[1], hw is not None

    def fun(theta, keep=None):
        p, LL = moved_poles(theta[:2 * m], s_use, np.arange(m)), L_use
        if keep is not None:
            sel = np.concatenate([keep, np.ones(p.size - m, dtype=bool)])
            p, LL = p[sel], LL[sel]
        if beyond:
            sp = -hw * np.exp(theta[2 * m + 1]) + 1j * (top + hw * theta[2 * m])
            p, LL = np.concatenate([p, np.full(n_ref, sp)]), np.vstack([LL, np.eye(n_ref)])
        return projection_residual(participation_basis(jw, p, LL, q), Y)

    return fun


def _noise_only(fun, x, m, lower, upper, dof, n_lines) -> np.ndarray:
    """Which of a set's ``m`` poles (at ``x``) explain no more of the window than a pole
    fitted to noise would, the pole beyond the top refitted without it: the group fit's
    noise test (:func:`~tiremodal_cli.modal.groupfit._above_noise`'s χ²(``dof``)/2 bound at
    1 − NOISE_ALPHA / ``n_lines``) with the modes above the band given a pole of their own."""
    r = fun(x)
    thr = scipy.special.chdtri(dof, NOISE_ALPHA / n_lines) / 2
    out = np.zeros(m, dtype=bool)
    for k in range(m):
        keep = np.arange(m) != k

        def g(th, keep=keep):
            return fun(np.concatenate([x[:2 * m], th]), keep)
        sol = scipy.optimize.least_squares(g, x[2 * m:], jac=lambda th: forward_jacobian(g, th),
                                           bounds=(lower[2 * m:], upper[2 * m:]), x_scale=0.1, max_nfev=40)
        out[k] = 2 * sol.cost - float(r @ r) < thr
    return out


def _refine_set(freq, rows, weight, s, s_orig, L, idx, q, at_noise=False):
    """Refine the poles ``idx`` of ``s`` (in their box about ``s_orig``); returns the new
    poles (all) or None, and which of ``idx`` the window does not locate: ended on their
    box's edge, or (near the band's top) explain no more than the noise (:func:`_noise_only`)."""
    fn, zeta = poles_to_modal(s_orig)
    hw = zeta * fn
    lo, hi = np.min(fn[idx] - WINDOW_HALF_WIDTHS * hw[idx]), np.max(fn[idx] + WINDOW_HALF_WIDTHS * hw[idx])
    w = (freq >= lo) & (freq <= hi)
    use = np.concatenate([idx, np.setdiff1d(np.arange(s.size), idx)])
    n_ref = L.shape[1]
    if 2 * n_ref * w.sum() <= 2 * use.size + 2 * n_ref + 2 * idx.size:
        return None, np.zeros(idx.size, dtype=bool)
    Yc = stack_references(rows[:, w], n_ref) * weight[None, :]
    s_use = s[use].copy()
    s_use[:idx.size] = s_orig[idx]
    m, hw0, top = idx.size, -s_orig[idx].real, 2 * np.pi * freq[-1]
    beyond = 2 * np.pi * hi + hw0.max() >= top  # the window within a half-width of the band's top
    # the mode beyond the top damped as the group's modes are (their median ζ)
    fun = _set_residual(2j * np.pi * freq[w], np.concatenate([Yc.real, Yc.imag], axis=0), s_use, L[use], m, q,
                        top, float(np.median(zeta)) * top if beyond else None)
    x0 = np.concatenate([(s[idx].imag - s_orig[idx].imag) / hw0, np.log(s[idx].real / s_orig[idx].real)])
    bound = np.concatenate([np.full(m, MAX_SHIFT_HALF_WIDTHS), np.full(m, np.log(MAX_DAMPING_FACTOR))])
    lower, upper = -bound, bound
    if beyond:
        x0 = np.concatenate([x0, [1.0, 0.0]])
        lower = np.concatenate([lower, [0.0, -np.log(MAX_DAMPING_FACTOR)]])
        upper = np.concatenate([upper, [BEYOND_TOP_HALF_WIDTHS, np.log(MAX_DAMPING_FACTOR)]])
    r0 = fun(x0)
    sol = scipy.optimize.least_squares(fun, x0, jac=lambda th: forward_jacobian(fun, th), bounds=(lower, upper),
                                       x_scale=0.1, max_nfev=40 * (m + beyond))
    at = np.abs(sol.x[:2 * m]) >= 0.98 * bound
    at = at[:m] | at[m:]
    if not sol.x.size or np.any(at):
        return None, at
    if beyond:
        at = _noise_only(fun, sol.x, m, lower, upper, 2 * rows.shape[0] + 2, freq.size)
    if 2 * sol.cost >= float(r0 @ r0) or (at_noise and not _window_at_noise(sol.cost, Yc.shape, m, n_ref, use.size)):
        return None, at
    out = s.copy()
    out[use] = moved_poles(sol.x[:2 * m], s_use, np.arange(m))
    return out, at


def _window_at_noise(cost, shape, m, n_ref, n_poles) -> bool:
    """Whether a refined window's weighted residual (``cost``, half its sum of squares over
    ``shape`` (n_ref K_w, n_c) entries of unit noise variance) is the noise's: 4 cost under the
    1 − NOISE_ALPHA quantile of χ² with 2 n_ref K_w n_c less the fitted parameters' dof."""
    dof = 2 * shape[0] * shape[1] - shape[1] * (2 * n_poles + 2 * n_ref) - 2 * m
    return dof > 0 and 4 * cost <= scipy.special.chdtri(dof, NOISE_ALPHA)


def refine_poles(freq, rows, synthesis, s, L=None, *, form="accelerance", free=None):
    """Refine a group's adopted poles by variable-projection least squares (module doc).

    Parameters
    ----------
    freq : (K,) ndarray, Hz           the band's lines (uniform)
    rows : (n_ref · n_c, K) complex   the group's FRFs, reference-major
    synthesis : (n_ref · n_c, K) complex   the group's fit with the poles ``s`` (its
                                      residual gives each row's noise)
    s : (m,) complex ndarray, rad/s   the adopted poles (Im > 0)
    L : (m, n_ref) complex ndarray, optional   participation factors (poly-reference);
                                      None: one reference, a free residue per row
    form : str                        the FRFs' form
    free : (m,) bool ndarray, optional    the poles to refine (default all); the others
                                      are held, with residues

    Returns
    -------
    (m,) complex ndarray — the poles, refined where the refinement was accepted.
    """
    return _refine(freq, rows, synthesis, s, L, form, free)[0]


def _refine(freq, rows, synthesis, s, L, form, free, at_noise=False):
    """:func:`refine_poles`, and which free poles their set's last attempt did not locate
    (bool (m,), :func:`_refine_set`)."""
    s = np.asarray(s, dtype=complex)
    unlocated = np.zeros(s.size, dtype=bool)
    if s.size == 0:
        return s, unlocated
    L = np.ones((s.size, 1), dtype=complex) if L is None else np.asarray(L, dtype=complex)
    q = FORM_POWER[form]
    res = rows - synthesis
    var = np.median(res.real**2 + res.imag**2, axis=1) / np.log(2)
    var = np.maximum(var.reshape(L.shape[1], -1).mean(axis=0), np.finfo(float).tiny)
    weight = 1 / np.sqrt(var)  # per channel: the references of a channel share its basis
    df = freq[1] - freq[0]
    fn, zeta = poles_to_modal(s)
    out = s.copy()
    idx_free = np.arange(s.size) if free is None else np.flatnonzero(free)
    if idx_free.size == 0:
        return s, unlocated
    sets = [idx_free[i] for i in overlapping_sets(fn[idx_free], zeta[idx_free] * fn[idx_free])]
    for idx in [i for _ in range(PASSES) for i in sets]:
        new, unlocated[idx] = _refine_set(freq, rows, weight, out, s, L, idx, q, at_noise)
        if new is None:
            continue
        f_new = poles_to_modal(new)[0]
        order_kept = np.array_equal(np.argsort(f_new, kind="stable"), np.argsort(fn, kind="stable"))
        if order_kept and (f_new.size < 2 or np.min(np.diff(np.sort(f_new))) > df):
            out = new
    return out, unlocated


def dropped_poles(s0, P, kept, freq) -> tuple:
    """The stable poles of a group its fit dropped, as nuisance poles for
    :func:`refine_adopted`: those farther than max(ζ f, one line) from every kept pole (a
    copy of a kept mode is no other mode) and than a line from each other.

    s0 : (m0,) complex, the group's stable poles ; P : (m0, n_ref) complex or None, their
    participation ; kept : (m,) complex, the poles kept ; freq : (K,) Hz, the lines.
    Returns (poles (r,) complex, participation (r, n_ref) or None).
    """
    fk, zk = poles_to_modal(np.asarray(kept, dtype=complex))
    f0 = poles_to_modal(np.asarray(s0, dtype=complex))[0]
    df = freq[1] - freq[0]
    take = []
    for i in [i for i, p in enumerate(s0) if not np.any(kept == p)]:
        if np.all(np.abs(fk - f0[i]) > np.maximum(zk * fk, df)) and np.all(np.abs(f0[take] - f0[i]) > df):
            take.append(i)
    return np.asarray(s0, dtype=complex)[take], (None if P is None else np.asarray(P)[np.array(take, dtype=int)])


def _refine_group(modes, mine, data, s, L, synth_g, s_rej, L_rej, alone=None):
    """One group's poles refined: those near a band edge as :func:`refine_poles` does, then
    the weak ones (share under ``min_significance``) with the group's dropped poles (if any)
    held in the basis. Returns ((m,) refined poles, (m,) bool: moved as a weak pole, (m,) bool: an
    edge pole the FRFs do not locate (:func:`refine_adopted`))."""
    free = np.zeros(s.size, dtype=bool)
    for i, k in mine.items():  # no normal mode (identify's gate, MPC ≥ 1/2): a copy, held where LSCE put it
        free[k] = mpc(modes[i].residues) >= 0.5
    fn, zeta = poles_to_modal(s)
    edge = free & (np.minimum(fn - data.freq[0], data.freq[-1] - fn) / (zeta * fn) <= EDGE_HALF_WIDTHS)
    weak = np.zeros(s.size, dtype=bool)
    for i, k in mine.items():
        weak[k] = max(modes[i].significance, modes[i].significance_in_group) < data.opt.min_significance
    weak &= free & ~edge
    s_new, unlocated = _refine(data.freq, data.rows, synth_g, s, L, data.form, edge)
    L_all, f_rej, strong = None if L is None else np.vstack([L, L_rej]), poles_to_modal(s_rej)[0], free & ~edge & ~weak
    for i, k in mine.items():  # alone in its window: no other mode, no dropped pole of its group
        near = abs(f_rej - fn[k]) <= WINDOW_HALF_WIDTHS * zeta[k] * fn[k]
        strong[k] &= alone is not None and bool(alone[i]) and not near.any()
    if strong.any():  # kept only where the refined window is at the noise (_window_at_noise)
        s_new = _refine(data.freq, data.rows, synth_g, np.concatenate([s_new, s_rej]), L_all, data.form,
                        np.concatenate([strong, np.zeros(s_rej.size, dtype=bool)]), at_noise=True)[0][:s.size]
    if weak.any():
        s_new = refine_poles(data.freq, data.rows, synth_g, np.concatenate([s_new, s_rej]), L_all, form=data.form,
                             free=np.concatenate([weak, np.zeros(s_rej.size, dtype=bool)]))[:s.size]
    return s_new, weak, unlocated


def refine_adopted(modes: list, kept: dict, synthesis=None, complete: bool = False) -> tuple[list, list]:
    """The merged modes with each pole refined against its dominant group's rows
    (:func:`refine_poles`; the group's other kept poles, the copies the merge dropped among
    them, held fixed). The shapes stay the group fits' (a pole moves by a fraction of its
    half-power half-width). ``kept`` : {group: (GroupData, poles (m,), participation (m,
    n_h) or None, the group fit's synthesis, the poles the fit dropped (r,) and their
    participation (r, n_h) or None — :func:`dropped_poles`)}. With ``synthesis`` ((n_frf,
    K) complex, the physical FRFs' fit) a moved pole is kept only where it also fits the
    physical FRFs better (:func:`_physical_residual`; for a weak pole, with every group's
    dropped poles in the basis too).

    Refined: the poles within :data:`EDGE_HALF_WIDTHS` of a band edge, and the weak ones
    (share of the response under ``min_significance``: kept by the own-peak rule), with the
    poles their group's fit dropped in the basis: a weak pole is biased by what its group's
    fit leaves out, above all its group's other aliases of its branch, and by LSCE's own
    estimate (docs/lsce.md, "Known limit" and "Session 35": the paper's sidewall same n = 45
    at 298.91 Hz, +0.32 %, comes to 297.91 Hz, −0.02 %). With ``complete`` (the groups a
    complete model: a full grid symmetric about its sensors, orders unmixed) also the strong
    poles alone in their window, kept where it ends at the noise (module docstring).

    An edge pole whose refinement ends on its box's edge (the optimum lies beyond ζ f or a
    factor 2 in damping) is not located by the data; such poles are dropped (returned as
    rejections, docs/lsce.md, "Session 33") and left out of the physical check of the others.
    """
    out, moves, drop = list(modes), [], set()
    rej_all = np.concatenate([k[4] for k in kept.values()]) if kept else np.zeros(0, dtype=complex)
    alone = _alone(modes) if complete else None
    for g, (data, s, L, synth_g, s_rej, L_rej) in kept.items():
        mine = {i: int(np.flatnonzero(s == m.pole)[0]) for i, m in enumerate(modes)
                if m.group == g and np.any(s == m.pole)}
        if mine:
            s_new, weak, unlocated = _refine_group(modes, mine, data, s, L, synth_g, s_rej, L_rej, alone)
            drop |= {i for i, k in mine.items() if unlocated[k]}
            moves += [(i, s_new[k], weak[k], data) for i, k in mine.items() if s_new[k] != s[k] and not unlocated[k]]
    live = np.array([i not in drop for i in range(len(out))], dtype=bool)
    for i, new, weak, data in moves:
        if synthesis is not None:
            poles = np.array([m.pole for m in out])[live]
            poles = np.concatenate([poles, rej_all]) if weak else poles
            j, moved = int(live[:i].sum()), poles.copy()
            moved[j] = new
            if _physical_residual(data, synthesis, moved, j) >= _physical_residual(data, synthesis, poles, j):
                continue
        out[i] = replace(out[i], pole=complex(new))
    f, z = poles_to_modal(np.array([m.pole for m in modes], dtype=complex))
    dropped = [{"frequency_hz": float(f[i]), "damping_ratio": float(z[i]), "group": int(modes[i].group),
                "reason": "at the band edge: not located by the FRFs (refined in its group's rows, its "
                          "least-squares optimum lies beyond ζf in frequency or a factor 2 in damping, or "
                          "with the modes above the band's top given a pole it explains no more than noise)"}
               for i in sorted(drop)]
    return [m for i, m in enumerate(out) if live[i]], dropped


def _alone(modes) -> np.ndarray:
    """(m,) bool: no other mode's half-power band reaches the mode's window (its group holds it alone)."""
    fn, zeta = poles_to_modal(np.array([m.pole for m in modes], dtype=complex))
    hw = zeta * fn
    d = np.abs(fn[:, None] - fn[None, :]) - WINDOW_HALF_WIDTHS * hw[:, None] - hw[None, :]
    np.fill_diagonal(d, np.inf)
    return np.all(d > 0, axis=1)


def _physical_residual(data, synthesis, poles, i) -> float:
    """The weighted residual of the physical FRFs over pole ``i``'s window (its half-power
    band and :data:`WINDOW_HALF_WIDTHS` half-widths about it) fitted with every adopted pole
    whose band reaches the window (a free residue per FRF) and the lower and upper residual
    terms; each FRF weighted by its noise (the median residual power of the stage's fit /
    ln 2)."""
    fn, zeta = poles_to_modal(poles)
    hw = zeta * fn
    lo, hi = fn[i] - WINDOW_HALF_WIDTHS * hw[i], fn[i] + WINDOW_HALF_WIDTHS * hw[i]
    w = (data.freq >= lo) & (data.freq <= hi)
    near = (fn + WINDOW_HALF_WIDTHS * hw >= lo) & (fn - WINDOW_HALF_WIDTHS * hw <= hi)
    res = data.H_phys - synthesis
    var = np.maximum(np.median(res.real**2 + res.imag**2, axis=1) / np.log(2), np.finfo(float).tiny)
    Yc = data.H_phys[:, w].T / np.sqrt(var)[None, :]
    Y = np.concatenate([Yc.real, Yc.imag], axis=0)
    jw = 2j * np.pi * data.freq[w]
    r = projection_residual(participation_basis(jw, poles[near], np.ones((int(near.sum()), 1), dtype=complex),
                                    FORM_POWER[data.form]), Y)
    return float(r @ r)
