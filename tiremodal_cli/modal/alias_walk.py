"""The alias walk of the tyre classification: each mode's circumferential order n along its
branch, from its spatial order on a grid of N points (split from
:mod:`tiremodal_cli.modal.classify` in session 20; the rules are in its module docstring,
"aliases").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tiremodal_cli.modal.spatial import max_order

__all__ = ["Reading", "BranchModes", "resolve_aliases"]


@dataclass(frozen=True)
class Reading:
    """What one mode's shape says on its own: its spatial order and branch, with confidences."""

    n_spatial: int
    n_confidence: float
    branch: str | None
    branch_confidence: float

    @property
    def sure(self) -> bool:
        """Both confidences ≥ 0.5."""
        return self.n_confidence >= 0.5 and self.branch_confidence >= 0.5


@dataclass(frozen=True)
class BranchModes:
    """The modes being classified: frequencies (Hz), readings, the number of points, and the
    significances (physical FRFs; own order group) that decide which modes move the mark."""

    freq_hz: np.ndarray
    reads: list
    n_points: int
    significance: np.ndarray | None
    significance_group: np.ndarray | None
    free_rim: bool = False
    complete: bool = True  # every point of the grid measured (no failed points)
    damping: np.ndarray | None = None  # damping ratios: a half-power bandwidth for the alias choice
    mixed: bool = False  # the orders mix (a lumped mass): a group's rows hold other orders' leaks

    def clear_in_group(self, r: int) -> bool:
        """Both confidences ≥ 0.5 and a significance ≥ 0.3 in its own order group (a mode
        weak in the physical FRFs beside far stronger ones of other orders), on a test whose
        orders do not mix (where they do, a group's share holds other orders' leaks)."""
        return (not self.mixed and self.reads[r].sure and self.significance_group is not None
                and self.significance_group[r] >= 0.3)

    def clear(self, r: int) -> bool:
        """Both confidences ≥ 0.5 and (when known) significance ≥ 0.3."""
        return self.reads[r].sure and (self.significance is None or self.significance[r] >= 0.3)


def resolve_aliases(m: BranchModes) -> tuple[list[int], set[int]]:
    """Each mode's order n: within a branch, n rises with frequency; aliasing can only start
    once the branch has reached the grid's highest order (⌊N/2⌋), and only clear modes
    (both confidences ≥ 0.5) move the mark.

    Returns (orders, one per mode; the modes of another family — every alias of theirs
    contradicted by the branch above them, :func:`_contradicted` — which keep their spatial
    order). Two rounds over the branches: the second asks of a mode clear only in its own
    order group that the other branch contradict its alias too, and reads that branch's
    orders as the first round resolved them."""
    ns = [o.n_spatial for o in m.reads]
    idx_of = {br: sorted((r for r in range(len(m.reads)) if m.reads[r].branch == br), key=lambda r: m.freq_hz[r])
              for br in {o.branch for o in m.reads}}
    own: dict = {br: (_off_below_lower_orders(m, idx) if m.complete else set()) for br, idx in idx_of.items()}
    for second in (False, True):
        for br, idx in idx_of.items():
            others = [q for b, ix in idx_of.items() if b != br and b is not None for q in ix] if second else None
            for _ in range(len(idx)):  # each pass can only add to ``own``
                _walk_branch(m, idx, ns, own[br])
                wrong = (_contradicted(m, idx, ns, others) - own[br]) if m.complete else set()
                if not wrong:
                    break
                own[br] |= wrong
    return ns, set().union(*own.values())


