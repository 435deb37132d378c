"""Tyre classification of modes: circumferential order n, branch, aliases, split pairs.

* **n** from the spatial pattern of the tread shape over the impact angles: the shape (the
  residues seen by a tread sensor) is made real along its principal direction and fitted
  with the harmonics of :func:`tiremodal_cli.modal.spatial.harmonic_design`; the order holding
  the most energy wins, and its share of the energy is the confidence. On a grid with missing
  points a reading that disagrees with the order group the mode's pole was estimated in is
  read at the group's order (its own share the confidence; ``_read``, session 21).
* **branch** from the relative phase of the sidewall and tread sensors' residues: in phase
  ("same", ω₁ of the model) or opposite ("opposite", ω₂).
* **aliases**: a grid of N points cannot tell n from N − n, N + n, …. Within a branch the
  model's frequencies rise with n, so once a branch has reached the grid's top order
  ⌊N/2⌋, a mode whose spatial order falls below one already passed at a lower frequency,
  and whose spatial order a lower mode of the branch already holds, takes the smallest
  alias that keeps the order rising. A spatial order not yet seen on the branch is its
  own (n = 0, the breathing mode, is out of the branch's order whenever the belt's
  extension or a tangential stiffness lifts it). A spatial order that a clear mode of the
  branch holds more than 5 % lower (farther than a split pair) is an alias even before the
  mark reaches ⌊N/2⌋: each order appears once per branch — except n = 1 with a free rim
  (a live rim channel), which adds the rim's mode to the tyre's n = 1 modes: there a third
  n = 1 reading of a branch is the first alias. On a complete grid a clear mode keeps
  its spatial order when its alias would make the branch fall below a clear mode read at
  its own order (a family the branch does not hold; ``alias_walk._contradicted``), and so does a
  clear mode that lies more than its bandwidth below every alias a branch rising at least
  linearly could put there (``alias_walk._below_rising_branch``); neither moves the mark. Only clear modes (both
  confidences ≥ 0.5, significance ≥ 0.3) move the mark; a mode clear only in its own order
  group moves it by continuing the branch (at most two orders up).
* **confidences**: ``n_confidence`` is the winning order's energy share; the branch's is
  |Re ρ| / (‖t‖‖s‖) with ρ = tᴴs the tread–sidewall product (1: perfectly in or out of
  phase). A mode whose tread barely moves (high-n same-direction modes) gets a low one.
* **dispersion order**: of two modes of a branch whose orders fall as the frequency rises,
  the less significant is flagged ``in_order = False`` (``identify`` leaves it out) — but
  an n = 1 "same" below the n = 0 mode is not compared with it: a free rim's mode reads as
  n = 1 "same" (tread and sidewall in phase) and lies off the branch, often below n = 0.
* **split pairs**: two modes with one (n, branch) within 5 % in frequency, both in their
  branch's dispersion order, are the cos/sin members of a pair split by a broken symmetry;
  both are reported, with the splitting (a third mode of that (n, branch) out of order —
  a misread, e.g. another order's mode seen in this order's group when the symmetry is
  broken — does not undo the pair).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from tiremodal_cli.conventions import OPPOSITE, SAME
from tiremodal_cli.modal.alias_walk import BranchModes, Reading, resolve_aliases
from tiremodal_cli.modal.crowds import branch_dispersion, crowds
from tiremodal_cli.modal.misreads import MISREAD_MAX_SIGNIFICANCE
from tiremodal_cli.modal.spatial import grid_design, grid_points, max_order

__all__ = ["Classification", "classify"]


@dataclass(frozen=True)
class Classification:
    n: int
    n_spatial: int
    n_confidence: float
    aliased: bool
    branch: str | None
    branch_confidence: float = 0.0
    pair: int | None = None
    splitting_hz: float | None = None
    in_order: bool = True
    crowd: bool = False
    n_candidates: tuple = ()
    #: a mode of another family than its branch's at its order: read at its spatial order
    #: because the branch above it contradicts every alias (``alias_walk._contradicted``)
    other_family: bool = False

    def to_dict(self):
        return {"n": self.n, "n_spatial": self.n_spatial, "n_confidence": self.n_confidence,
                "n_aliased": self.aliased, "branch": self.branch, "branch_confidence": self.branch_confidence,
                "pair": self.pair, "splitting_hz": self.splitting_hz, "in_order": self.in_order,
                "crowd": self.crowd, "n_candidates": list(self.n_candidates)}


def _real(v):
    """A complex shape turned real along its principal direction."""
    phi = 0.5 * np.angle(np.sum(v**2))
    return np.real(v * np.exp(-1j * phi))


def order_energy(shape_over_points, angles_rad) -> dict[int, float]:
    """Share of a real shape's energy in each circumferential order (least squares)."""
    x = np.asarray(shape_over_points, dtype=float)
    D, names = grid_design(angles_rad)  # with points missing from a grid: the minimum-norm fit
    coef = np.linalg.lstsq(D, x, rcond=None)[0]
    energy: dict[int, float] = {}
    for c, (n, _) in zip(coef, names):
        col = D[:, names.index((n, _))]
        energy[n] = energy.get(n, 0.0) + float(c**2 * col @ col)
    tot = sum(energy.values())
    return {n: e / tot for n, e in energy.items()} if tot > 0 else energy


