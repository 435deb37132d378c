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
from tiremodal_cli.modal.groupfit import PEAK_OVER_NOISE
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import mpc

__all__ = ["GroupMode", "MergedMode", "SAME_POLE_ALPHA", "SAME_POLE_FLOOR_BW", "swap_cost", "merge_groups",
           "off_edges", "leak_copies", "under_residual"]


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
                 min_significance: float = 0.05) -> list[MergedMode]:
    """One mode per physical pole.

    Candidates: poles of other order groups within the dominant pole's half-power
    half-width (|Δf| ≤ ζ f) — one pole seen in several groups (leakage of a grid with
    missing points, or a mode whose shape holds several orders when the symmetry is
    broken). A candidate is the same pole when its group's data accept the dominant pole
    in place of its own, or the dominant group's data accept the candidate's pole
    (:func:`swap_cost`: 2ΔE below the χ²(2) quantile 1 − ``alpha``; either way one pole
    serves both groups — with a broken symmetry the weaker copy is at times the better
    estimate),
    or lies within :data:`SAME_POLE_FLOOR_BW` of a bandwidth (the estimator's bias) —
    and adding its share does not turn a normal mode (MPC ≥ 0.5) into none;
    two modes of neighbouring orders (the opposite branch's n = 0 and 1 lie 0.15 % apart,
    a twentieth of a bandwidth) are rejected by their own data, however close; two weak
    poles pinned apart are two modes (:func:`_pinned_apart`; ``line_hz`` (Hz, 0: not
    applied) and ``min_significance`` are its). The merged mode's shape is the sum of the
    groups' shares, its pole the dominant group's.

    Returns
    -------
    list of MergedMode, by |pole|
    """
    thr = scipy.special.chdtri(2, alpha) / 2  # χ² upper quantile (scipy.stats costs 0.4 s to import)
    fn, zeta = poles_to_modal(np.array([f.pole for f in found]))
    energy = np.array([np.linalg.norm(f.residues) ** 2 for f in found])
    used = np.zeros(len(found), dtype=bool)
    out = []
    for i in np.argsort(-energy):
        if used[i]:
            continue
        # one pole found twice in its own group (two clusters): a twin, not a split pair
        for j in range(len(found)):
            if (j != i and not used[j] and found[j].group == found[i].group and abs(fn[j] - fn[i]) <= 5e-4 * fn[i]
                    and abs(zeta[j] - zeta[i]) <= 0.05 * zeta[i]):
                used[j] = True
        groups_seen = {found[i].group: i}
        near = sorted((j for j in range(len(found)) if not used[j] and found[j].group != found[i].group
                       and abs(fn[j] - fn[i]) <= zeta[i] * fn[i]), key=lambda j: abs(fn[j] - fn[i]))
        for j in near:
            floor = abs(fn[j] - fn[i]) <= SAME_POLE_FLOOR_BW * 2 * zeta[i] * fn[i]
            apart = _pinned_apart(found[i], found[j], fn[i], fn[j], line_hz, min_significance)
            if found[j].group not in groups_seen and (floor or (not apart and (found[j].swap_cost(found[i].pole) <= thr
                                                                               or found[i].swap_cost(found[j].pole) <= thr))):
                # one normal mode seen twice: its shares add up in phase; a share that would
                # turn a normal mode (MPC ≥ 0.5, identify's gate) into none is not its own
                now = sum(found[q].residues for q in groups_seen.values())
                if not (mpc(now) >= 0.5 > mpc(now + found[j].residues)):
                    groups_seen[found[j].group] = j
        phys = sum(found[j].residues for j in groups_seen.values())
        tot = sum(energy[j] for j in groups_seen.values())
        for j in groups_seen.values():
            used[j] = True
        out.append(MergedMode(found[i].pole, found[i].group, phys, found[i].significance,
                              {int(found[j].group): float(energy[j] / tot) for j in groups_seen.values()},
                              found[i].significance_in_group, found[i].frequency_std_hz, found[i].peak,
                              found[i].group_noise, found[i].swap_cost))
    out.sort(key=lambda m: abs(m.pole))
    return out


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