def _contradicted(m: BranchModes, idx: list[int], ns: list[int], others=None) -> set[int]:
    """The modes of one branch read as aliases that a clear mode of the branch above them
    contradicts: one more than a split pair's 5 % higher, read at its own spatial order
    (unaliased), and that order lies between the mode's spatial order and its alias —
    the alias would make the branch fall, its spatial order keeps it rising. Such a mode
    lies off the branch's dispersion (a family the branch does not hold: the ring's
    sidewall-shear modes of n = 1–5 at 93–98 Hz, beside the branch's own n = 4 at 90 Hz
    and n = 6 at 126 Hz); it keeps its spatial order. Only on a complete grid: with points
    missing every order leaks into every spatial reading (:mod:`tiremodal_cli.modal.gaps`),
    and the paper's failed-points case's n = 8 same at 147.2 Hz, read as spatial order 2, was
    given n = 2 (its diagnosis's final fit 0.09 → 2.1 % RMS, 8 modes set aside).

    The mode must be clear, or (``others``: the other branches' modes, resolved) read
    surely (both confidences ≥ 0.5) on a test whose orders do not mix, with its alias
    contradicted on the other branch as well: a mode weak in the physical FRFs has no branch
    reading to trust (its tread–sidewall product is mostly its neighbours' misfit;
    ``classify._other_branch``), but where both branches contradict the alias the branch it
    was read on does not matter, only its order's reading. Session 38: the ring sidewall
    shear's n = 1 at 98.32 Hz explains 10 % of the physical response beside the branch's
    n = 4 0.015 Hz away and was read n = 33, though neither branch can hold an order 33
    there; a held-out ring with sidewall coupling has a same n = 35 at 418 Hz, 2 % of its
    band's response, read on the opposite branch, whose alias only that branch contradicts.
    Until session 52 the second round also asked for 30 % of its own group's response
    (:meth:`BranchModes.clear_in_group`): the car tyre's cavity mode (n = 1 at 218.47 Hz, ζ
    0.5 %, 3 % of the physical response and 27 % of its group's) was read as the in-phase
    alias n = 33 below the branch's n = 6 … 17 and every anti-phase order, and, out of the
    branch's order there, put the branch's n = 20 and 21 out of order too and kept the weak
    aliases above them off their branch (``classify._other_branch``)."""
    f, reads = m.freq_hz, m.reads
    out = set()

    def against(r, n_s, qs):
        return any(f[q] > 1.05 * f[r] and m.clear(q) and ns[q] == reads[q].n_spatial and n_s < ns[q] < ns[r]
                   for q in qs)

    for i, r in enumerate(idx):
        n_s = reads[r].n_spatial
        if ns[r] == n_s:
            continue
        if m.clear(r):
            if against(r, n_s, idx[i + 1:]):
                out.add(r)
        elif others and not m.mixed and m.reads[r].sure and against(r, n_s, idx[i + 1:]) and against(r, n_s, others):
            out.add(r)
    return out


def _off_below_lower_orders(m: BranchModes, idx: list[int]) -> set[int]:
    """The clear modes of one branch (``idx``, by frequency), read at their spatial order
    n_s ≥ 2, that lie below clear modes of the branch of two or more distinct orders
    1 ≤ n < n_s, more than a split pair's 5 % above them — all below the branch's first
    clear mode at the grid's highest order ⌊N/2⌋, where aliasing starts (above it the
    aliases read at falling spatial orders, and a rising alias lies "below" the lower
    spatial orders of the aliases after it). A branch rises with n from n = 1 (MODEL.md;
    only the breathing mode n = 0 may sit anywhere), so it cannot hold n_s below lower
    orders: the mode belongs to another branch or family, keeps its spatial order and does
    not move the mark (as :func:`_contradicted`'s), and is no evidence that a later reading
    of n_s is an alias. Two orders, not one: one clear mode above may itself be of another
    family (the ring's tangential n = 1 above its branch's n = 29). Session 45: on the
    held-out 20-point ring with a mass (seed 9000), the in-phase n = 9 and 11 (153.2 and
    159.4 Hz), fitted as three poles read as anti-phase n = 9, lay below the anti-phase
    n = 1 … 8 (184–226 Hz); the walk then took the true n = 9 at 243.9 Hz for a mode off its
    branch and read n = 11 … 16 as n = 9 … 4, unflagged."""
    f, reads = m.freq_hz, m.reads
    at_top = [f[q] for q in idx if m.clear(q) and reads[q].n_spatial == max_order(m.n_points)]
    f_top = min(at_top) if at_top else np.inf
    out = set()
    for i, r in enumerate(idx):
        n_s = reads[r].n_spatial
        if n_s < 2 or f[r] >= f_top or not m.clear(r):
            continue
        lower = {reads[q].n_spatial for q in idx[i + 1:]
                 if 1.05 * f[r] < f[q] < f_top and m.clear(q) and 1 <= reads[q].n_spatial < n_s}
        if len(lower) >= 2:
            out.add(r)
    return out


