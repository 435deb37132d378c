"""The crowd test's continuation of the in-phase branch (:mod:`tiremodal_cli.modal.crowds`).

Truths used: the seed model's closed form (MODEL.md, ``closed_form_hz``, with its n⁴ bending
term, which the saturating law leaves out) and the independent finite-element ring
(``ring_modes``, the matrix's ``ring`` generator at its default parameters); a mode is in a
crowd when another order aliasing onto it (N ± n on N points) lies within its half-power
bandwidth 2ζf on the branch's true dispersion (the ruler's definition).
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.modal.classify import classify
from tiremodal_cli.modal.crowds import branch_dispersion, saturating_dispersion
from tiremodal_cli.tyre.effects import resolve_effects
from tiremodal_cli.tyre.frequencies import branch_frequencies
from tiremodal_cli.tyre.model import TyreParameters, closed_form_hz
from tiremodal_cli.tyre.ring import ring_modes
from tiremodal_cli.tyre.ring_parameters import RingParameters


@pytest.fixture(scope="module")
def ring_same():
    """{n: f (Hz)} of the finite-element ring's in-phase branch (its lowest mode of each order)."""
    m = ring_modes(RingParameters(), f_max_hz=175)
    out = {}
    for f, n, b in zip(m.freq_hz, m.n, m.branch):
        if b == "same":
            out.setdefault(int(n), float(f))
    return out


def test_the_saturating_law_continues_both_generators_in_phase_branch():
    """Fitted to n = 2 … 17, the law continues the seed model's branch to n = 60 within 0.1 Hz
    (its bending term grows as n⁴) and the ring's to n = 44 within 0.05 Hz (next test); the
    last step's slope (0.45 Hz per order at n = 17, the premise of a straight continuation)
    is 16.5 Hz off at n = 60 (9.5 Hz off the ring's at n = 44)."""
    ff = closed_form_hz(np.arange(2, 61), TyreParameters())[:, 0]
    law = saturating_dispersion(np.arange(2, 18), ff[:16])
    assert law is not None
    np.testing.assert_allclose([law(n) for n in range(18, 61)], ff[16:], atol=0.1)
    assert ff[15] + (ff[15] - ff[14]) * (60 - 17) - ff[58] > 10.0


def test_the_law_continues_the_finite_element_ring(ring_same):
    ns = np.arange(2, 18)
    law = saturating_dispersion(ns, [ring_same[n] for n in ns])
    assert law is not None
    far = [n for n in range(18, 45) if n in ring_same]
    assert len(far) >= 20
    np.testing.assert_allclose([law(n) for n in far], [ring_same[n] for n in far], atol=0.05)
    step = ring_same[17] - ring_same[16]
    assert ring_same[17] + step * (44 - 17) - ring_same[44] > 5.0


def test_a_branch_without_saturation_gets_no_law():
    """A branch rising at a steady step (no resonance to tend to) is not continued by it."""
    ns = np.arange(2, 18)
    assert saturating_dispersion(ns, 60.0 + 20.0 * ns) is None
    assert saturating_dispersion(ns[:4], [70.0, 90.0, 100.0, 105.0]) is None  # too few orders


def test_crowd_biased_top_orders_make_no_false_crowd(ring_same):
    """34 points, the ring's in-phase branch n = 0 … 17 with ζ = 0.02, its orders 12 … 17
    as the estimator found them in the matrix's ``ring:noise=0.05`` case: biased up to 1 Hz
    towards the crowd, the last step 0.1 Hz per order (the truth's 0.45). By the truth n = 11
    (159.41 Hz) is alone: its alias 34 − 11 = 23 lies at 166.47 Hz, 7.06 Hz away, outside
    2ζf = 6.38 Hz; the last step's continuation put n = 23 at 165.8 Hz, inside (a false
    crowd, a right label scored as an alias). With ζ = 0.026 (2ζf = 8.29 Hz) n = 23 is inside
    by the truth, and n = 11 is a crowd with 23 among its candidates."""
    th = 2 * np.pi * np.arange(34) / 34
    biased = [162.14, 163.25, 164.20, 164.78, 165.08, 165.18]  # n = 12 … 17
    f = [ring_same[n] for n in range(12)] + biased
    S = np.zeros((18, 2, 34), complex)
    for n in range(18):
        S[n, 0] = np.cos(n * th)
        S[n, 1] = 0.5 * S[n, 0]
    assert ring_same[23] - ring_same[11] > 2 * 0.02 * ring_same[11]
    res = classify(f, S, th, ("tread", "sidewall"), damping_ratio=[0.02] * 18)
    assert [c.n for c in res] == list(range(18))
    assert not res[11].crowd and not res[11].aliased
    assert ring_same[23] - ring_same[11] < 2 * 0.026 * ring_same[11]
    wide = classify(f, S, th, ("tread", "sidewall"), damping_ratio=[0.026] * 18)
    assert wide[11].crowd and 23 in wide[11].n_candidates