def classify(freq_hz, shapes, point_angle, channel_location, significance=None,
             damping_ratio=None, significance_group=None, group=None, mixed: bool = False) -> list[Classification]:
    """Classify every mode.

    Parameters
    ----------
    freq_hz : (n_modes,) array
    shapes : (n_modes, n_channels, n_points) complex array     residues
    point_angle : (n_points,) array, rad
    channel_location : sequence of str
    significance : (n_modes,) array, optional — only modes ≥ 0.3 move the alias mark
    damping_ratio : (n_modes,) array, optional — for the crowd test (see :func:`tiremodal_cli.modal.crowds.crowds`)
    significance_group : (n_modes,) array, optional — each mode's share of the response in
        its own order group: a mode ≥ 0.3 there (but not in the physical FRFs) moves the
        alias mark only by continuing the branch (to at most two orders above the mark)
    group : (n_modes,) int array, optional — the order group each mode's pole was estimated
        in; on a grid with missing points a spatial reading that disagrees with it is read
        at the group's order (:func:`_read`)
    mixed : bool — the test's orders mix (a lumped mass: :mod:`~tiremodal_cli.modal.mixing` on
        a structure symmetric about its sensors, or no such symmetry, :mod:`~tiremodal_cli.modal.symmetry`,
        since session 37): a merged mode's shape sums its copies' shares of other groups, and
        it is read at the group its pole was estimated in, as on a grid with missing points

    Returns
    -------
    list of Classification, in the order of ``freq_hz``
    """
    locs = list(channel_location)
    it = locs.index("tread")
    isw = locs.index("sidewall") if "sidewall" in locs else None
    n_p = grid_points(point_angle)  # points failed on a uniform grid alias as the whole grid
    gappy = n_p > len(point_angle)
    reads = [_read(shapes[r], it, isw, point_angle, int(group[r]) if (gappy or mixed) and group is not None else None)
             for r in range(len(freq_hz))]
    free_rim = _free_rim(shapes, locs)
    ns, families = resolve_aliases(BranchModes(freq_hz, reads, n_p, significance, significance_group, free_rim,
                                 complete=n_p == len(point_angle),
                                 damping=None if damping_ratio is None else np.asarray(damping_ratio, float),
                                 mixed=mixed))
    in_order = _in_dispersion_order(freq_hz, reads, ns, significance)
    reads = _partners_branches(freq_hz, reads, ns)
    reads = _other_branch(freq_hz, reads, ns, in_order, n_p, significance, mixed, damping_ratio)
    pairs = _split_pairs(freq_hz, reads, ns, in_order)
    on_branch = [o.sure and (in_order[r] or ns[r] == o.n_spatial) for r, o in enumerate(reads)]
    crowd = crowds(freq_hz, damping_ratio, ns, [o.n_spatial for o in reads], [o.branch for o in reads],
                    on_branch, n_p, [p[0] for p in pairs])
    n_top = max_order(n_p)
    res = []
    for r, o in enumerate(reads):
        cands = crowd[r]
        res.append(Classification(n=int(ns[r]), n_spatial=int(o.n_spatial),
                                  # a crowd's order cannot be told: its share of the candidates
                                  n_confidence=o.n_confidence / len(cands) if cands else o.n_confidence,
                                  aliased=bool(ns[r] != o.n_spatial or any(c > n_top for c in cands)),
                                  branch=o.branch, branch_confidence=o.branch_confidence, pair=pairs[r][0],
                                  splitting_hz=pairs[r][1], in_order=bool(in_order[r]), crowd=bool(cands),
                                  n_candidates=tuple(cands), other_family=r in families))
    return res