def _walk_branch(m: BranchModes, idx: list[int], ns: list[int], own: frozenset | set = frozenset()) -> None:
    """:func:`_resolve_aliases` along one branch's modes ``idx`` (by frequency), into ``ns``;
    the modes ``own`` keep their spatial order and do not move the mark (:func:`_contradicted`)."""
    f, reads, n_top = m.freq_hz, m.reads, max_order(m.n_points)
    top, marks = -1, []
    for i, r in enumerate(idx):
        n = reads[r].n_spatial
        if r in own:
            ns[r] = n
            continue
        # an alias needs its true order seen below it: the lower spatial order alone is
        # no evidence (the breathing mode n = 0 can sit anywhere on the branch: with a
        # stiff tangential or membrane term it lies above dozens of orders)
        # ... and a spatial order that a clear lower mode of the branch holds, more than a
        # split pair's 5 % below, is an alias whether or not the mark reached ⌊N/2⌋
        # (each order appears once per branch)
        seen = [q for q in idx[:i] if reads[q].n_spatial == n and q not in own]  # (another family's: no evidence)
        far = any(f[r] - f[q] > 0.05 * f[r] and m.clear(q) for q in seen)
        if n == 1 and m.free_rim:
            # a free rim adds one n = 1 mode (the rim on the tyre's stiffness) to the tyre's
            # two: n = 1 may appear twice on a branch before an alias is read (a split pair,
            # within 5 %, counts once)
            lower = sorted(f[q] for q in seen if f[r] - f[q] > 0.05 * f[r] and m.clear(q))
            far = 1 + sum(b - a > 0.05 * b for a, b in zip(lower, lower[1:])) >= 2 if lower else False
        off = False  # a clear mode below every alias the branch could hold (another family)
        if (n < top and top >= n_top - 1 and seen) or far:
            alias = _smallest_alias_from(reads[r].n_spatial, top, m.n_points)
            off = alias is not None and m.clear(r) and _below_rising_branch(alias, f[r], m, r, marks)
            if alias is not None and not off:
                n = _by_dispersion(alias, reads[r].n_spatial, f[r], m, r, marks)
        ns[r] = n
        if off:  # it keeps its spatial order and does not move the mark
            continue
        # a mode weak in the physical FRFs but clear in its own group (an order beside a
        # far stronger one of another order) continues the branch one order at a time
        # (one missed order allowed); a jump is a mode of another kind seen through the
        # tread (a cavity mode)
        weak_next = (reads[r].sure and m.significance_group is not None and m.significance_group[r] >= 0.3
                     and top < n <= top + 2)
        if m.clear(r) or weak_next:
            top = max(top, n)
            marks.append((n, f[r]))


