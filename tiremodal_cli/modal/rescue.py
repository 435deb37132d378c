"""A peak an order group's fit leaves unexplained: the sweep redone at twice the order.

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

__all__ = ["LEVEL_LINES", "unexplained_bands", "far_bands", "rescue_clusters", "with_rescued"]

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