def under_residual(modes: list[MergedMode], line_hz: float, n_channels: int, min_significance: float = 0.05,
                   min_mac: float = 0.9) -> tuple[list, list]:
    """Drop the weak leaks of a stronger mode of another order group (docs/lsce.md).

    A mode j is a stronger mode i seen in another order, and dropped, when all hold:
    (a) j explains under ``min_significance`` of the physical response in its half-power
    band (it was kept only for its share within its group); (c) its pole scatters by more
    than one line ``line_hz`` over the model orders (the FRFs' resolution, as (c) of
    :func:`~tiremodal_cli.modal.groupfit.own_peaks`: the data do not locate it); (d) it lies
    within ζ_i f_i of a mode of another group with a larger peak (the candidate window of
    :func:`merge_groups`); (e) it and the strongest of those, i, have one pattern at the
    sensors, MAC ≥ ``min_mac`` (0.9, the stabilization's cluster MAC) of their channel
    vectors (:func:`channel_mac`: a roving-hammer residue is φ(c) ψ(p), one φ per physical
    mode in every group). Such a pole is fitted to i's leak into j's group (an added mass
    puts every mode into every order), biased too far from i for the swap test. Each
    condition keeps real modes: (a) those the physical share supports; (c) the ring's
    sidewall same-direction modes and the paper's same-direction crowd pinned under their
    group's residual; (d) a weak mode alone; (e) a weak mode of the other branch beside a
    strong one. Until session 10 the rule also asked (b) that j's peak in its group's rows
    be under 3 × the group's fit residual RMS (:data:`~tiremodal_cli.modal.groupfit.PEAK_OVER_NOISE`);
    a weak mode on a peak of its own is one both above the noise and pinned (the own-peak
    rule), and a pole that wanders by several lines over the model orders is located by no
    peak, however high the leak it is fitted to (the ring's added-mass leaks at 406.72 and
    708.11 Hz stand 5 × above their group's residual and scatter by 3 and 4.6 lines).
    Then :func:`_leak_twins`. For a complete grid (or no spatial split): with points
    missing, every group's residual holds every order's leak (those are judged by
    :func:`leak_copies`).

    Parameters
    ----------
    modes : list of MergedMode ; line_hz : float, Hz, the band's line spacing
    n_channels : int, live response channels (the residues are channel-major)

    Returns
    -------
    kept : list of MergedMode ; dropped : list of dict (frequency, damping, group, reason)
    """
    if not modes:
        return modes, []
    fn, zeta = poles_to_modal(np.array([m.pole for m in modes]))
    kept, dropped = [], []
    for j, m in enumerate(modes):
        over = [i for i, o in enumerate(modes) if o.group != m.group and o.peak > m.peak
                and abs(fn[j] - fn[i]) <= zeta[i] * fn[i]]
        if m.significance >= min_significance or not m.frequency_std_hz > line_hz or not over:
            kept.append(m)
            continue
        i = max(over, key=lambda i: modes[i].peak)
        cm = channel_mac(modes[i].residues, m.residues, n_channels)
        if cm < min_mac:
            kept.append(m)
            continue
        dropped.append({"frequency_hz": float(fn[j]), "damping_ratio": float(zeta[j]), "group": int(m.group),
                        "reason": f"a leak of the group {modes[i].group} mode at {fn[i]:.2f} Hz: it explains "
                                  f"{100 * m.significance:.1f} % of the response at its frequency and its pole "
                                  f"scatters by {m.frequency_std_hz:.2f} Hz over the model orders (more than a "
                                  f"line, {line_hz:.3g} Hz; its response {m.peak:.3g} at resonance, its group's fit "
                                  f"residual RMS {m.group_noise:.3g}); MAC of the two modes' responses at the "
                                  f"sensors {cm:.3f}"})
    return _leak_twins(kept, dropped, modes, line_hz, min_significance)


def _leak_twins(kept: list, dropped: list, modes: list, line_hz: float, min_significance: float,
                alpha: float = SAME_POLE_ALPHA) -> tuple[list, list]:
    """Drop a weak mode whose group's data accept the pole of a leak just dropped: the same leak.

    A leak seen in two groups is merged when its group's data accept the other's pole (the
    swap test), unless the summed shares would turn a normal mode into none (MPC; the copies'
    patterns at the points need not add in phase); the copy left apart then keeps a sensor
    pattern mixed by the two orders (seen: the ring's opposite n = 13 with the added mass,
    331.08 Hz, leaks at 332.77 Hz in group 9, MAC 0.97, dropped, and at 332.45 Hz in group 5,
    MAC 0.50, whose group accepts the 332.77 Hz pole: ΔE = −17.5; merged, the two shares'
    MPC would be 0.43). A kept mode m is that leak when (a) and (c) of :func:`under_residual`
    hold for it and its group's swap test (:func:`swap_cost`, χ²(2)/2 quantile 1 − ``alpha``)
    accepts a dropped leak's pole within m's half-power half-width.
    """
    if not dropped or not kept:
        return kept, dropped
    thr = scipy.special.chdtri(2, alpha) / 2
    gone = [m for m in modes if all(m is not k for k in kept)]
    fg, _ = poles_to_modal(np.array([m.pole for m in gone]))
    fk, zk = poles_to_modal(np.array([m.pole for m in kept]))
    out = []
    for j, m in enumerate(kept):
        twin = [q for q, g in enumerate(gone) if g.group != m.group and abs(fg[q] - fk[j]) <= zk[j] * fk[j]]
        if m.significance < min_significance and m.frequency_std_hz > line_hz and m.swap_cost is not None and twin:
            q = min(twin, key=lambda q: m.swap_cost(gone[q].pole))
            cost = m.swap_cost(gone[q].pole)
            if cost <= thr:
                dropped.append({"frequency_hz": float(fk[j]), "damping_ratio": float(zk[j]), "group": int(m.group),
                                "reason": f"the same pole as the leak at {fg[q]:.2f} Hz (group {gone[q].group}) "
                                          f"dropped: its group's data accept that pole (ΔE = {cost:.1f} ≤ "
                                          f"{thr:.1f}); it explains {100 * m.significance:.1f} % of the response "
                                          f"and its pole scatters by {m.frequency_std_hz:.2f} Hz over the model "
                                          f"orders (more than a line)"})
                continue
        out.append(m)
    return out, dropped