def test_the_law_stands_alone_only_where_it_describes_the_branch(ring_same):
    """The ring's branch (no sidewall term growing with n): its top mode is no outlier
    above the law, and the continuation is the law, within 0.05 Hz of the truth to n = 44.
    The seed model with a sidewall membrane (T_s = 5 kN, the matrix's value: the sidewall's
    stiffness grows as n², the branch keeps rising): the law fitted to n = 2 … 17 lies
    below the top mode by more than its scatter and 4–9 Hz below the truth at n = 18 … 20;
    the continuation is the last step's, within 0.3 Hz there."""
    ns = list(range(18))
    ring = branch_dispersion(ns, [ring_same[n] for n in ns], "same")
    far = [n for n in range(18, 45) if n in ring_same]
    np.testing.assert_allclose([ring(n) for n in far], [ring_same[n] for n in far], atol=0.05)
    p = TyreParameters()
    f = branch_frequencies(np.arange(21), p, resolve_effects({"sidewall_membrane": {"T_s": 5.0e3}}))[:, 0]
    law = saturating_dispersion(np.arange(2, 18), f[2:18])
    assert law is not None and all(f[n] - law(n) > 4.0 for n in (18, 19, 20))
    membrane = branch_dispersion(ns, list(f[:18]), "same")
    np.testing.assert_allclose([membrane(n) for n in (18, 19, 20)], f[18:21], atol=0.3)


def test_a_lone_order_across_an_alias_span_does_not_bridge_the_dispersion(ring_same):
    """24 points, the ring's in-phase branch n = 0 … 24 with ζ = 0.02, and one weak row the
    alias walk read as the same branch's n = 51 at 380.36 Hz (a copy, as in the matrix's
    24-point case at 0.1 % noise). By the truth n = 19 is a crowd: its alias 24 + 5 = 29 lies
    within 2ζf of it. Interpolated to the lone row, f(29) would be 206 Hz and the crowd lost;
    27 orders with no mode between (more than N/2 = 12, an alias span) do not bridge it."""
    from tiremodal_cli.modal.crowds import crowds
    N = 24
    assert abs(ring_same[29] - ring_same[19]) < 2 * 0.02 * ring_same[19]
    ns = list(range(25)) + [51]
    f = [ring_same[n] for n in range(25)] + [380.36]
    n_sp = [min(n % N, N - n % N) for n in ns]
    out = crowds(f, [0.02] * len(f), ns, n_sp, ["same"] * len(f), [True] * len(f), N)
    assert 29 in out[19]
    assert crowds(f[:-1], [0.02] * 25, ns[:-1], n_sp[:-1], ["same"] * 25, [True] * 25, N)[19] == out[19]


def test_an_alias_span_gap_cuts_the_branchs_points():
    from tiremodal_cli.modal.crowds import _anchored
    pts = {0: 53.0, 1: 57.0, 5: 110.0, 24: 166.8, 51: 380.4}
    assert _anchored(pts, 24) == {0: 53.0, 1: 57.0, 5: 110.0}  # 5 → 24 is 19 > 12 orders
    assert _anchored(pts, 48) == {0: 53.0, 1: 57.0, 5: 110.0, 24: 166.8}  # 24 → 51 is 27 > 24
    assert _anchored(pts, 60) == pts


@pytest.fixture(scope="module")
def ring_opposite():
    """{n: f (Hz)} of the finite-element ring's anti-phase branch to n = 49."""
    m = ring_modes(RingParameters(), f_max_hz=1600)
    out = {}
    for f, n, b in zip(m.freq_hz, m.n, m.branch):
        if b == "opposite":
            out.setdefault(int(n), float(f))
    return out


