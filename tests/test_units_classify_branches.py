"""A mode of another family read at its spatial order, and weak in-phase aliases read on
their branch by its dispersion (:mod:`tiremodal_cli.modal.alias_walk`,
:func:`tiremodal_cli.modal.classify._other_branch`; docs/lsce.md, "Session 52").

Truths used (as tests/test_units_classify.py): a tread shape cos nθ has circumferential order
n; a sidewall in phase with the tread is the in-phase branch, against it the anti-phase one;
on N equally spaced points n and N − n take the same values; along a branch the frequency
rises with n. The set-up is the car tyre's sidewall membrane + cavity test (34 points): the
in-phase branch n = 0 … 20 at 150 + 10 n Hz, the anti-phase one n = 0 … 17 from 400 Hz at
30 Hz per order, the cavity's narrow n = 1 at 218 Hz read on the in-phase branch, and the
in-phase n = 22 and 23 so sidewall-dominated that their tread–sidewall product is the
neighbours' misfit (read "anti-phase" at their spatial orders 12 and 11).
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.modal.classify import classify

LOCS = ("tread", "sidewall")
N_P = 34
TH = 2 * np.pi * np.arange(N_P) / N_P


def _set_up(cavity: bool, weak: bool):
    """(frequencies, shapes, significance, significance in group, damping) of the set-up."""
    rows = [(150.0 + 10 * n, n, 0.5, 0.6, 0.6, 0.03) for n in range(21)]  # f, n, ratio, sig, sig_group, ζ
    rows += [(400.0 + 30 * n, n, -0.5, 0.6, 0.6, 0.03) for n in range(18)]
    if cavity:  # narrow, weak in the physical FRFs and under 0.3 of its group's response
        rows.append((218.0, 1, 0.5, 0.03, 0.27, 0.005))
    if weak:  # the sidewall in quadrature but for a trace against the tread: read anti-phase
        rows += [(370.0, 22, -0.1 + 1j, 0.02, 0.5, 0.037), (380.0, 23, -0.1 + 1j, 0.02, 0.5, 0.037)]
    S = np.zeros((len(rows), 2, N_P), complex)
    for r, (_, n, ratio, *_rest) in enumerate(rows):
        S[r, 0] = np.cos(n * TH)
        S[r, 1] = ratio * S[r, 0]
    f, _, _, sig, sig_g, zeta = (np.array(c) for c in zip(*rows))
    return f, S, sig, sig_g, zeta


def _classes(cavity: bool, weak: bool, with_damping: bool = True):
    f, S, sig, sig_g, zeta = _set_up(cavity, weak)
    return f, classify(f, S, TH, LOCS, sig, zeta if with_damping else None, sig_g)


def test_a_narrow_mode_whose_alias_both_branches_contradict_keeps_its_order():
    """The cavity's n = 1 at 218 Hz: read as the in-phase alias 33 it would lie below the
    branch's n = 7 … 20 read at their own orders, and below every anti-phase order too. Its
    order reading is sure (one harmonic), so it keeps n = 1, a mode of another family, however
    little of the physical response or of its group it explains; the branch's own modes keep
    their orders and stay in order."""
    f, res = _classes(cavity=True, weak=False)
    cav = res[int(np.flatnonzero(f == 218.0)[0])]
    assert (cav.n, cav.aliased, cav.other_family) == (1, False, True)
    assert [c.n for c in res[:21]] == list(range(21)) and all(c.in_order for c in res[:21])


def test_weak_in_phase_aliases_read_anti_phase_are_read_on_their_branch_by_its_dispersion():
    """n = 22 at 370 Hz reads anti-phase spatial order 12, out of that branch's order (its n =
    12 at 760 Hz). On the in-phase branch every order of its class {12, 22, 46, 56, 80} but
    the held 12 fits between the clear modes (none lies above 350 Hz); the branch's dispersion,
    10 Hz per order from its n = 20 at 350 Hz, puts n = 22 at 370 Hz, within the mode's
    half-power bandwidth, and n = 46 at 610 Hz, far outside: it is read n = 22 in phase,
    aliased and in order (so no misread); n = 23 likewise. Without the damping ratios (no
    bandwidth to judge by) the orders stay ambiguous and the readings stay anti-phase."""
    for with_damping, expect in ((True, [(22, "same", True), (23, "same", True)]),
                                 (False, [(12, "opposite", False), (11, "opposite", False)])):
        f, res = _classes(cavity=False, weak=True, with_damping=with_damping)
        got = [(res[i].n, res[i].branch, res[i].in_order) for i in np.flatnonzero(np.isin(f, [370.0, 380.0]))]
        assert got == expect, with_damping
        assert [c.n for c in res[:21]] == list(range(21))


def test_the_cavity_and_the_weak_aliases_together():
    """Both at once (the car test): the cavity row no longer sits on the in-phase branch as n =
    33, out of its order, and the weak aliases are read n = 22 and 23 there."""
    f, res = _classes(cavity=True, weak=True)
    got = [(res[i].n, res[i].branch) for i in np.flatnonzero((f == 370.0) | (f == 380.0))]
    assert got == [(22, "same"), (23, "same")]
