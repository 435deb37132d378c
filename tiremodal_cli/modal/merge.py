"""One mode per physical pole: the order groups' modes merged, and those at the band's edges dropped.

With the spatial split (:mod:`tiremodal_cli.modal.spatial`) one pole may be found in several
order groups; :func:`merge_groups` decides which are one pole (a swap test on the groups'
own data, :func:`swap_cost`) and sums their shares. :func:`off_edges` drops a mode whose
half-power band crosses an edge of the analysis band.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.special

from tiremodal_cli.frf.windows import correct_poles
from tiremodal_cli.modal.groupfit import PEAK_OVER_NOISE, PIN_SIGMAS
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import mpc
from tiremodal_cli.modal.own_mode import channel_shape, own_mode

__all__ = ["GroupMode", "MergedMode", "SAME_POLE_ALPHA", "SAME_POLE_FLOOR_BW", "COPY_MAX_AMPLITUDE", "CHANNEL_MAC_MAX",
           "channel_shape", "swap_cost",
           "merge_groups", "off_edges"]


@dataclass(frozen=True)
class GroupMode:
    """A mode as one order group's fit found it.

    pole : complex, rad/s ; group : int ; residues : (n_frf,) complex, physical FRFs
    significance : float (in the physical FRFs) ; frequency_std_hz : float (its cluster's
    :attr:`~tiremodal_cli.modal.stabilization.Cluster.frequency_std_hz`) ; swap_cost : callable(pole) → 2ΔE/2 of its group
    (:func:`swap_cost`) ; significance_in_group : float
    """

    pole: complex
    group: int
    residues: np.ndarray
    significance: float
    frequency_std_hz: float
    swap_cost: Callable
    significance_in_group: float
    group_noise: float = 0.0  # the group's residual after its fit, RMS over the band's lines (rows' norm)
    peak: float = 0.0  # the mode's response in its group's rows (accelerance) at resonance, ‖r‖ |s|² / |Re s|
    visibility: float = 0.0  # its peak over the residual RMS in the row that shows it best (groupfit.row_visibility)
    fitted: bool = False  # a pole fitted beside a stronger one (modal.beside): its scatter is its standard error


@dataclass(frozen=True)
class MergedMode:
    """A physical pole: the dominant group's pole, the groups' shares of its shape summed.

    order_energy : {group: share of the mode's energy} ; frequency_std_hz : the dominant
    group's cluster's scatter (Hz) ; peak, group_noise : the dominant group's
    :attr:`GroupMode.peak` and :attr:`GroupMode.group_noise` (accelerance, rows' norm)
    """

    pole: complex
    group: int
    residues: np.ndarray
    significance: float
    order_energy: dict
    significance_in_group: float
    frequency_std_hz: float
    peak: float = 0.0
    group_noise: float = 0.0
    swap_cost: Callable | None = None  # the dominant group's :attr:`GroupMode.swap_cost`
    # kept apart from a stronger pole of another group by its channel shape alone (the other
    # rules would have merged it): :func:`~tiremodal_cli.modal.misreads.misread` drops it in a crowd
    by_channels: bool = False


#: probability that one pole seen in two order groups is taken for two modes: the swap test
#: of :func:`merge_groups` (χ² with 2 degrees of freedom, the pole's frequency and damping)
SAME_POLE_ALPHA = 1e-3
#: two poles of different groups closer than this share of the half-power bandwidth 2ζf
#: are one pole whatever the swap test says: the estimator's own bias, which a test at high
#: SNR reads as two poles. Measured on the validation matrix (docs/validation.md,
#: datasheet): |f̂ − f| / 2ζf of the modes found has a median of 0.0002 and is below 0.01
#: for 92–93 % of them; the rest are left to the swap test (the matrix's surplus — one
#: mode reported twice — is under 1 % of the modes adopted)
SAME_POLE_FLOOR_BW = 0.01


def swap_cost(rows, synthesis, s, k, refit):
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


def merge_groups(found: list[GroupMode], alpha: float = SAME_POLE_ALPHA, line_hz: float = 0.0,
                 min_significance: float = 0.05, orthogonal: bool = False, leak=None,
                 n_channels: int = 1, mixed: bool = False) -> list[MergedMode]:
    """One mode per physical pole.

    Candidates: poles of other order groups within the dominant pole's half-power
    half-width (|Δf| ≤ ζ f) — one pole seen in several groups (leakage of a grid with
    missing points, or a mode whose shape holds several orders when the symmetry is
    broken). A candidate is the same pole when its group's data accept the dominant pole
    in place of its own, or the dominant group's data accept the candidate's pole
    (:func:`swap_cost`: 2ΔE below the χ²(2) quantile 1 − ``alpha``; either way one pole
    serves both groups — with a broken symmetry the weaker copy is at times the better
    estimate), or lies within :data:`SAME_POLE_FLOOR_BW` of a bandwidth (the estimator's
    bias), or is neither visible in its group nor pinned by its data (session 31: nothing
    tells it from a copy, which a lumped mass's mixing biases beyond the swap test) — and adding its share does not turn a normal mode (MPC ≥ 0.5) into none;
    two modes of neighbouring orders (the opposite branch's n = 0 and 1 lie 0.15 % apart,
    a twentieth of a bandwidth) are rejected by their own data, however close; two weak
    poles pinned apart are two modes (:func:`_pinned_apart`; ``line_hz`` (Hz, 0: not
    applied) and ``min_significance`` are its), and where the orders mix (``mixed``) a pole
    of its own group pinned apart (:func:`~tiremodal_cli.modal.own_mode.own_mode`). Two poles are two modes however close
    (:func:`_two_modes`) when they move the ``n_channels`` channels otherwise
    (:func:`_other_channel_shape`) or, with ``orthogonal`` (FRFs that show a symmetric
    structure, :mod:`~tiremodal_cli.modal.symmetry`), when each is located by its own
    group's data (:func:`_both_located`) or, on a grid with gaps (``leak``), one lies above
    what the other can leak into its group (:func:`_above_leak`).
    The merged mode's shape is the sum of the groups' shares, its pole the dominant group's;
    a mode kept apart by its channel shape alone, where the others would have merged it, is
    marked :attr:`MergedMode.by_channels` (in a crowd it is a blend:
    :func:`~tiremodal_cli.modal.misreads.crowd_blends`).

    Returns list of MergedMode, by |pole|.
    """
    thr = scipy.special.chdtri(2, alpha) / 2  # χ² upper quantile (scipy.stats costs 0.4 s to import)
    fn, zeta = poles_to_modal(np.array([f.pole for f in found]))
    energy = np.array([np.linalg.norm(f.residues) ** 2 for f in found])
    used, out, by_channels = np.zeros(len(found), dtype=bool), [], set()
    for i in np.argsort(-energy):
        if used[i]:
            continue
        _mark_twins(found, i, fn, zeta, used)
        groups_seen = {found[i].group: i}
        near = sorted((j for j in range(len(found)) if not used[j] and found[j].group != found[i].group
                       and abs(fn[j] - fn[i]) <= zeta[i] * fn[i]), key=lambda j: abs(fn[j] - fn[i]))
        for j in near:
            how = _joins(found, i, j, groups_seen, fn, zeta, energy[j] / energy[i], thr, line_hz, min_significance,
                         n_channels, orthogonal, leak, mixed)
            if how == "channels":  # another mode by its channel shape alone (merged otherwise)
                by_channels.add(j)
            elif how == "same":
                groups_seen[found[j].group] = j
        phys = sum(found[j].residues for j in groups_seen.values())
        tot = sum(energy[j] for j in groups_seen.values())
        for j in groups_seen.values():
            used[j] = True
        out.append(MergedMode(found[i].pole, found[i].group, phys, found[i].significance,
                              {int(found[j].group): float(energy[j] / tot) for j in groups_seen.values()},
                              found[i].significance_in_group, found[i].frequency_std_hz, found[i].peak,
                              found[i].group_noise, found[i].swap_cost, i in by_channels))
    out.sort(key=lambda m: abs(m.pole))
    return out


def _joins(found, i, j, groups_seen: dict, fn, zeta, ratio, thr, line_hz, min_significance, n_channels, orthogonal,
           leak, mixed=False) -> str | None:
    """How the weaker pole ``j`` of another group meets the dominant ``i``'s mode
    (:func:`merge_groups`): "same" (one pole: its share is added), "channels" (another mode
    by its channel shape alone, where the other rules would have merged it) or None."""
    a, b = found[i], found[j]
    two = _two_modes(a, b, ratio, line_hz, n_channels, orthogonal, leak)
    if two == "located" or b.group in groups_seen:
        return None
    floor = abs(fn[j] - fn[i]) <= SAME_POLE_FLOOR_BW * 2 * zeta[i] * fn[i]
    # neither on a peak of its own nor pinned by its group's data: nothing tells it from a's copy
    unseen = line_hz > 0 and b.visibility < PEAK_OVER_NOISE and b.frequency_std_hz > line_hz
    apart = (_pinned_apart(a, b, fn[i], fn[j], line_hz, min_significance)
             or (mixed and own_mode(found, i, j, fn, zeta, line_hz, n_channels)))
    if not (floor or unseen or (not apart and (b.swap_cost(a.pole) <= thr or a.swap_cost(b.pole) <= thr))):
        return None
    # one normal mode seen twice: its shares add up in phase; a share that would turn a
    # normal mode (MPC ≥ 0.5, identify's gate) into none is not its own
    now = sum(found[q].residues for q in groups_seen.values())
    if mpc(now) >= 0.5 > mpc(now + b.residues):
        return None
    return "channels" if two == "channels" else "same"


def _two_modes(a: GroupMode, b: GroupMode, energy_ratio: float, line_hz: float, n_channels: int, orthogonal: bool,
               leak) -> str | None:
    """Whether the weaker ``b`` of another group is another mode than ``a`` however close
    (:func:`merge_groups`), and by which rule: "located" (each located by its own group's
    data, or above a's leak), "channels" (by its channel shape alone), or None."""
    if orthogonal and (_both_located(a, b, energy_ratio, line_hz, leak is None) or _above_leak(a, b, leak)):
        return "located"
    return "channels" if _other_channel_shape(a, b, n_channels, line_hz) else None


def _above_leak(a: GroupMode, b: GroupMode, leak: dict | None) -> bool:
    """On a grid with missing points (``leak``: :func:`~tiremodal_cli.modal.spatial.leakage`)
    of a structure symmetric about its sensors, whether b is stronger in its group than a
    can leak into it: p_b > leak[(g_b, g_a)] p_a + σ_b (the bound of
    :func:`~tiremodal_cli.modal.leaks.leak_copies`) — a mode of its own, not a's copy.
    Measured (``benchmarks/gaps_sweep.py``, session 22): with the driving point left out (its
    own mirror image, a gap no image fills) found 224 → 245 of 260, spurious 31 → 26; on
    grids whose gaps the mirror images fill it is not reached; before the mirror images, on
    every gappy grid, it lost modes (916 → 894 of 1,040) and added spurious ones (62 → 102)."""
    return leak is not None and b.peak > leak.get((b.group, a.group), 0.0) * a.peak + b.group_noise


def _mark_twins(found, i, fn, zeta, used) -> None:
    """Mark as used the twins of ``found[i]``: one pole found twice in its own group (two
    clusters within 0.05 % in frequency and 5 % in damping), not a split pair."""
    for j in range(len(found)):
        if (j != i and not used[j] and found[j].group == found[i].group and abs(fn[j] - fn[i]) <= 5e-4 * fn[i]
                and abs(zeta[j] - zeta[i]) <= 0.05 * zeta[i]):
            used[j] = True


#: a pole of another group whose amplitude is under this share of the stronger one's
#: (energy ratio under its square, 0.0025) may be the stronger mode's copy there, however
#: well located (:func:`_both_located`; measured on the validation matrix)
COPY_MAX_AMPLITUDE = 0.05


#: two poles whose channel shapes are nearer orthogonal than parallel (MAC below 1/2, an
#: angle over 45°) are two modes (:func:`_other_channel_shape`)
CHANNEL_MAC_MAX = 0.5


def _other_channel_shape(a: GroupMode, b: GroupMode, n_channels: int, line_hz: float) -> bool:
    """Whether the weaker pole ``b`` moves the channels otherwise than ``a`` — another mode,
    never its copy (session 29).

    In a roving-hammer test the sensors stay put: one mode's FRFs are ψ_c(θ_s) φ(θ_p) g(ω),
    rank one over (channel, point), so every part of that mode — its share in any order
    group, a copy from the points' own errors (each point's H (1 − N_F/F)), a lumped mass's
    mixing, a leak of a grid with gaps — moves the channels as ψ_c does. A pole of another
    group whose channel shape is nearer orthogonal than parallel to a's (MAC <
    :data:`CHANNEL_MAC_MAX`) is not a's: the ring's sidewall-coupled same-direction n = 55
    at 624.7 Hz in group 13 beside the opposite n = 24 at 625.1 Hz in group 10 (0.03 of its
    half-width, 4 · 10⁻⁵ of its energy: the copy rule's ground) moves tread and sidewall
    with a MAC of 0.13 against it. ``b`` must be visible (its channel shape measured:
    :attr:`GroupMode.visibility` ≥ :data:`~tiremodal_cli.modal.groupfit.PEAK_OVER_NOISE`)
    and pinned (its scatter over the model orders, or a fitted pole's standard error, at
    most a line, ``line_hz``: located by its own group's data, as :func:`_both_located`
    asks) — the shape says a pole is no copy, not that it is a mode: a group's stray pole
    beside a crowd has a shape of its own too (measured: three such rows at the held-out
    seeds + 1000, 0.76–0.88 Hz scatter on 0.5 Hz lines) — and its part that a's copy
    cannot hold (its residues with a's channel shape projected out) a normal mode (MPC ≥
    1/2, identify's gate: on noise-free data a fit's stray pole at a strong mode's
    frequency, in a group its copy leaks into, has a shape of its own, complex — the seed
    test of ``test_lsce`` at 139.59 Hz, MPC 0.14, beside the same n = 7; until session 31
    the whole pole's MPC, which a copy of a beside the mode blends: the coupling + mass's
    same n = 49 at 562.40 Hz, MPC 0.31, 0.95 without a's channel shape); with one channel every
    MAC is 1 and the rule says nothing. The argument needs ``b`` to be one mode: in a crowd of
    its alias class one pole stands for several, and a pole kept apart by this rule alone is
    then dropped after the classification (session 30,
    :func:`~tiremodal_cli.modal.misreads.crowd_blends`). Measured on the validation matrix:
    docs/lsce.md, "Channel shapes (session 29)" and "Crowd blends (session 30)"."""
    if n_channels < 2 or line_hz <= 0 or b.visibility < PEAK_OVER_NOISE or b.frequency_std_hz > line_hz:
        return False
    u, v = channel_shape(a, n_channels), channel_shape(b, n_channels)
    if abs(np.vdot(u, v)) ** 2 >= CHANNEL_MAC_MAX:
        return False
    R = np.asarray(b.residues).reshape(n_channels, -1)
    return mpc((R - np.outer(u, u.conj() @ R)).ravel()) >= 0.5  # b's part that a's copy cannot hold


def _both_located(a: GroupMode, b: GroupMode, energy_ratio: float, line_hz: float, complete: bool = True) -> bool:
    """Whether two poles of different groups of a complete grid are each located by their own
    group's data — two modes, however close (session 16).

    Each is visible (:attr:`GroupMode.visibility` ≥ :data:`~tiremodal_cli.modal.groupfit.PEAK_OVER_NOISE`)
    and the weaker ``b`` pinned (its scatter over the model orders at most a line, ``line_hz``):
    (b) of :func:`_pinned_apart` without its (a) weakness and (c) separation. Until session 25
    the stronger had to be pinned too; a crowd's blend is not (one pole for two orders of its
    alias class, it wanders over the model orders), and its broad pole lets its group's data
    accept any pole near it, so the swap test merged a pinned mode of another order into it
    (the 24-point paper test at 2,560 Hz: the opposite n = 48 at 843.6 Hz, group 0, 0.35 Hz
    scatter, 43 % of the energy of group 1's blend of n = 47 and 49 at 837.2 Hz, 4.5 Hz). On a complete grid
    the order groups are orthogonal: a pole shows in a second group only as a copy (a broken
    symmetry, the test's own errors), a small share seldom both visible and pinned there.
    Two modes of different orders at one frequency — the paper's same-direction crowd under
    the sidewall resonance (group 0 holds n = N, each group g the pair N ± g, within a
    twentieth of a bandwidth), the ring's sidewall-shear n = 1 and n = 4 0.015 Hz apart —
    are each their group's own, and the floor and swap test (built for copies) join them.
    Measured on the validation matrix (every cross-group merge of the complete grids under
    the rules before, a truth mode of the candidate's alias class within the dominant's
    half-power half-width counted as a second mode): of 497 merged pairs both located in the
    symmetric cases 487 were two modes (98 %), of 478 not both located 51 (11 %); with a
    lumped mass 20 of 35. A copy stays small where the data locate it anyway (noise-free
    data: every copy is visible): the weaker must hold ``energy_ratio`` ≥
    :data:`COPY_MAX_AMPLITUDE` ² of the stronger's energy — of the 532 located pairs, 12 of
    the 13 under it were copies and 506 of the 519 above it two modes.

    Since session 28 the weaker is located also when it lies more than
    :data:`~tiremodal_cli.modal.groupfit.PIN_SIGMAS` × its scatter (a fitted pole's
    standard error, :mod:`~tiremodal_cli.modal.beside`) from the stronger — on a complete grid
    (``complete``), where a copy is told by its energy above; with points missing a leak's
    copy in a noisy group wanders anywhere in its band, and only a fitted pole is so judged.
    Measured on the matrix (docs/lsce.md, "A weak mode beside a strong one").
    """
    apart = np.ptp(poles_to_modal(np.array([a.pole, b.pole]))[0]) > PIN_SIGMAS * b.frequency_std_hz
    pinned = b.frequency_std_hz <= line_hz or ((complete or b.fitted) and apart)
    return (line_hz > 0 and energy_ratio >= COPY_MAX_AMPLITUDE**2 and pinned
            and all(m.visibility >= PEAK_OVER_NOISE for m in (a, b)))


def _pinned_apart(a: GroupMode, b: GroupMode, fa: float, fb: float, line_hz: float, min_significance: float) -> bool:
    """Whether two weak poles of different groups are two modes by their scatter over the model orders.

    True when each (a) explains under ``min_significance`` of the physical response (a
    mode the share does not support, kept by its group's share or its own peak), (b)
    stands on a peak of its own in its group and is pinned there (the own-peak rule,
    :func:`~tiremodal_cli.modal.groupfit.own_peaks`: its peak at least
    :data:`~tiremodal_cli.modal.groupfit.PEAK_OVER_NOISE` × the residual RMS of the row of
    its group that shows it best (:attr:`GroupMode.visibility`; the rows' norm until session 15), its
    cluster's frequency scatter σ at most ``line_hz``, the FRFs' resolution), and (c) the
    two lie more than a line and more than 3 √(σ_a² + σ_b²) apart: one pole estimated in
    two groups gives estimates within their scatter (3 σ: a 0.3 % false split for Gaussian
    scatter), and within a line the FRFs cannot tell them. The swap test has no power
    there: a weak mode's pole moved by a fraction of its bandwidth changes its group's
    fit by little against a residual that is mostly misfit (the paper's sidewall
    same-direction n = 41 and 42 in groups 7 and 8, 0.7–0.8 % of the physical response,
    ζ ≈ 3.8 %, 4.5 Hz apart, scatter 0.15 and 0.21 Hz: ΔE = −12 against the χ²(2)/2
    quantile 6.9). A strong mode's swap test has the power, and judges (without (a) the
    rule lost a mode of the ring's 5-hit case and turned the paper's tangential + added
    mass diagnosis wrong: docs/lsce.md); a leak the swap test is there to merge stays under its
    group's noise floor or wanders over the model orders (the own-peak rule's (b) and
    (c); seen: a pinned leak of the ring's opposite n = 18 with a free rim, 3.8 Hz
    above it, at 1.6 × its group's residual).
    """
    if line_hz <= 0 or any(m.frequency_std_hz > line_hz or m.visibility < PEAK_OVER_NOISE
                           or m.significance >= min_significance for m in (a, b)):
        return False
    return abs(fa - fb) > max(line_hz, 3 * float(np.hypot(a.frequency_std_hz, b.frequency_std_hz)))


def off_edges(modes: list[MergedMode], f_lo: float, f_hi: float, exp_tau_s) -> tuple[list, list]:
    """Drop modes whose half-power band (f ± ζ f) reaches past an edge of the analysis band.

    Such a pole is fitted to one flank of a peak, usually a mode just outside the band
    leaking in (seen: the 308 Hz mode of a 40–300 Hz band returned at 299.5 Hz with a
    third of its damping); its frequency cannot be trusted. The lowest band line of a
    band starting at 0 Hz is no edge.
    """
    kept, rejected = [], []
    f, z = poles_to_modal(correct_poles(np.array([m.pole for m in modes]), exp_tau_s))
    for m, fi, zi in zip(modes, f, z):
        hw = zi * fi
        if fi + hw > f_hi or (f_lo > 0 and fi - hw < f_lo):
            rejected.append({"frequency_hz": float(fi), "damping_ratio": float(zi), "group": int(m.group),
                             "reason": f"at the band edge: its half-power band {fi - hw:.1f}–{fi + hw:.1f} Hz "
                                       f"crosses the analysis band {f_lo:.1f}–{f_hi:.1f} Hz"})
        else:
            kept.append(m)
    return kept, rejected