def _below_rising_branch(smallest: int, f_r: float, m: BranchModes, r: int, marks: list) -> bool:
    """Whether the clear mode ``r`` at ``f_r`` Hz lies below every alias of its class that
    the branch could hold. Where the branch rises at least linearly (its last two steps per
    order, over its last three marked orders, do not shrink) and goes on so, an order c
    above the last mark (n₁, f₁) lies at f₁ + s (c − n₁ − 1) or higher: the next order
    above f₁ (the branch may flatten there), each order after it at least the last step s
    higher. A mode more than its half-power bandwidth 2ζf below that for the ``smallest``
    alias is no alias of the branch but a mode of another family read on it (the ring's
    tangential n = 1 opposite at 785.3 Hz, 7 Hz above the branch's n = 29 at 778.4 Hz, 32 Hz
    per order: its smallest alias n = 33 lies at 874 Hz or higher; read as n = 33 it moved
    the mark, and the branch's n = 30 … 42 were read as n = 38, 65, 100 … 110). Where the
    branch flattens (a step shrinks: the same-direction branch under the sidewall
    resonance) no such bound holds and the walk reads the alias. Only on a complete grid,
    as :func:`_by_dispersion`."""
    if m.damping is None or not m.complete:
        return False
    last = {}
    for n, fq in marks:  # the highest-frequency reading of each marked order
        last[n] = max(fq, last.get(n, fq))
    pts = sorted(last.items())[-3:]
    if len(pts) < 3:
        return False
    (n0, f0), (n1, f1), (n2, f2) = pts
    s1, s2 = (f1 - f0) / (n1 - n0), (f2 - f1) / (n2 - n1)
    if not (s1 > 0 and s2 >= s1):
        return False
    return f_r < f2 + s2 * (smallest - n2 - 1) - 2 * m.damping[r] * f_r


def _by_dispersion(smallest: int, n_spatial: int, f_r: float, m: BranchModes, r: int, marks: list) -> int:
    """The alias order of the mode ``r`` at ``f_r`` Hz: the ``smallest`` alias at or above the
    mark, unless the branch's last step continued (the last two marks' frequency per order)
    puts another alias of its class nearer ``f_r`` and the two predictions lie more than the
    mode's half-power bandwidth 2ζf apart — the dispersion tells them (a step of 9.5 Hz per
    order on the ring's sidewall coupling: its n = 35 same at 418.2 Hz, 40 Hz above the n = 31,
    was read as n = 33). Where the branch flattens (a crowd) the predictions lie within a
    bandwidth and the smallest stays. Only on a complete grid, as :func:`_contradicted` (with
    points missing every order leaks into every spatial reading; on the paper's failed-points
    combination the walk's new labels changed nothing found but the joint refinement's
    proposals, 9 → 13, and the run 43 → 154 s). The step is the branch's two highest marked
    orders' (session 38: a clear mode read at its own spatial order below the mark — the
    20-point ring's opposite n = 17 at 430.7 Hz read n = 3, its alias unseen — made the last
    two marks n = 3 and 18, a step of 1.75 Hz per order, and the n = 20 at 508.2 Hz was read
    n = 40, every order above it one alias span too high)."""
    if m.damping is None or not m.complete:
        return smallest
    last = {}
    for n, fq in marks:  # the highest-frequency reading of each marked order
        last[n] = max(fq, last.get(n, fq))
    if len(last) < 2 or max(last) != marks[-1][0]:  # the last mark below the branch's top: no step to continue
        return smallest
    (n0, f0), (n1, f1) = sorted(last.items())[-2:]
    slope = (f1 - f0) / (n1 - n0)
    if not slope > 0:
        return smallest
    n_p = m.n_points
    cands = sorted({smallest} | {c for k in range(1, smallest // n_p + 3) for c in (k * n_p - n_spatial, k * n_p + n_spatial)
                                 if c >= smallest})
    pred = {c: f1 + slope * (c - n1) for c in cands}
    best = min(cands, key=lambda c: abs(pred[c] - f_r))
    return best if abs(pred[best] - pred[smallest]) > 2 * m.damping[r] * f_r else smallest


def _smallest_alias_from(n_spatial: int, top: int, n_points: int) -> int | None:
    """The smallest order k N ± n_s (k ≤ 10) at or above ``top``; None when there is none."""
    k = 1
    cands = []
    while not cands or min(cands) < top:
        cands = [c for c in (k * n_points - n_spatial, k * n_points + n_spatial) if c >= top]
        k += 1
        if k > 10:
            break
    return min(cands) if cands else None
