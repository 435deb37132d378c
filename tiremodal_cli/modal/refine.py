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
ones — under ``min_significance`` of the response, kept by the own-peak rule — of a group
whose fit dropped other stable poles, refined with those poles held in the basis
(:func:`dropped_poles`: a weak pole's bias is what its group's fit leaves out, above all
its group's other aliases of its branch, dropped as weak themselves); a moved pole is kept
only where it also fits the physical FRFs better (every adopted pole near it in the basis,
and for a weak pole every group's dropped poles, a free residue per FRF: the model the
group's rows lack where an added mass mixes the orders).

References
----------
Golub & Pereyra (1973), The differentiation of pseudo-inverses and nonlinear least
squares problems whose variables separate, SIAM J. Numer. Anal. 10(2).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.optimize

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.lsce import poles_to_modal
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


def _refine_set(freq, rows, weight, s, s_orig, L, idx, q):
    """Refine the poles ``idx`` of ``s`` (in their box about ``s_orig``); returns the new
    poles (all) or None."""
    fn, zeta = poles_to_modal(s_orig)
    hw = zeta * fn
    lo = np.min(fn[idx] - WINDOW_HALF_WIDTHS * hw[idx])
    hi = np.max(fn[idx] + WINDOW_HALF_WIDTHS * hw[idx])
    w = (freq >= lo) & (freq <= hi)
    others = np.setdiff1d(np.arange(s.size), idx)
    use = np.concatenate([idx, others])
    n_ref = L.shape[1]
    n_unknown = 2 * use.size + 2 * n_ref
    if 2 * n_ref * w.sum() <= n_unknown + 2 * idx.size:
        return None
    jw = 2j * np.pi * freq[w]
    Yc = stack_references(rows[:, w], n_ref) * weight[None, :]
    Y = np.concatenate([Yc.real, Yc.imag], axis=0)
    s_use, L_use = s[use].copy(), L[use]
    s_use[:idx.size] = s_orig[idx]
    loc = np.arange(idx.size)

    def fun(theta):
        return projection_residual(participation_basis(jw, moved_poles(theta, s_use, loc), L_use, q), Y)

    m = idx.size
    hw0 = -s_orig[idx].real
    x0 = np.concatenate([(s[idx].imag - s_orig[idx].imag) / hw0, np.log(s[idx].real / s_orig[idx].real)])
    bound = np.concatenate([np.full(m, MAX_SHIFT_HALF_WIDTHS), np.full(m, np.log(MAX_DAMPING_FACTOR))])
    r0 = fun(x0)
    sol = scipy.optimize.least_squares(fun, x0, jac=lambda th: forward_jacobian(fun, th), bounds=(-bound, bound),
                                       x_scale=0.1, max_nfev=40 * m)
    if not sol.x.size or np.any(np.abs(sol.x) >= 0.98 * bound) or 2 * sol.cost >= float(r0 @ r0):
        return None
    out = s.copy()
    out[use] = moved_poles(sol.x, s_use, loc)
    return out


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
    s = np.asarray(s, dtype=complex)
    if s.size == 0:
        return s
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
        return s
    sets = [idx_free[i] for i in overlapping_sets(fn[idx_free], zeta[idx_free] * fn[idx_free])]
    for idx in [i for _ in range(PASSES) for i in sets]:
        new = _refine_set(freq, rows, weight, out, s, L, idx, q)
        if new is None:
            continue
        f_new = poles_to_modal(new)[0]
        order_kept = np.array_equal(np.argsort(f_new, kind="stable"), np.argsort(fn, kind="stable"))
        if order_kept and (f_new.size < 2 or np.min(np.diff(np.sort(f_new))) > df):
            out = new
    return out


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


def _refine_group(modes, mine, data, s, L, synth_g, s_rej, L_rej):
    """One group's poles refined: those near a band edge as :func:`refine_poles` does, then
    the weak ones (share under ``min_significance``) with the group's dropped poles held in
    the basis. Returns ((m,) refined poles, (m,) bool: moved as a weak pole)."""
    free = np.zeros(s.size, dtype=bool)
    free[list(mine.values())] = True
    fn, zeta = poles_to_modal(s)
    edge = free & (np.minimum(fn - data.freq[0], data.freq[-1] - fn) / (zeta * fn) <= EDGE_HALF_WIDTHS)
    weak = np.zeros(s.size, dtype=bool)
    for i, k in mine.items():
        weak[k] = max(modes[i].significance, modes[i].significance_in_group) < data.opt.min_significance
    weak &= free & ~edge & (s_rej.size > 0)
    s_new = refine_poles(data.freq, data.rows, synth_g, s, L, form=data.form, free=edge) if edge.any() else s
    if weak.any():
        L_all = None if L is None else np.vstack([L, L_rej])
        s_new = refine_poles(data.freq, data.rows, synth_g, np.concatenate([s_new, s_rej]), L_all, form=data.form,
                             free=np.concatenate([weak, np.zeros(s_rej.size, dtype=bool)]))[:s.size]
    return s_new, weak


def refine_adopted(modes: list, kept: dict, synthesis=None) -> list:
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
    (share of the response under ``min_significance``: kept by the own-peak rule) of a
    group that dropped other poles. A weak pole is biased by what its group's fit leaves
    out — above all its group's other aliases of its branch, dropped as weak themselves
    (docs/lsce.md, "Known limit", session 12: the paper's sidewall same n = 45 at 298.91 Hz,
    +0.32 %, refitted with its group's dropped n = 57 pole at 354.76 Hz in the basis, has
    its least-squares optimum at 297.91 Hz, −0.02 %); refined without them it moves the
    wrong way (n = 47: 306.05 → 304.29 Hz, truth 307.09).
    """
    out = list(modes)
    rej_all = np.concatenate([k[4] for k in kept.values()]) if kept else np.zeros(0, dtype=complex)
    for g, (data, s, L, synth_g, s_rej, L_rej) in kept.items():
        mine = {i: int(np.flatnonzero(s == m.pole)[0]) for i, m in enumerate(modes)
                if m.group == g and np.any(s == m.pole)}
        if not mine:
            continue
        s_new, weak = _refine_group(modes, mine, data, s, L, synth_g, s_rej, L_rej)
        for i, k in mine.items():
            if s_new[k] == s[k]:
                continue
            if synthesis is not None:
                poles = np.array([m.pole for m in out])
                poles = np.concatenate([poles, rej_all]) if weak[k] else poles
                moved = poles.copy()
                moved[i] = s_new[k]
                if _physical_residual(data, synthesis, moved, i) >= _physical_residual(data, synthesis, poles, i):
                    continue
            out[i] = replace(out[i], pole=complex(s_new[k]))
    return out


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