def _free_rim(shapes, locs) -> bool:
    """Whether a rim channel recorded the modes (a live rim channel: a free rim). A dead
    channel's residues are NaN (the FRF stage's null); a rim clamped to a rigid fixture
    records nothing."""
    rim = [c for c, loc in enumerate(locs) if loc == "rim"]
    sh = np.asarray(shapes)
    return bool(rim) and sh.size > 0 and any(np.all(np.isfinite(sh[:, c])) and np.any(sh[:, c] != 0) for c in rim)


def _read(shape, it: int, isw: int | None, point_angle, group: int | None = None) -> Reading:
    """One mode's (n_channels, n_points) shape read alone: the order holding most of the
    tread's energy, and the branch from the tread–sidewall product (None: no sidewall).

    ``group`` (a grid with missing points): the order group the mode's pole was estimated
    in. There the shape's harmonics are a minimum-norm fit of more columns than points, and
    every order leaks into the others (:mod:`~tiremodal_cli.modal.gaps`); the group is read
    after the found modes' leaks are taken out of it. Where the two disagree the group's
    order is read, with its own energy share as the confidence (often under 0.5: the mode
    then does not move the alias mark). Measured on the matrix's and held-out failed-points
    cases (docs/lsce.md, "Session 21"): of the disagreements outside a crowd, the group
    was right in every one (the paper's n = 8 same at 147.2 Hz read as spatial order 2, and
    the opposite n = 4 at 189.7 Hz read as 11, which moved the mark and sent the branch's
    n = 9 … 11 to 15, 34, 35)."""
    tread = shape[it]
    e = order_energy(_real(tread), point_angle)
    n_s = max(e, key=e.get)
    if group is not None and group in e and group != n_s:
        n_s = group
    branch, b_conf = None, 0.0
    if isw is not None and np.all(np.isfinite(shape[isw])):
        side = shape[isw]
        rho = np.vdot(tread, side)
        branch = SAME if rho.real >= 0 else OPPOSITE
        den = np.linalg.norm(tread) * np.linalg.norm(side)
        b_conf = float(abs(rho.real) / den) if den > 0 else 0.0
    return Reading(n_s, float(e[n_s]), branch, b_conf)


def _in_dispersion_order(freq_hz, reads: list[Reading], ns: list[int], significance) -> np.ndarray:
    """(n_modes,) bool. Within a branch n rises with frequency; of two modes out of that
    order the less significant is the misread (a weak mode far above the branch's
    saturation read as a high alias is flagged as well)."""
    sig = np.ones(len(reads)) if significance is None else np.asarray(significance)
    in_order = np.ones(len(reads), dtype=bool)
    for r in range(len(reads)):
        for q in range(len(reads)):
            if q != r and reads[q].branch == reads[r].branch and freq_hz[q] > freq_hz[r] and ns[q] < ns[r]:
                if reads[r].branch == "same" and ns[r] == 1 and ns[q] == 0:
                    continue  # an n = 1 "same" below n = 0 may be a free rim's mode, off the branch
                in_order[r if sig[q] >= sig[r] else q] = False
    return in_order


