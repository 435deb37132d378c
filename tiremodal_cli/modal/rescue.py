"""A peak an order group's fit leaves unexplained, or a blend of two modes: the sweep redone at
twice the order.

LSCE spends its poles where the impulse responses carry their energy. On a wide band (a
5,120 Hz front end: 0.5–1,320 Hz in 0.5 Hz lines) a low mode in accelerance carries little
of it beside the high band's modes and noise, and the group's sweep may end before the
mode's pole appears: the ring's rim n = 1 at 24.45 Hz (peak 1,184 × the noise floor) got
no pole at any order up to 30 of its group's poly-reference sweep, and stands stable from
order 31 on when the sweep goes to 60. The group's fit then leaves the whole mode in its
residual.

**The rule** (:func:`unexplained_bands`): in the group's residual, each line's power summed
over the rows, each row over its noise variance (the median of its residual power over ln
2, as the noise test), is χ²(2R)/2 for R rows of noise alone. The noise level drifts over a
wide band (H1's noise follows the force spectrum); it is taken locally, as the running
median over :data:`LEVEL_LINES` lines over the χ²'s median. A line whose power exceeds the
1 − α/K quantile of χ²(2R)/2 (α = :data:`~tiremodal_cli.modal.groupfit.NOISE_ALPHA`,
Bonferroni over the band's K lines) is one the noise does not explain; a run of at least
two such lines (a peak spans lines: one line over the level is the noise's tail — 3.5 % of
seeded draws of noise alone on 6 rows, against 0 of 1,000 for two) whose highest line lies
outside the half-power band (and more than a line) of every pole the fit kept is a peak no
pole of the group stands for. When every group is fitted, such a run that no pole of any
group reaches either (:func:`far_bands`: a group's peak beside another group's mode is that
mode seen in the group — a leak, or a member of the same-direction crowd under the sidewall
resonance, which every group holds; on a grid whose groups are orthogonal only the crowd,
poles of two other groups or more, since session 32) is a peak no sweep found: the group's sweep is redone at
twice its highest order (as far as the band's lines allow; :func:`with_rescued`), and its
stable clusters inside those runs join the group's — the group's fit judges them with the
rest, by every rule of :mod:`~tiremodal_cli.modal.groupfit`. Not with points missing from the
grid: there every group holds every mode's leaks, and its sweep already goes to the unsplit
order.

**A blend the sweep's top resolves** (:func:`split_at_top`, session 39): an adopted cluster
that ends below the sweep's highest order, where two narrower tracks stand one on each side
of it within its bandwidth, is one pole for two modes at the orders too low to resolve them;
the sweep is redone at twice the order for it, and the blend set aside when that sweep gives
exactly two narrower clusters there, one on each side (:func:`without_blends`), and the
group's fit keeps both (:func:`parts_kept`); otherwise nothing changes.

Measured on the validation matrix (session 20): the first version, without the cross-group
condition, re-swept the 5,120 Hz ring cases' crowd at 167 Hz and a failed-points case's
band top (found −2, spurious +1 there); with it, see docs/lsce.md ("Session 20").
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.ndimage
import scipy.special

from tiremodal_cli.modal.groupfit import NOISE_ALPHA
from tiremodal_cli.modal.guard import guarded_diagram
from tiremodal_cli.modal.lsce import poles_to_modal

__all__ = ["LEVEL_LINES", "far_bands", "rescue_clusters", "split_at_top", "unexplained_bands", "with_rescued",
           "without_blends", "parts_kept"]

#: lines of the running median that gives the residual's local noise level (s18 measured
#: on the matrix's residuals: with a 101-line running median, 0.22 % of the lines exceed
#: the 0.1 % level of a complex Gaussian; with one level for the band, 6.9 %)
LEVEL_LINES = 101


def unexplained_bands(freq, rows, synthesis, s, alpha: float = NOISE_ALPHA) -> list[tuple[float, float]]:
    """The runs of lines (Hz, (lo, hi)) where the group's residual holds a peak that the
    noise does not explain and no kept pole stands for (module doc).

    freq : (K,) Hz ; rows : (R, K) complex, the group's rows ; synthesis : (R, K) complex,
    its fit (0 when no pole is kept) ; s : (m,) complex, the kept poles (rad/s)
    """
    res = rows - synthesis
    p = res.real**2 + res.imag**2
    var = np.maximum(np.median(p, axis=1) / np.log(2), np.finfo(float).tiny)
    E = np.sum(p / var[:, None], axis=0)
    R, K = rows.shape
    median = scipy.special.chdtri(2 * R, 0.5) / 2  # the median of χ²(2R)/2
    level = scipy.ndimage.median_filter(E, size=min(LEVEL_LINES, K), mode="reflect") / median
    E = E / np.maximum(level, np.finfo(float).tiny)
    over = np.flatnonzero(E > scipy.special.chdtri(2 * R, alpha / K) / 2)
    if over.size == 0:
        return []
    fn, zeta = poles_to_modal(np.asarray(s, dtype=complex)) if np.size(s) else (np.zeros(0), np.zeros(0))
    line = freq[1] - freq[0]
    out = []
    for run in np.split(over, np.flatnonzero(np.diff(over) > 1) + 1):
        if run.size < 2:  # a peak spans lines; one line over the level is the noise's tail
            continue
        f_pk = freq[run[np.argmax(E[run])]]
        if not np.any(np.abs(fn - f_pk) <= np.maximum(zeta * fn, line)):
            out.append((float(freq[run[0]]), float(freq[run[-1]])))
    return out


def far_bands(bands, poles, line_hz: float, groups=None, min_groups: int = 1, own=None) -> list[tuple[float, float]]:
    """The ``bands`` (Hz) that no pole of the group ``own`` reaches, nor the poles of
    ``min_groups`` other order groups: a pole reaches a band when it lies within its
    half-power half-width (at least a line) of any of the band's lines. A group's peak beside another group's mode is that
    mode seen in the group — a leak, where the grid's symmetry is broken, or a member of the
    crowd under the sidewall resonance, which every group holds — not a mode no sweep found.
    On a grid whose order groups are orthogonal (complete, symmetric about the sensors) a
    mode leaks into no other group, and only a crowd (poles of ``min_groups`` = 2 groups or
    more) stands for the peak: one other group's mode beside it is no such reason (the
    paper's tangential + viscoelastic tyre on 20 points, 3,200 Hz: the n = 1 same at
    51.46 Hz, 0.57 Hz below the n = 0 of group 0, got no stable pole in its group's sweep
    and was lost; swept again at twice the order it is found at 51.465 Hz).

    bands : list of (lo, hi) Hz ; poles : (m,) complex, rad/s ; line_hz : the lines' spacing ;
    groups : (m,) int, each pole's order group (None: every pole its own) ; min_groups : int ;
    own : int, the group whose bands these are (its poles reach a band alone)
    """
    fn, zeta = poles_to_modal(np.asarray(poles, dtype=complex)) if len(poles) else (np.zeros(0), np.zeros(0))
    reach = np.maximum(zeta * fn, line_hz)
    groups = np.arange(fn.size) if groups is None else np.asarray(groups)
    out = []
    for lo, hi in bands:
        near = np.abs(fn - np.clip(fn, lo, hi)) <= reach
        if not near.any() or (np.unique(groups[near & (groups != own)]).size < min_groups
                              and not np.any(near & (groups == own))):
            out.append((lo, hi))
    return out


def rescue_clusters(diagram, bands) -> list:
    """The stable clusters of ``diagram`` (a sweep at twice the order) inside ``bands``."""
    return [c for c in diagram.selected() if any(lo <= c.freq_hz <= hi for lo, hi in bands)]


def with_rescued(data, diagram, bands, sweep, group_max: int):
    """``diagram`` with the stable clusters, inside ``bands``, of the group's sweep redone at
    twice its highest order (as far as the band's K lines allow: K/2 − 1 for one reference,
    (K − 2)/3 for two); None when it has none there, or when the lines allow no higher order.

    data : GroupData ; diagram : Diagram ; bands : :func:`unexplained_bands` ;
    sweep : callable (GroupData, Band, highest order) → list of OrderPoles ; group_max : int
    """
    K = data.freq.size
    poly, top = min(2 * data.opt.poly_order, (K - 2) // 3), min(2 * group_max, K // 2 - 1)
    if poly <= data.opt.poly_order and top <= group_max:
        return None  # the lines allow no higher order: the sweep would be the same
    twice = replace(data, opt=replace(data.opt, poly_order=max(poly, data.opt.poly_order)))
    top = max(top, group_max)
    extra = rescue_clusters(guarded_diagram(twice, lambda b: sweep(twice, b, top)), bands)
    for c in extra:
        c.reason = f"{c.reason}; from a sweep to twice the order, in a peak the group's fit left unexplained"
    if not extra:
        return None  # (their poles join the diagram's: its plot shows where they came from)
    return replace(diagram, clusters=diagram.clusters + extra, poles=diagram.poles + [m for c in extra for m in c.members])


def split_at_top(diagram, freq) -> list:
    """The adopted clusters the sweep's highest order resolves into two modes: bands (Hz, (lo,
    hi)) one half-power bandwidth about each, for :func:`with_rescued`.

    Two modes within a bandwidth or two of each other give LSCE one broad pole at the model
    orders too low to resolve them (the ring's 36-point sidewall shear, 1 s records: the
    branch's n = 4 at 90.36 Hz and the second family's n = 4 at 98.32 Hz, one pole at 95.45 Hz
    with ζ 4.8 % stable over orders 9–22), and two from a higher order on, still converging
    at the sweep's top (order 30: 90.1 and 98.4 Hz, ζ 3.4 and 2.7 %, against 2 % for the
    group's other modes). The signature, read from the diagram alone: an adopted cluster
    with no member at the highest order, where two poles narrower than it (0 < ζ' < ζ) lie one
    on each side of it, more than a line from it and within its bandwidth 2ζf, neither of them
    a member of an adopted cluster (a mode found already is a neighbour, not a part). A blend
    is broader than either of its parts and lies between them; the sweep has not converged
    there, and is redone at twice the order (as :func:`with_rescued`). Only a cluster whose
    bandwidth lies inside the analysis band (``freq``, (K,) Hz): at the band's edges a mode
    is fitted to one flank, and the sweep's poles there wander with the edge."""
    line_hz = freq[1] - freq[0]
    if not diagram.poles:
        return []
    top = max(p.order for p in diagram.poles)
    found = {id(m) for c in diagram.selected() for m in c.members}  # poles of modes already found
    at_top = [p for p in diagram.poles
              if p.order == top and p.damping_ratio > 0 and p.status != "new" and id(p) not in found]
    out = []
    for c in diagram.selected():
        if top in c.orders or c.std_hz is not None:
            continue
        f, z = c.freq_hz, c.damping_ratio
        if f - 2 * z * f < freq[0] or f + 2 * z * f > freq[-1]:
            continue
        narrow = [p.freq_hz for p in at_top if p.damping_ratio < z and abs(p.freq_hz - f) <= 2 * z * f]
        if any(g < f - line_hz for g in narrow) and any(g > f + line_hz for g in narrow):
            out.append((f - 2 * z * f, f + 2 * z * f))
    return out


def without_blends(diagram, bands, line_hz: float, first_new: int):
    """``diagram`` with each adopted cluster of :func:`split_at_top`'s ``bands`` set aside
    where the rescued clusters (``diagram.clusters[first_new:]``) resolve it: two of them in
    the band, no more (a blend of two modes is two; where the higher order fills the band with
    more — a crowd, another group's leaks, the noise — it resolves no blend), narrower than
    it, one on each side of it more than a line off, each with its half-power band
    overlapping the blend's (a mode whose band lies apart from the blend's is no part of it:
    the matrix's 1-hit paper test, group 0, a cluster at 726.6 Hz (ζ 1.6 %) and two at 720.0
    and 742.6 Hz (ζ 0.8 and 0.3 %), the second 16 Hz off against half-widths of 11.5 and 2.4 Hz). Of the rescued clusters only those of
    the bands so resolved are kept (a band the higher order does not resolve stays as it was). Returns (diagram, [(the blend's frequency (Hz), its parts'
    representative poles (rad/s))]), or None when none is set aside."""
    old, new = diagram.clusters[:first_new], diagram.clusters[first_new:]
    selected = [c for c in old if c.adopted]
    keep, resolved, aside = [], [], {}
    for lo, hi in bands:
        mid = 0.5 * (lo + hi)
        blend = min(selected, key=lambda c: abs(c.freq_hz - mid))
        parts = sorted((c for c in new if c.adopted and lo <= c.freq_hz <= hi), key=lambda c: c.freq_hz)
        hw = blend.damping_ratio * blend.freq_hz
        if (len(parts) == 2 and all(c.damping_ratio < blend.damping_ratio for c in parts)
                and all(abs(c.freq_hz - blend.freq_hz) < hw + c.damping_ratio * c.freq_hz for c in parts)
                and parts[0].freq_hz < blend.freq_hz - line_hz < blend.freq_hz + line_hz < parts[1].freq_hz):
            aside[id(blend)] = replace(blend, adopted=False, reason=(
                f"{blend.reason}; a blend of two modes: the sweep to twice the order resolves it into poles on "
                f"either side of it"))  # a copy: the diagram given stays as it was
            keep += [c for c in parts if c not in keep]
            resolved.append((blend.freq_hz, [c.representative.s for c in parts]))
    if not resolved:
        return None
    kept = {id(m) for c in keep for m in c.members}
    dropped = {id(m) for c in new if c not in keep for m in c.members}
    return replace(diagram, clusters=[aside.get(id(c), c) for c in old] + keep,
                   poles=[p for p in diagram.poles if id(p) not in dropped or id(p) in kept]), resolved


def parts_kept(resolved, kept_poles, line_hz: float) -> bool:
    """Whether the group's fit keeps, of every blend :func:`without_blends` set aside, a part
    on each side of it (a part the fit drops — no peak, under the noise — was no mode, and
    the blend stands)."""
    kept = {complex(p) for p in np.atleast_1d(kept_poles)}
    for f_blend, parts in resolved:
        f = poles_to_modal(np.array([p for p in parts if complex(p) in kept], dtype=complex))[0]
        if not (np.any(f < f_blend - line_hz) and np.any(f > f_blend + line_hz)):
            return False
    return True