def test_candidates_reach_one_alias_span_above_the_branchs_top(ring_opposite):
    """24 points, the ring's anti-phase branch read by the alias walk up to n = 47 (2 N, as
    the matrix's 2,560 Hz paper test reads its branch to n = 60), ζ = 0.035. By the truth n = 47
    (1,475.7 Hz) is a crowd: n = 49 of its alias class (24 · 2 + 1) lies 93.1 Hz above, inside
    2ζf = 103.3 Hz; n = 30 is alone (its class's n = 42 is 461 Hz above). Candidates capped at
    1.5 N = 36 had left n = 47 a confident order."""
    from tiremodal_cli.modal.crowds import candidate_limit, crowds
    N, zeta = 24, 0.035
    assert ring_opposite[49] - ring_opposite[47] < 2 * zeta * ring_opposite[47]
    assert ring_opposite[42] - ring_opposite[30] > 2 * zeta * ring_opposite[30]
    ns = list(range(48))
    f = [ring_opposite[n] for n in ns]
    n_sp = [min(n % N, N - n % N) for n in ns]
    out = crowds(f, [zeta] * 48, ns, n_sp, ["opposite"] * 48, [True] * 48, N)
    assert out[47] == (47, 49)
    assert out[30] == ()
    assert candidate_limit(N, 47) == 71 and candidate_limit(N, 10) == 36


def test_an_in_phase_row_above_the_anti_phase_branch_is_not_on_its_branch(ring_same, ring_opposite):
    """24 points, the ring's in-phase branch n = 0 … 24 (ζ = 0.02) and its anti-phase branch
    n = 0 … 47, and one band-top row the alias walk read as the in-phase n = 25 at 1,323.3 Hz
    (as in the matrix's 24-point 5,120 Hz combination at seed + 2000). The in-phase mode of
    an order is the smaller root of its two-degree-of-freedom system: n = 25's lies below the
    anti-phase n = 25 (the ring's, 785 Hz), so the row is no point of the in-phase branch.
    Taken as its last step it lifted the branch's continuation off the crowd (n = 19's alias
    29 within 2ζf by the truth): the crowd flags are those of the table without the row (the
    row still holds its order 25, no candidate of another row then)."""
    from tiremodal_cli.modal.crowds import crowds
    N = 24
    assert ring_same[25] < ring_opposite[25] < 1323.3
    assert abs(ring_same[29] - ring_same[19]) < 2 * 0.02 * ring_same[19]
    ns = list(range(25)) + list(range(48))
    br = ["same"] * 25 + ["opposite"] * 48
    f = [ring_same[n] for n in range(25)] + [ring_opposite[n] for n in range(48)]
    n_sp = [min(n % N, N - n % N) for n in ns]
    base = crowds(f, [0.02] * len(f), ns, n_sp, br, [True] * len(f), N)
    out = crowds(f + [1323.3], [0.02] * (len(f) + 1), ns + [25], n_sp + [1], br + ["same"], [True] * (len(f) + 1), N)
    assert 29 in base[19] and 29 in out[19]
    assert [bool(c) for c in out[:len(f)]] == [bool(c) for c in base]


def test_a_pole_broadened_by_its_alias_s_flank_is_no_crowd_by_its_own_damping(ring_same):
    """34 points, the ring's in-phase branch n = 0 … 17 (ζ = 0.02, every mode clear). By the
    truth n = 11 (159.41 Hz) is no crowd: its alias 34 − 11 = 23 lies 7.06 Hz above it,
    outside 2ζf = 6.38 Hz, and n = 12 is one (its alias 22 lies 5.19 Hz off, inside 6.45 Hz).
    The matrix's 5 % noise test estimated n = 11 at ζ = 0.0224 — a pole partly blending the
    flank of a neighbour it does not resolve is broader than the mode — which put the
    extrapolated n = 23 inside 2ζf. The test's bandwidth takes the lesser of the mode's
    damping and the median over its branch's clear modes: n = 11 stays no crowd at ζ =
    0.0224, and n = 12 stays a crowd at the same inflated damping."""
    from tiremodal_cli.modal.crowds import crowds
    N = 34
    assert ring_same[23] - ring_same[11] > 2 * 0.02 * ring_same[11]
    assert ring_same[22] - ring_same[12] < 2 * 0.02 * ring_same[12]
    ns = list(range(18))
    f = [ring_same[n] for n in ns]
    z = [0.02] * 18
    z[11] = z[12] = 0.0224
    out = crowds(f, z, ns, ns, ["same"] * 18, [True] * 18, N)
    assert out[11] == ()
    assert out[12] == (12, 22)