def _partners_branches(freq_hz, reads: list[Reading], ns: list[int]) -> list[Reading]:
    """A mode whose branch cannot be read (the co-located tread and sidewall sensors sit at
    its node) beside a clear mode of the same n within 5 % is taken as that mode's partner:
    it gets the partner's branch (one mode after another, in the list's order)."""
    reads = list(reads)
    for r in range(len(reads)):
        if reads[r].branch_confidence >= 0.5:
            continue
        partners = [q for q in range(len(reads)) if q != r and ns[q] == ns[r] and reads[q].branch_confidence >= 0.5
                    and abs(freq_hz[q] - freq_hz[r]) < 0.05 * freq_hz[r]]
        if len(partners) == 1 and sum(1 for q in range(len(reads)) if ns[q] == ns[r]
                                      and reads[q].branch == reads[partners[0]].branch) == 1:
            reads[r] = replace(reads[r], branch=reads[partners[0]].branch)
    return reads


def _other_branch(freq_hz, reads: list[Reading], ns: list[int], in_order, n_points: int,
                  significance=None, mixed: bool = False, damping_ratio=None) -> list[Reading]:
    """A mode whose branch cannot be read and that is out of the order of the branch it was
    read on is read on the other branch, when exactly one order of its alias class
    (k N ± n_s, k ≤ 2) fits that branch's dispersion: no clear mode of the branch holds that
    order, every clear mode of a lower order lies below it, every one of a higher order
    above. ``ns`` and ``in_order`` are updated in place; the order is flagged aliased when it
    is not the spatial one. (The sample's 260.3 Hz mode: read n = 16 "opposite" at branch
    confidence 0.22, out of order; on the same branch only n = 18 fits, between n = 17 at
    251.2 Hz and n = 19 at 269.6 Hz — the generator's n = 18 same at 260.4 Hz.)

    A branch cannot be read at a confidence under 0.5, nor (session 34) on a mode that
    explains under :data:`~tiremodal_cli.modal.misreads.MISREAD_MAX_SIGNIFICANCE` of the
    physical response in its half-power band (``significance``, (n_modes,)): its tread–sidewall
    product is then mostly its neighbours' misfit (the paper's membrane: the same-direction
    n = 55 at 344.7 Hz, 0.4 % of its band's response on the flank of the opposite n = 13 of
    its order group, reads "opposite" at confidence 0.60). Such a mode out of order was
    dropped as a misread (:mod:`~tiremodal_cli.modal.misreads`) whatever the other branch
    held. Measured: docs/lsce.md, "Session 34".

    Since session 46, where the orders mix (``mixed``: a lumped mass splits the pairs), also a
    mode whose branch cannot be read that lies in the order of the branch it was read on,
    where a clear mode of the branch holds its order: read there it is that mode's split
    partner, which its branch reading does not support; it is read on the other branch where
    one order fits (the ring coupling + mass's in-phase n = 22 at 292.5 Hz, read at confidence
    0.06 as the partner of the anti-phase n = 12 at 307.1 Hz, 4.8 % away, where the mass splits
    its neighbours' pairs by 0.5–0.8 %). A true partner whose branch cannot be read stays one
    unless the other branch has a place for it. Not on a structure symmetric about its
    sensors: there a second mode of a held order is no split partner and is dropped as a blend
    (:mod:`~tiremodal_cli.modal.misreads`) — read on the other branch instead, it was kept
    (measured: a held-out car ring's 769.9 Hz row, 0.3 % of the response, became a spurious
    in-phase n = 45).
    Where several orders fit, the branch's dispersion may pick one (:func:`_by_the_branch`,
    session 52)."""
    reads = list(reads)
    weak = np.zeros(len(reads), dtype=bool) if significance is None else \
        np.asarray(significance, dtype=float) < MISREAD_MAX_SIGNIFICANCE
    for r in range(len(reads)):
        o = reads[r]
        held = mixed and any(q != r and reads[q].sure and reads[q].branch == o.branch and ns[q] == ns[r]
                             for q in range(len(reads)))
        if (o.branch_confidence >= 0.5 and not weak[r]) or (in_order[r] and not held) or o.branch not in (SAME, OPPOSITE):
            continue
        other = OPPOSITE if o.branch == SAME else SAME
        clear = [q for q in range(len(reads)) if q != r and reads[q].branch == other and reads[q].sure]
        alias = sorted({c for k in range(3) for c in (k * n_points - o.n_spatial, k * n_points + o.n_spatial) if c >= 0})
        fits = [c for c in alias
                if all(ns[q] != c for q in clear)
                and all(freq_hz[q] < freq_hz[r] for q in clear if ns[q] < c)
                and all(freq_hz[q] > freq_hz[r] for q in clear if ns[q] > c)]
        if len(fits) > 1 and damping_ratio is not None:
            fits = _by_the_branch(fits, freq_hz, r, damping_ratio[r], ns, [q for q in clear if in_order[q]], other)
        if len(fits) == 1 and clear:
            reads[r] = replace(o, branch=other)
            ns[r], in_order[r] = fits[0], True
    return reads


