"""Direct tests of the stabilization diagram (:mod:`tiremodal_cli.modal.stabilization`).

Truths used: the poles of a 2-DOF mass–spring–damper are the eigenvalues of its state
matrix (computed here by scipy, not by the code under test); a physical pole stays put as
the model order rises, a computational one wanders (Peeters et al. 2004, the premise of
every stabilization diagram); the stability test's tolerances are the documented ones.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from tiremodal_cli.modal.lsce import Band, OrderPoles, poles_to_modal, principal_responses, sweep
from tiremodal_cli.modal.stabilization import StabilizationOptions, stabilize

F_LO, WIDTH = 0.0, 100.0


def _band(n_lines=256):
    f = F_LO + WIDTH * np.arange(n_lines) / n_lines
    z = np.zeros((1, n_lines), complex)
    return Band(freq_hz=f, f_lo=F_LO, width_hz=WIDTH, dt=1 / WIDTH, U=np.ones((1, 1)), prf=z, irf=z,
                singular_values=np.ones(1))


def _pole(f_hz, zeta):
    wn = 2 * np.pi * f_hz
    return complex(-zeta * wn, wn * np.sqrt(1 - zeta**2))


def _order(p, poles, shapes):
    """OrderPoles of order p with the given poles and (participation) shapes."""
    s = np.array(poles, complex)
    fn, zeta = poles_to_modal(s)
    return OrderPoles(order=p, s=s, z=np.exp(s / WIDTH), freq_hz=fn, damping_ratio=zeta,
                      participation=np.array(shapes, complex))


MODES = [(20.0, 0.02, [1.0, 0.5, 0.1]), (55.0, 0.01, [0.2, -1.0, 0.6])]


def _sweep(rng, orders, scatter=1e-4, spurious=True):
    out = []
    for p in orders:
        poles, shapes = [], []
        for f, z, v in MODES:
            poles.append(_pole(f * (1 + scatter * rng.normal()), z * (1 + scatter * rng.normal())))
            shapes.append(np.array(v) + scatter * rng.normal(size=3))
        if spurious:  # a computational pole: anywhere in the band, any shape, each order
            poles.append(_pole(rng.uniform(5, 95), rng.uniform(0.005, 0.15)))
            shapes.append(rng.normal(size=3) + 1j * rng.normal(size=3))
        out.append(_order(p, poles, shapes))
    return out


def test_repeated_poles_are_stable_and_selected_a_wandering_pole_is_not():
    rng = np.random.default_rng(2024)
    orders = list(range(4, 44, 2))
    d = stabilize(_band(), _sweep(rng, orders))
    sel = d.selected()
    assert len(sel) == 2
    for c, (f, z, v) in zip(sel, MODES):
        assert c.freq_hz == pytest.approx(f, rel=1e-3)
        assert c.damping_ratio == pytest.approx(z, rel=1e-2)
        assert len(c.members) == len(orders) - 1  # stable from the second order on
        assert c.representative.freq_hz == pytest.approx(f, rel=1e-3)
    # no adopted cluster is made of the wandering pole, and it is rarely even "stable"
    spur = [p for p in d.poles if all(abs(p.freq_hz - f) > 0.02 * f for f, _, _ in MODES)]
    assert len(spur) == len(orders)
    assert sum(p.status == "stable" for p in spur) <= 1
    assert all(not c.adopted for c in d.clusters if all(abs(c.freq_hz - f) > 0.02 * f for f, _, _ in MODES))


@pytest.mark.parametrize("df, dz, shape2, status", [
    (0.005, 0.0, [1.0, 0.5, 0.1], "stable"),   # 0.5 % < tol_freq 1 %
    (0.02, 0.0, [1.0, 0.5, 0.1], "new"),       # 2 % > tol_freq
    (0.005, 0.10, [1.0, 0.5, 0.1], "fv"),      # damping 10 % off > tol_damping 5 %
    (0.005, 0.0, [1.0, -0.5, 0.1], "fd"),      # MAC 0.36 < tol_mac 0.98
    (0.005, 0.10, [1.0, -0.5, 0.1], "f"),      # only the frequency agrees
])
def test_stability_status_follows_the_documented_tolerances(df, dz, shape2, status):
    opt = StabilizationOptions()
    a = _order(10, [_pole(30.0, 0.02)], [[1.0, 0.5, 0.1]])
    b = _order(12, [_pole(30.0 * (1 + df), 0.02 * (1 + dz))], [shape2])
    d = stabilize(_band(), [a, b], opt)
    assert [p.status for p in d.poles] == ["new", status]


def test_min_count_rejects_a_pole_stable_at_too_few_orders():
    """A pole present at only 3 of 20 orders is computational (default min_count: 15 % of
    the orders, at least 3 → 3; stable at 2 orders < 3)."""
    rng = np.random.default_rng(9)
    orders = list(range(2, 42, 2))
    ops = _sweep(rng, orders, spurious=False)
    brief = {orders[5], orders[6], orders[7]}
    ops = [_order(op.order, list(op.s) + ([_pole(80.0, 0.01)] if op.order in brief else []),
                  list(op.participation) + ([[0.0, 0.3, 1.0]] if op.order in brief else []))
           for op in ops]
    d = stabilize(_band(), ops)
    c80 = [c for c in d.clusters if abs(c.freq_hz - 80.0) < 0.8]
    assert len(c80) == 1 and not c80[0].adopted and "computational" in c80[0].reason
    assert len(d.selected()) == 2


def test_out_of_band_and_negatively_damped_poles_are_not_candidates():
    a = _order(4, [_pole(30.0, 0.02), _pole(150.0, 0.02), complex(+1.0, 2 * np.pi * 40)],
               [[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    d = stabilize(_band(), [a])
    assert [round(p.freq_hz, 6) for p in d.poles] == [30.0]


def _two_dof_frf(freq_hz):
    """Receptance of a 2-DOF chain (m, k, c) and its poles from the state matrix."""
    M = np.diag([1.0, 0.5])
    K = np.array([[3.0e4 + 2.0e4, -2.0e4], [-2.0e4, 2.0e4]])
    C = 2e-4 * K + 0.5 * M  # Rayleigh damping
    w = 2 * np.pi * freq_hz
    H = np.array([np.linalg.inv(K - wk**2 * M + 1j * wk * C) for wk in w])  # (K, 2, 2)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    lam = scipy.linalg.eigvals(A)
    return H.reshape(len(w), 4).T, lam[lam.imag > 0]


def test_two_dof_system_poles_are_recovered_through_lsce_and_stabilization():
    """FRFs of a known 2-DOF system (2 % noise on the band, seeded) → principal responses →
    LSCE sweep → stabilization: the two adopted modes are the state matrix's eigenvalues,
    frequency within 0.1 %, damping within 5 %."""
    rng = np.random.default_rng(4)
    f = np.arange(0, 64.0, 64.0 / 512)
    H, lam = _two_dof_frf(f)
    H = H + 0.002 * np.abs(H).max() * (rng.normal(size=H.shape) + 1j * rng.normal(size=H.shape))
    band = principal_responses(f, H, (2.0, 60.0))
    d = stabilize(band, sweep(band, range(4, 31, 2)))
    sel = d.selected()
    fn, zt = poles_to_modal(np.sort_complex(lam))
    order = np.argsort(fn)
    fn, zt = fn[order], zt[order]
    assert 10 < fn[0] < fn[1] < 50  # the truth is in the band (a test that can fail)
    assert len(sel) == 2
    for c, f0, z0 in zip(sel, fn, zt):
        assert c.freq_hz == pytest.approx(f0, rel=1e-3)
        assert c.damping_ratio == pytest.approx(z0, rel=0.05)


def _drifting(orders, step_rad, zeta=0.02, f_hz=40.0, seed=36):
    """A single-reference pole at ``f_hz`` over ``orders``, stable at each, whose weak shape
    component (0.35 of the other) turns by ``step_rad`` per order, as one near its noise does
    when the extra poles of each order take up the noise differently; the frequency
    scattered by 1e-4."""
    from tiremodal_cli.modal.stabilization import StablePole
    rng = np.random.default_rng(seed)
    out = []
    for k, p in enumerate(orders):
        f = f_hz * (1 + 1e-4 * rng.normal())
        out.append(StablePole(p, _pole(f, zeta), f, zeta, np.array([0.35 * np.exp(1j * step_rad * k), 1.0]), "stable"))
    return out


def test_a_pole_whose_weak_shape_component_drifts_is_one_cluster():
    """Session 36: each order's pole matches the last (MAC 0.994 ≥ tol_mac), but over ten
    orders the shape turns so far (MAC 0.68 end to end) that the clustering splits it, each
    part under the 6 orders a mode needs. One pole, never twice at an order, its clusters'
    frequencies one: joined, one cluster of all ten orders. With participation vectors
    (a poly-reference sweep) the parts stay apart: there another participation is another
    orientation, the second member of a degenerate pair."""
    from tiremodal_cli.modal.stabilization import _cluster, _joined
    opt = StabilizationOptions()
    poles = _drifting(list(range(20, 40, 2)), 0.25)
    parts = _cluster(poles, opt)
    assert len(parts) >= 2 and max(len(c.members) for c in parts) < 6
    joined = _joined(parts, opt, 0.1)  # scatter 0.004 Hz: pinned within a line of 0.1 Hz
    assert len(joined) == 1 and len(joined[0].members) == 10
    for p in poles:
        p.participation = p.shape
    assert len(_joined(_cluster(poles, opt), opt)) == len(parts)


def _cluster_of(orders, f_hz, zeta):
    from tiremodal_cli.modal.stabilization import Cluster, StablePole
    members = [StablePole(p, _pole(f, zeta), f, zeta, np.ones(2), "stable") for p, f in zip(orders, f_hz)]
    return Cluster(members=members, orders=set(orders))


@pytest.mark.parametrize("orders_b, f_b, zeta_b, line_hz, one", [
    ([30, 32, 34], [40.001, 39.999, 40.003], 0.02, 0.01, True),    # disjoint orders, overlapping poles
    ([26, 32, 34], [40.001, 39.999, 40.003], 0.02, 0.01, False),   # both at order 26: two modes
    ([30, 32, 34], [40.001, 39.999, 40.003], 0.022, 0.01, False),  # damping 10 % apart (> tol_damping)
    ([30, 32, 34], [40.006, 40.007, 40.009], 0.02, 0.01, False),   # frequencies apart: the poles tell them
    ([30, 32, 34], [40.001, 39.999, 40.003], 0.02, 0.001, False),  # scatter over a line: not pinned
])
def test_clusters_are_joined_only_when_their_poles_cannot_be_told_apart(orders_b, f_b, zeta_b, line_hz, one):
    from tiremodal_cli.modal.stabilization import _joined
    a = _cluster_of([20, 22, 24, 26], [40.0, 40.002, 39.998, 40.004], 0.02)
    b = _cluster_of(orders_b, f_b, zeta_b)
    assert len(_joined([a, b], StabilizationOptions(), line_hz)) == (1 if one else 2)
