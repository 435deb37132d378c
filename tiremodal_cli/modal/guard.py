"""A guard band between the zoom band's ends, so that LSCE's band is not periodic across them.

LSCE fits damped exponentials to the band's impulse responses, ``h = ifft(H)`` over the K
lines of the band (:mod:`.lsce`). The DFT makes the band periodic: to the model a mode at
``f_b`` near the band's top is also a mode at ``f_b − K df``, below the band's foot, and its
flank (the periodic image's) reaches the foot's lines, where the data hold only the true
mode's far flank. A weak mode near the foot is biased by that missing flank as by a
neighbour (docs/lsce.md, "Pole refinement": the ring's 24.45 Hz rim mode at −0.59 % with
its group's 1,211 Hz pole 4.2 of its half-widths away across the wrap).

The guard (:func:`~tiremodal_cli.modal.lsce.bridge`) appends G lines after the band's top
(between the top and the foot of the periodic band): the images move G df further apart,
while the poles, the lines and their data are unchanged. The guard's lines hold the
straight line from the top's value to the foot's (a bridge), so the periodic data stay
continuous across both ends (zeros would put a step of the top's value at the top, which
in accelerance is the band's largest: measured, spurious poles within 10 Hz of the top in
the ring's 5,120 Hz Timoshenko + rim combination).

How wide (:func:`guard_lines`): every pair of the group's stable poles is kept at least
:data:`~tiremodal_cli.modal.refine.EDGE_HALF_WIDTHS` half-power half-widths (of the wider
of the two) apart across the wrap — the distance from an edge within which LSCE's median
error is at least twice the interior's (measured on the matrix, refine.py). Only poles
whose half-power band lies inside the band count (the others are the band edges' own
poles, which :func:`~tiremodal_cli.modal.merge.off_edges` drops). No guard — and no second
sweep — when every pair already is that far apart. A guard costs model order (the sweep's
poles also model the bridge): a guard of one whole band (K lines) lost four of the ring
Timoshenko + rim combination's same-direction n = 7 … 10 modes, and a guard of 6
half-widths of the group's widest pole in every group moved right modes in crowded groups
(docs/lsce.md, "Guard band across the wrap"), hence the least guard, only where needed —
and the guarded sweep only re-estimates the poles the wrap biases (:func:`wrap_biased`),
each replacing its first-sweep pole when the group's rows fit it better; every other pole
stays the first sweep's (a whole group swept with the guard moved right poles in crowds).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tiremodal_cli.modal.lsce import poles_to_modal, principal_responses
from tiremodal_cli.modal.lsfd import lsfd
from tiremodal_cli.modal.refine import EDGE_HALF_WIDTHS, MAX_SHIFT_HALF_WIDTHS, WINDOW_HALF_WIDTHS
from tiremodal_cli.modal.stabilization import Cluster, stabilize

__all__ = ["guard_lines", "guarded_diagram", "wrap_biased"]


def guarded_diagram(data, poles_of):
    """An order group's stabilization diagram; with ``data.opt.guard`` (the default) the
    poles the band's wrap biases re-estimated in a second sweep with a guard after the top.

    Parameters
    ----------
    data : :class:`~tiremodal_cli.modal.groupfit.GroupData`   the group's rows (n_rows, K) and lines
    poles_of : callable                     Band → list of OrderPoles (the group's sweep)

    Returns
    -------
    :class:`~tiremodal_cli.modal.stabilization.Diagram`: the first sweep's, in which only the
    clusters of the poles :func:`wrap_biased` names are replaced by the guarded sweep's
    (:func:`_re_estimated`); the first sweep's unchanged without ``data.opt.guard``, when no
    guard is needed (:func:`guard_lines` = 0) or the method is not LSCE (pLSCF fits the
    lines themselves: no impulse responses, no wrap).
    """
    opt = data.opt
    if data.group >= 0 and data.n_h == 1 and opt.method == "lsce":  # one reference: no shape test (stabilization)
        opt = replace(opt, stabilization=replace(opt.stabilization, shapes=False))
    b = principal_responses(data.freq, data.rows, None, rtol=opt.rtol_svd)
    d = stabilize(b, poles_of(b), opt.stabilization)
    if not opt.guard or opt.method != "lsce" or not d.selected():
        return d
    sel = d.selected()
    fn, zeta = poles_to_modal(np.array([c.representative.s for c in sel], dtype=complex))
    df = (data.freq[-1] - data.freq[0]) / (data.freq.size - 1)
    inside = np.flatnonzero((fn - zeta * fn >= data.freq[0]) & (fn + zeta * fn <= data.freq[-1]))  # merge.off_edges
    args = (fn[inside], zeta[inside], data.freq[0], data.freq[-1] + df)
    g = guard_lines(*args, df)
    if g == 0:
        return d
    b = principal_responses(data.freq, data.rows, None, rtol=opt.rtol_svd, guard=g)
    dg = stabilize(b, poles_of(b), opt.stabilization)
    return _re_estimated(data, d, dg, [sel[i] for i in inside[wrap_biased(*args)]])


def _re_estimated(data, d, dg, named):
    """``d`` with each named cluster replaced by the guarded sweep's stable cluster nearest
    it — within :data:`~tiremodal_cli.modal.refine.MAX_SHIFT_HALF_WIDTHS` of its half-power
    half-width (as a refined pole's move) — when the group's rows fit better with the new
    pole: the residual of the group's LSFD fit (every selected pole, free residues, residual
    terms) over the pole's window of ``WINDOW_HALF_WIDTHS`` half-widths (as refine.py's
    check in the physical FRFs). Every other cluster stays the first sweep's. The new cluster
    holds both sweeps' poles (representative: the guarded one's), so its frequency scatter —
    the pole's uncertainty downstream (identify weighs by it) — holds the wrap's move: the
    guard is the least that reaches 6 half-widths, and a bias of the move's order may remain
    (measured: the 24.45 Hz rim mode 24.30 → 24.49 Hz, the guarded cluster's own scatter
    0.005 Hz, which set the mode aside in the diagnosis as 7 σ off)."""
    clusters = list(d.clusters)
    cand = dg.selected()
    for c in named:
        s = np.array([k.representative.s for k in d.selected()], dtype=complex)
        i = int(np.flatnonzero(s == c.representative.s)[0])
        f0, z0 = c.representative.freq_hz, c.representative.damping_ratio
        near = [k for k in cand if abs(k.representative.freq_hz - f0) <= MAX_SHIFT_HALF_WIDTHS * z0 * f0]
        if not near:
            continue
        new = min(near, key=lambda k: abs(k.representative.freq_hz - f0))
        s_new = s.copy()
        s_new[i] = new.representative.s
        w = np.abs(data.freq - f0) <= WINDOW_HALF_WIDTHS * z0 * f0
        if _window_residual(data, s_new, w) < _window_residual(data, s, w):  # both sweeps' poles: its scatter holds the move
            clusters[clusters.index(c)] = Cluster(c.members + new.members, c.orders | new.orders, True, new.reason,
                                                  new.representative)
            d = replace(d, clusters=clusters)
    return d


def _window_residual(data, s, window) -> float:
    """‖rows − LSFD synthesis‖² of the group's rows (n_rows, K) with poles ``s`` over the lines ``window``."""
    r = (data.rows - lsfd(data.freq, data.rows, s, form=data.form).synthesis)[:, window]
    return float(np.sum(r.real**2 + r.imag**2))


