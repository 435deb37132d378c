"""The tyre model against MODEL.md's closed form, the 3×3 rim problem, and each effect's physics."""

import numpy as np
import pytest
import scipy.linalg
from numpy.testing import assert_allclose

from tiremodal_cli.tyre.effects import EFFECTS
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.model import PAPER_PARAMETERS as P, closed_form_hz
from tiremodal_cli.tyre.solve import frf, solve_modes
def table(m, branch):
    """{n: frequency} of the cos members of a branch."""
    return {int(n): f for f, n, h, b in zip(m.freq_hz, m.n, m.harmonic, m.branch) if b == branch and h == "cos"}


def test_paper_example_frequencies():
    """MODEL.md: 68.1, 82.5, 98.3, 114.0 Hz (same, n = 2…5), 185.4 … 263.8 Hz (opposite, n = 2…10)."""
    f = closed_form_hz(np.arange(2, 11), P)
    assert_allclose(f[:4, 0], [68.1, 82.5, 98.3, 114.0], atol=0.05)
    assert_allclose(f[[0, -1], 1], [185.4, 263.8], atol=0.05)
    # the same-direction branch saturates towards sqrt((k_r1 + k_r2)/m_s)/2π ≈ 168 Hz
    lim = np.sqrt((P.k_r1 + P.k_r2) / P.m_s) / (2 * np.pi)
    assert 167.5 < lim < 168.0
    assert closed_form_hz(200, P)[0] < lim


def test_blocks_equal_closed_form_both_branches():
    m = solve_modes(P, n_max=30)
    same, opp = table(m, "same"), table(m, "opposite")
    ns = np.arange(2, 31)
    cf = closed_form_hz(ns, P)
    assert_allclose([same[n] for n in ns], cf[:, 0], rtol=1e-12)
    assert_allclose([opp[n] for n in ns], cf[:, 1], rtol=1e-12)
    # n = 0 uses the same 2×2 form; every n ≥ 1 has a cos and a sin member at one frequency
    assert_allclose([same[0], opp[0]], closed_form_hz(0, P), rtol=1e-12)
    for n in range(1, 31):
        assert np.sum(m.n == n) == 4


def test_n1_with_rim_is_the_3x3_eigenproblem():
    p = P.replace(m_w=250.0)
    K1 = p.EI / p.R**4 + p.P0 * p.b / p.R + p.k_r1
    M = np.diag([p.rhoA, p.m_s, p.m_w / (np.pi * p.R)])
    K = np.array([[K1, -p.k_r1, 0], [-p.k_r1, p.k_r1 + p.k_r2, -p.k_r2], [0, -p.k_r2, p.k_r2]])
    expect = np.sqrt(scipy.linalg.eigvalsh(K, M)) / (2 * np.pi)
    m = solve_modes(p, n_max=3)
    got = np.sort(m.freq_hz[(m.n == 1) & (np.array(m.harmonic) == "cos")])
    assert_allclose(got, expect, rtol=1e-12)
    n1 = sorted((f, b) for f, n, h, b in zip(m.freq_hz, m.n, m.harmonic, m.branch) if n == 1 and h == "cos")
    assert [b for _, b in n1] == ["rim", "same", "opposite"]
    # clamped rim is the m_w → ∞ limit
    clamped = table(solve_modes(P, n_max=2), "same")[1]
    heavy = table(solve_modes(P.replace(m_w=1e9), n_max=2), "same")[1]
    assert_allclose(heavy, clamped, rtol=1e-6)


def test_shapes_are_mass_normalised_and_frf_is_reciprocal():
    m = solve_modes(P.replace(m_w=500.0), n_max=8)
    ang = np.array([0.3, 1.1])
    H = frf(m, [40.0, 150.0], 0.02, ["tread", "tread"], ang, ang, form="receptance")
    assert_allclose(H[0, 1], H[1, 0], rtol=1e-12)
    # static check: receptance at 0 Hz of an n-symmetric structure is real and positive at the drive point
    H0 = frf(m, [0.0], 0.02, ["tread"], [0.0], [0.0], form="receptance")
    assert H0[0, 0, 0].real > 0 and abs(H0[0, 0, 0].imag) < 1e-15


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_every_effect_is_documented_with_bounds(name):
    e = EFFECTS[name]
    assert e.parameters and e.signature and e.reference
    for p in e.parameters:
        assert p.lower <= p.default <= p.upper and p.unit
    with pytest.raises(ParameterError, match="outside"):
        e.resolve({e.parameters[0].name: e.parameters[0].upper * 10 + 1})