def _by_the_branch(fits: list[int], freq_hz, r: int, zeta: float, ns, placed: list[int], branch: str) -> list[int]:
    """Of several orders of an alias class that fit a branch (:func:`_other_branch`; above the
    branch's highest clear mode every alias fits), the one its dispersion places at the mode:
    the branch's f(n) from its clear modes in dispersion order
    (:func:`~tiremodal_cli.modal.crowds.branch_dispersion`) puts that order within the mode's
    half-power bandwidth 2ζf and every other within none ([that order]; else ``fits``).

    Session 52, the car tyre's membrane + cavity: its in-phase n = 19, 22 … 25 (404–468 Hz,
    1–4 % of the response, the tread a fiftieth of the sidewall) read "anti-phase" at their
    spatial orders, out of that branch's order; on the in-phase branch each fit as k·34 ± n_s
    for two or more k, and each was dropped as a misread. Its dispersion, 9.8 Hz per order
    above the n = 20 at 414.7 Hz, places n = 22 at 434 Hz (the row: 435.35 Hz) and n = 46
    some 240 Hz higher."""
    f_of = branch_dispersion([ns[q] for q in placed], [freq_hz[q] for q in placed], branch)
    if f_of is None:
        return fits
    near = [c for c in fits if abs(f_of(c) - freq_hz[r]) <= 2 * zeta * freq_hz[r]]
    return near if len(near) == 1 else fits


def _split_pairs(freq_hz, reads: list[Reading], ns: list[int], in_order) -> list[tuple]:
    """Per mode (pair id, splitting in Hz), or (None, None): two in-order modes of one
    (n, branch) within 5 % in frequency are a split pair."""
    pair_id = {}
    for r in range(len(reads)):
        if in_order[r]:  # a mode out of its branch's order is a misread, no member of a pair
            pair_id.setdefault((ns[r], reads[r].branch), []).append(r)
    out = []
    for r in range(len(reads)):
        members = pair_id.get((ns[r], reads[r].branch), []) if in_order[r] else []
        pid = split = None
        if len(members) == 2 and abs(freq_hz[members[0]] - freq_hz[members[1]]) < 0.05 * freq_hz[r]:
            pid = min(members)
            split = float(abs(freq_hz[members[0]] - freq_hz[members[1]]))
        out.append((pid, split))
    return out
