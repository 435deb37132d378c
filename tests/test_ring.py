"""The finite-element reference tyre (tiremodal_cli/ring.py) against classical results.

Every truth here is an analytic result from the literature or an exact limit, not the code
under test: the free thin ring (Love; Soedel 2004, §4.5), the pressurised inextensible ring
(follower pressure), the paper's closed form (MODEL.md) as a limit, the rigid-walled
acoustic annulus, a rigid body on a spring, and a point mass on a node of a mode.
"""

import numpy as np
import pytest

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.model import TyreParameters, closed_form_hz
from tiremodal_cli.tyre.ring import classical_ring_hz, ring_modes
from tiremodal_cli.tyre.ring_parameters import RING_VARIANTS, RingParameters

FREE = dict(m_s=0.0, k_r1=0.0, k_r2=0.0, tangential=True, EA=1e9)


def _first(m, n, branch=None):
    """Lowest mode of order n (and branch, when given)."""
    sel = m.n == n
    if branch is not None:
        sel &= np.array(m.branch) == branch
    assert sel.any(), f"no mode of order {n} ({branch})"
    return m.freq_hz[sel][0]


def test_free_thin_ring_against_the_classical_frequencies():
    """ω² = EI n²(n² − 1)² / (ρA R⁴ (n² + 1)) for an inextensible free ring, n = 2…10."""
    p = RingParameters(P0=0.0, **FREE)
    m = ring_modes(p, f_max_hz=200)
    ns = np.arange(2, 11)
    got = np.array([_first(m, n) for n in ns])
    np.testing.assert_allclose(got, classical_ring_hz(ns, p), rtol=2e-3)
    # each bending mode is a degenerate cos/sin pair
    for n in ns:
        f = m.freq_hz[(m.n == n) & (np.array(m.branch) != "tangential")]
        assert f.size >= 2 and abs(f[1] / f[0] - 1) < 1e-6


def test_pressurised_inextensible_ring():
    """A free ring under inflation (hoop tension T = P0 b R and follower pressure): the
    pressure adds the radial stiffness (P0 b / R)(n² − 1), so
    ω² = [EI (n² − 1)² / R⁴ + P0 b (n² − 1) / R] / (ρA (1 + 1/n²))."""
    p = RingParameters(**FREE)
    m = ring_modes(p, f_max_hz=600)
    ns = np.arange(2, 11)
    w2 = (p.EI * (ns**2 - 1) ** 2 / p.R**4 + p.P0 * p.b * (ns**2 - 1) / p.R) / (p.rhoA * (1 + 1 / ns**2))
    got = np.array([_first(m, n) for n in ns])
    np.testing.assert_allclose(got, np.sqrt(w2) / (2 * np.pi), rtol=2e-3)


def test_radial_only_limit_is_the_papers_closed_form():
    """Tangential freedoms tied, no membrane stiffness (EA = 0: with v tied, a stiff belt
    would hold w by its hoop strain w/R — the paper's beam has none), no sidewall coupling,
    clamped rim: the paper's model, K_n = EI n⁴/R⁴ + T n²/R² + k_r1, both branches, n = 1…20."""
    p = RingParameters()
    m = ring_modes(p, f_max_hz=700)
    tp = TyreParameters()
    for n in range(1, 21):
        same, opp = closed_form_hz(n, tp)
        assert _first(m, n, "same") == pytest.approx(same, rel=2e-3)
        assert _first(m, n, "opposite") == pytest.approx(opp, rel=2e-3)


@pytest.mark.parametrize("variant", ["none", "tangential"])
def test_mesh_convergence_at_the_default_mesh(variant):
    """Doubling the default mesh changes no frequency of order n ≤ 20 by 0.05 % or more."""
    p = RingParameters().replace(**RING_VARIANTS[variant])
    a = ring_modes(p, f_max_hz=320)
    b = ring_modes(p.replace(n_elements=2 * p.n_elements), f_max_hz=320)
    for n in range(0, 21):
        for br in ("same", "opposite"):
            sa = (a.n == n) & (np.array(a.branch) == br)
            sb = (b.n == n) & (np.array(b.branch) == br)
            if sa.any() and sb.any():
                assert a.freq_hz[sa][0] == pytest.approx(b.freq_hz[sb][0], rel=5e-4), (n, br)


def test_cavity_modes_of_a_rigid_walled_annulus():
    """With the tread–air coupling made negligible (a narrow wall), the cavity's modes are
    those of a closed acoustic annulus: f = n c / (2π R_c)."""
    p = RingParameters(cavity=True, b=1e-4, P0=0.0)
    m = ring_modes(p, f_max_hz=400)
    for n in (1, 2):
        f = m.freq_hz[(m.n == n) & (np.array(m.branch) == "cavity")]
        assert f.size == 2
        np.testing.assert_allclose(f, n * p.c_air / (2 * np.pi * p.cavity_radius), rtol=2e-4)


def test_rim_on_fixture_carries_the_whole_tyre_rigidly():
    """Stiff sidewalls: tyre and rim translate as one body on the fixture spring,
    f = √(k_f / (m_rim + 2πR (ρA + m_s))) / 2π."""
    p = RingParameters(tangential=True, EA=1e9, k_r1=1e10, k_r2=1e10, k_t1=1e10, k_t2=1e10,
                       sidewall_tangential=True, rim_mass=60.0, fixture_k=1e6, P0=0.0)
    m = ring_modes(p, f_max_hz=100)
    m_total = p.rim_mass + 2 * np.pi * p.R * (p.rhoA + p.m_s)
    f = np.sqrt(p.fixture_k / m_total) / (2 * np.pi)
    assert m.freq_hz[0] == pytest.approx(f, rel=1e-3)
    assert m.freq_hz[1] == pytest.approx(f, rel=1e-3)  # x and y


def test_point_mass_on_a_node_leaves_one_member_of_each_pair():
    """A point mass at θ = 0 splits each pair n: the member with a node there (sin nθ) keeps
    its frequency exactly, the other drops by the first-order amount
    Δω²/ω² ≈ −m w(0)² (unit modal mass)."""
    base = ring_modes(RingParameters(), f_max_hz=200)
    mass = 0.3
    loaded = ring_modes(RingParameters(masses=((0.0, mass),)), f_max_hz=200)
    from tiremodal_cli.tyre.ring import ring_observation

    for n in (2, 3, 4):
        sel_b = np.flatnonzero((base.n == n) & (np.array(base.branch) == "same"))
        f0 = base.freq_hz[sel_b[0]]
        sel = np.flatnonzero((loaded.n == n) & (np.array(loaded.branch) == "same"))
        f = np.sort(loaded.freq_hz[sel[:2]])
        assert f[1] == pytest.approx(f0, rel=1e-6)  # the sin member (rounding: ~1e-9)
        cos_mode = sel_b[0] if base.harmonic[sel_b[0]] == "cos" else sel_b[1]
        w0 = ring_observation(base, "tread", 0.0) @ base.shapes[cos_mode]
        expect = f0 * np.sqrt(1 - mass * w0**2)
        assert f[0] == pytest.approx(expect, rel=0.1 * (1 - expect / f0))


def test_bad_parameters_are_refused():
    with pytest.raises(ParameterError, match="k_r1"):
        RingParameters(k_r1=-1.0)
    with pytest.raises(ParameterError, match="unknown ring parameter 'kr1'"):
        RingParameters.from_mapping({"kr1": 1.0})
    with pytest.raises(ParameterError, match="tangential"):
        RingParameters.from_mapping({"tangential": "yes"})
    with pytest.raises(ParameterError, match="n_elements"):
        RingParameters(n_elements=5)
