"""The weak copies of a mode in other order groups, dropped after the merge.

A grid with missing points shows each mode in other groups through its leakage
(:func:`leak_copies`); an added mass puts every mode into every order, and a weak pole
fitted to such a leak, too far from its mode for the swap test, is dropped by
:func:`under_residual` (split from :mod:`tiremodal_cli.modal.merge` in session 16).
"""

from __future__ import annotations

import numpy as np
import scipy.special

from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.merge import COPY_MAX_AMPLITUDE, SAME_POLE_ALPHA, GroupMode, MergedMode

__all__ = ["under_residual", "channel_mac", "leak_copies"]


def under_residual(modes: list[MergedMode], line_hz: float, n_channels: int, min_significance: float = 0.05,
                   min_mac: float = 0.9, orthogonal: bool = False) -> tuple[list, list]:
    """Drop the weak leaks of a stronger mode of another order group (docs/lsce.md).

    A mode j is a stronger mode i seen in another order, and dropped, when all hold:
    (a) j explains under ``min_significance`` of the physical response in its half-power
    band (it was kept only for its share within its group); (c) its pole scatters by more
    than one line ``line_hz`` over the model orders (the FRFs' resolution, as (c) of
    :func:`~tiremodal_cli.modal.groupfit.own_peaks`: the data do not locate it); (d) it lies
    within ζ_i f_i of a mode of another group with a larger peak (the candidate window of
    :func:`~tiremodal_cli.modal.merge.merge_groups`); (e) it and the strongest of those, i, have one pattern at the
    sensors, MAC ≥ ``min_mac`` (0.9, the stabilization's cluster MAC) of their channel
    vectors (:func:`channel_mac`: a roving-hammer residue is φ(c) ψ(p), one φ per physical
    mode in every group). Such a pole is fitted to i's leak into j's group (an added mass
    puts every mode into every order), biased too far from i for the swap test. Each
    condition keeps real modes: (a) those the physical share supports; (c) the ring's
    sidewall same-direction modes and the paper's same-direction crowd pinned under their
    group's residual; (d) a weak mode alone; (e) a weak mode of the other branch beside a
    strong one. (f) With ``orthogonal`` (the orders unmixed, :mod:`~tiremodal_cli.modal.mixing`)
    j's peak is under :data:`~tiremodal_cli.modal.merge.COPY_MAX_AMPLITUDE` of i's: the only
    copies are then the test's errors, and adjacent orders of one branch pass (e) (session 36,
    docs/lsce.md). Until session 10 the rule also asked (b) a peak under 3 × the group's
    residual RMS; a pole that wanders over the orders is located by no peak (docs/lsce.md).
    Then :func:`_leak_twins`. For a complete grid (or no spatial split): with points
    missing, every group's residual holds every order's leak (those are judged by
    :func:`leak_copies`).

    Parameters
    ----------
    modes : list of MergedMode ; line_hz : float, Hz, the band's line spacing
    n_channels : int, live response channels (the residues are channel-major)
    orthogonal : bool, the order groups orthogonal (condition (f))

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
        if cm < min_mac or (orthogonal and not m.peak < COPY_MAX_AMPLITUDE * modes[i].peak):
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
    hold for it and its group's swap test (:func:`~tiremodal_cli.modal.merge.swap_cost`, χ²(2)/2 quantile 1 − ``alpha``)
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