def channel_mac(a, b, n_channels: int) -> float:
    """MAC of two modes' patterns over the response channels (the sensors).

    In a roving-hammer test the residue of mode r at channel c and point p is φ_r(c) ψ_r(p):
    its order groups' shares differ in ψ (the points' pattern) only; φ_r, the response at
    the fixed sensors, is one for the mode in every group. ``a``, ``b`` : (n_channels ·
    n_points,) residues (channel-major); φ is the leading left singular vector of each
    (n_channels, n_points) matrix.
    """
    u = [np.linalg.svd(np.asarray(x).reshape(n_channels, -1), full_matrices=False)[0][:, 0] for x in (a, b)]
    return float(abs(np.vdot(u[0], u[1])) ** 2 / (np.vdot(u[0], u[0]).real * np.vdot(u[1], u[1]).real))


def leak_copies(found: list[GroupMode], leak: dict) -> tuple[list, list]:
    """Drop the copies of a mode that a grid with missing points shows in other order groups.

    With points missing, the decomposition (:func:`~tiremodal_cli.modal.spatial.decompose`)
    puts up to ``leak[(n, m)]`` (:func:`~tiremodal_cli.modal.spatial.leakage`) of an
    order-m pattern's coefficients into group n, and group n's sweep finds the pole there
    as well — a weak copy, biased by the other orders' leaks by more than its noise (seen:
    0.1–0.8 % on a 40-point ring test with 9 points failed), so the swap test does not
    merge it. Its size tells it: a mode j of group n within the half-power half-widths of
    a mode i of group m and of its own (|Δf| ≤ min(ζ_i f_i, ζ_j f_j): a copy is i's pole
    estimated again, fitted to i's resonance, so its band holds f_i — since session 11;
    the ring's air-cavity n = 3 at 375.8 Hz, ζ = 0.5 %, 3.8 Hz below the opposite n = 15
    with ζ f = 7.6 Hz, was dropped as its copy) is i's copy when its response in group n at
    resonance (:attr:`GroupMode.peak`) is no larger than i's leakage into group n plus
    group n's fit residual: p_j ≤ leak[(n, m)] p_i + σ_n. A mode of order n at that
    frequency (the ring's opposite n = 1 and n = 4 lie 0.02 bandwidths apart) fills group
    n well above that and stays. Modes are taken strongest first. Only for a grid with
    missing points (on a complete grid nothing leaks and this is not called).

    Returns
    -------
    kept : list of GroupMode ; dropped : list of dict (frequency, damping, group, reason)
    """
    if not found:
        return found, []
    fn, zeta = poles_to_modal(np.array([f.pole for f in found]))
    own = np.array([f.peak for f in found])
    dropped_by: dict[int, int] = {}
    for i in np.argsort(-own):
        if i in dropped_by:
            continue
        for j in range(len(found)):
            gi, gj = found[i].group, found[j].group
            near = abs(fn[j] - fn[i]) <= min(zeta[i] * fn[i], zeta[j] * fn[j])
            if (j != i and j not in dropped_by and gj != gi and near
                    and own[j] <= leak.get((gj, gi), 0.0) * own[i] + found[j].group_noise):
                dropped_by[j] = i
    kept = [f for j, f in enumerate(found) if j not in dropped_by]
    why = [{"frequency_hz": float(fn[j]), "damping_ratio": float(zeta[j]), "group": int(found[j].group),
            "reason": f"a copy of the group {found[i].group} mode at {fn[i]:.2f} Hz seen through the grid's "
                      f"missing points: its response {own[j]:.3g} is within the leakage "
                      f"{leak.get((found[j].group, found[i].group), 0.0):.3f} × {own[i]:.3g} plus its group's "
                      f"residual {found[j].group_noise:.3g}"} for j, i in sorted(dropped_by.items())]
    return kept, why


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