def wrap_biased(freq_hz, damping_ratio, f_lo: float, f_hi: float) -> np.ndarray:
    """Which poles lie within ``EDGE_HALF_WIDTHS`` half-widths of another pole's image across the wrap.

    Parameters
    ----------
    freq_hz, damping_ratio : (n,) arrays     the group's stable poles (Hz; ratio)
    f_lo, f_hi : float, Hz                   the band's first line and its top (first line + K df)

    Returns
    -------
    (n,) bool: pole a is biased when, for some pole b on the other side of the band, the
    distance across the wrap (f_a − f_lo) + (f_hi − f_b) (a below b; mirrored) is under
    EDGE_HALF_WIDTHS × ζ_b f_b — b's image's flank, in b's half-widths (the distance from
    an edge within which LSCE's error is at least twice the interior's: refine.py).
    """
    f = np.asarray(freq_hz, float)
    hw = np.asarray(damping_ratio, float) * f
    wrap = (f - f_lo)[:, None] + (f_hi - f)[None, :]  # a (row) below b (column)
    wrap = np.where(f[:, None] < f[None, :], wrap, wrap.T)  # symmetric: the pair's distance
    close = (wrap < EDGE_HALF_WIDTHS * hw[None, :]) & (f[:, None] != f[None, :])
    return close.any(axis=1)


def guard_lines(freq_hz, damping_ratio, f_lo: float, f_hi: float, line_hz: float) -> int:
    """The least guard (lines) that keeps every pair of poles ``EDGE_HALF_WIDTHS`` apart across the wrap.

    Parameters
    ----------
    freq_hz, damping_ratio : (n,) arrays     the group's stable poles (Hz; ratio)
    f_lo, f_hi : float, Hz                   the band's first line and its top (first line + K df)
    line_hz : float, Hz                      the line spacing df

    Returns
    -------
    int: G ≥ 0 lines. For poles a < b the distance across the wrap is
    (f_a − f_lo) + (f_hi − f_b) + G df; it must reach EDGE_HALF_WIDTHS × max(ζ_a f_a, ζ_b f_b).
    0 when every pair already is that far apart (or fewer than two poles).
    """
    f = np.asarray(freq_hz, float)
    hw = np.asarray(damping_ratio, float) * f
    if f.size < 2:
        return 0
    wrap = (f - f_lo)[:, None] + (f_hi - f)[None, :]  # a (row) below b (column)
    need = EDGE_HALF_WIDTHS * np.maximum(hw[:, None], hw[None, :]) - wrap
    need[~(f[:, None] < f[None, :])] = -np.inf
    return int(np.ceil(max(0.0, float(need.max())) / line_hz))