def test_membrane_lifts_high_n_of_same_branch_only():
    base = table(solve_modes(P, n_max=10), "same")
    eff = table(solve_modes(P, n_max=10, effects={"sidewall_membrane": {"T_s": 2e4}}), "same")
    rel = {n: eff[n] / base[n] - 1 for n in range(2, 11)}
    assert rel[2] < 0.015 and rel[8] > 0.05 and rel[8] > 5 * rel[2]
    assert all(rel[n + 1] > rel[n] for n in range(2, 10))


def test_tangential_is_strongest_at_low_n():
    base = table(solve_modes(P, n_max=10), "same")
    eff = table(solve_modes(P, n_max=10, effects={"tangential": {"c_t": 1.0, "k_t": 0.0}}), "same")
    rel = {n: abs(eff[n] / base[n] - 1) for n in range(1, 11)}
    assert rel[1] > rel[2] > rel[4] > rel[8]
    # tangential inertia ρA/n² alone lowers every mode
    assert all(eff[n] < base[n] for n in range(1, 11))


def test_timoshenko_rotary_inertia_grows_with_n():
    base = table(solve_modes(P, n_max=10), "opposite")
    eff = table(solve_modes(P, n_max=10, effects={"timoshenko": {"rhoI": 0.01}}), "opposite")
    rel = [1 - eff[n] / base[n] for n in range(2, 11)]
    assert all(b > a for a, b in zip(rel, rel[1:])) and rel[-1] > 0.02


def test_timoshenko_at_its_null_is_the_model_it_extends():
    """ρI = 0 and a shear-rigid tread (c_s = 1/κGA = 0) are the Euler–Bernoulli model: the
    candidate is nested in the model it extends (its F-test a test of nested models). A
    finite κGA with ρI = 0 is not: shear softens the bending, increasingly with n."""
    base = solve_modes(P, n_max=40)
    null = solve_modes(P, n_max=40, effects={"timoshenko": {"rhoI": 0.0, "c_s": 0.0}})
    for b in ("same", "opposite"):
        f0, f1 = table(base, b), table(null, b)
        assert_allclose([f1[n] for n in f0], [f0[n] for n in f0], rtol=1e-9)
    shear = table(solve_modes(P, n_max=40, effects={"timoshenko": {"rhoI": 0.0, "c_s": 1e-5}}), "opposite")
    opp = table(base, "opposite")
    soft = [1 - shear[n] / opp[n] for n in (10, 20, 40)]
    assert 0 < soft[0] < soft[1] < soft[2] and soft[2] > 1e-3


def test_viscoelastic_is_self_consistent():
    beta = 0.1
    m = solve_modes(P, n_max=4, effects={"viscoelastic": {"beta": beta}})
    # each mode satisfies the eigenproblem with springs evaluated at its own frequency
    from tiremodal_cli.tyre.effects import resolve_effects
    from tiremodal_cli.tyre.model import block

    eff = resolve_effects({"viscoelastic": {"beta": beta}})
    for f, n in zip(m.freq_hz, m.n):
        b = block(int(n), P, eff, freq_hz=f)
        w2 = scipy.linalg.eigvalsh(b.K, b.M)
        assert np.min(np.abs(np.sqrt(w2) / (2 * np.pi) - f)) < 1e-9 * f


def test_added_mass_splits_pairs():
    m = solve_modes(P, n_max=12, effects={"added_mass": {"m_a": 1.0, "theta_a": 0.0}})
    base = table(solve_modes(P, n_max=12), "same")
    for n in (2, 3, 4):
        pair = np.sort(m.freq_hz[(m.n == n) & (np.array(m.branch) == "same")])
        assert pair.size == 2
        # the member with a node at the mass (sin) keeps its frequency; the other drops
        assert_allclose(pair[1], base[n], rtol=1e-9)
        assert pair[0] < base[n] * 0.995


def test_air_cavity_adds_one_mode_per_harmonic_near_fc():
    m = solve_modes(P, n_max=4, effects={"air_cavity": {"f_cavity_hz": 125.0, "gamma": 0.05}})
    cav = m.freq_hz[np.array(m.branch) == "cavity"]
    assert cav.size == 2 and np.all(np.abs(cav / 125.0 - 1) < 0.05)
    assert set(m.n[np.array(m.branch) == "cavity"]) == {1}


def test_bad_parameters():
    with pytest.raises(ParameterError, match="k_r1=-1"):
        P.replace(k_r1=-1.0)
    with pytest.raises(ParameterError, match="unknown effect"):
        solve_modes(P, effects={"nope": {}})
    with pytest.raises(ParameterError, match="n_max"):
        solve_modes(P, n_max=0)