def _anti_phase(ring: RingParameters, f_max_hz: float) -> dict:
    """{n: f (Hz)} of a finite-element ring's anti-phase branch (its lowest mode of each order)."""
    from tiremodal_cli.tyre.ring import elements_for
    m = ring_modes(ring.replace(n_elements=max(ring.n_elements, elements_for(ring, f_max_hz))), f_max_hz=f_max_hz)
    out = {}
    for f, n, b in zip(m.freq_hz, m.n, m.branch):
        if b == "opposite":
            out.setdefault(int(n), float(f))
    return out


@pytest.fixture(scope="module")
def car_opposite():
    """The passenger-car tyre's anti-phase branch (``TYRES["car"]``, no physics added): n = 0
    at 336.5 Hz, 16.8 Hz per order at n = 7 and 73 Hz at n = 14."""
    from tiremodal_cli.workflow.validation import TYRES
    return _anti_phase(TYRES["car"].ring, 800.0)


@pytest.mark.parametrize("tyre, variant", [("car", "none"), ("car", "timoshenko"), ("car", "tangential"),
                                           ("gl073a", "timoshenko")])
def test_the_rising_steps_keep_every_true_order_of_the_anti_phase_branch(tyre, variant):
    """The rule's false alarms on the physics: every order of the finite-element ring's
    anti-phase branch stays a point of the dispersion — the Timoshenko tread's declining
    steps (3 % per order) and the tangential stiffness's fall of half a step at n = 3 → 4
    included."""
    from tiremodal_cli.modal.crowds import _off_the_rising_steps
    from tiremodal_cli.workflow.validation import TYRES
    t = TYRES[tyre]
    pts = _anti_phase(t.ring.replace(**t.ring_variants[variant]), 1300.0)
    assert len(pts) >= 15
    assert _off_the_rising_steps(pts, "opposite", {n: 0.0 for n in pts}) == pts  # even with no tolerance


def test_a_copy_read_high_above_the_band_top_order_makes_no_false_crowd(car_opposite):
    """The car tyre at 1,024 Hz on 34 points: its anti-phase branch n = 0 … 7 in the band
    (377.9 Hz the top), ζ = 0.02, and a copy of n = 7 one line (1.1 Hz) above it read n = 16
    (the matrix's car test). By the truth n = 7 is no crowd: its aliases n = 27 and 41 lie
    hundreds of hertz above. Taken as a point of the branch, the copy continued it at 0.12 Hz
    per order and put n = 27 and 41 inside n = 7's 15 Hz bandwidth."""
    from tiremodal_cli.modal.crowds import crowds
    N = 34
    ns = list(range(8))
    f = [car_opposite[n] for n in ns]
    assert car_opposite[14] - car_opposite[7] > 2 * 0.02 * car_opposite[7]  # n = 27, 41 higher still
    base = crowds(f, [0.02] * 8, ns, ns, ["opposite"] * 8, [True] * 8, N)
    out = crowds(f + [f[7] + 1.1], [0.02] * 9, ns + [16], ns + [16], ["opposite"] * 9, [True] * 9, N)
    assert base[7] == () and out[7] == ()


@pytest.mark.parametrize("n_read, f_read", [(20, 506.7), (15, 449.0)])
def test_a_row_read_high_below_its_branch_does_not_flatten_it(car_opposite, n_read, f_read):
    """The car tyre on 40 points (a row at 506.7 Hz read n = 20) and in receptance (449.0 Hz
    read n = 15): each lies below the branch's n = 14 at 728.6 Hz, and the running maximum
    made the branch flat from n = 14 on, putting n = 14 in a crowd with its aliases. Left
    out of the dispersion, the crowd flags are those of the branch alone."""
    from tiremodal_cli.modal.crowds import crowds
    N = 40
    ns = list(range(15))
    f = [car_opposite[n] for n in ns]
    base = crowds(f, [0.02] * 15, ns, ns, ["opposite"] * 15, [True] * 15, N)
    n_sp = min(n_read % N, N - n_read % N)
    out = crowds(f + [f_read], [0.02] * 16, ns + [n_read], ns + [n_sp], ["opposite"] * 16, [True] * 16, N)
    assert out[:15] == base and base[14] == ()
