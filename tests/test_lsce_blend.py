"""A broad pole standing for two modes, resolved by the sweep at twice the order
(:func:`tiremodal_cli.modal.rescue.split_at_top`, :func:`~tiremodal_cli.modal.rescue.without_blends`,
:func:`~tiremodal_cli.modal.rescue.parts_kept`).

Truths used: stabilization diagrams written here — a blend's cluster as the held-out 36-point
sidewall-shear test showed it (one pole at 95.45 Hz, ζ 4.8 %, stable over orders 9–21; at the
sweep's top order 30 two narrower tracks at 90.1 and 98.4 Hz, ζ 3.4 and 2.7 %), and the
diagrams that must not be read so: a cluster that reaches the top order, tracks on one side
only, tracks broader than the cluster, poles new at the top order, poles of modes already
found, a cluster at the band's edge, a band the higher order fills with more than two poles.
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.modal.rescue import parts_kept, split_at_top, without_blends
from tiremodal_cli.modal.stabilization import Cluster, Diagram, StablePole

F = np.arange(34.0, 1250.0, 1.0)  # 1 Hz lines


def _pole(f0, zeta):
    return complex(-zeta * 2 * np.pi * f0, 2 * np.pi * f0 * np.sqrt(1 - zeta**2))


def _p(order, f0, zeta, status="stable"):
    return StablePole(order, _pole(f0, zeta), f0, zeta, np.zeros(0, complex), status)


def _cluster(f0, zeta, orders, adopted=True):
    members = [_p(o, f0, zeta) for o in orders]
    return Cluster(members, set(orders), adopted, "stable", members[len(members) // 2])


def _diagram(clusters, extra):
    return Diagram([m for c in clusters for m in c.members] + extra, clusters, list(range(1, 31)))


def _top(lo=(90.1, 0.034), hi=(98.4, 0.027), status="fv"):
    return [_p(29, lo[0] - 0.4, lo[1], status), _p(30, lo[0], lo[1], status),
            _p(29, hi[0] + 0.1, hi[1], status), _p(30, hi[0], hi[1], status)]


def test_a_cluster_the_top_order_splits_in_two_is_a_blend_band():
    """The held-out blend: one band, one bandwidth 2ζf about the cluster."""
    blend = _cluster(95.45, 0.048, range(9, 22))
    bands = split_at_top(_diagram([blend], _top()), F)
    assert len(bands) == 1
    lo, hi = bands[0]
    assert np.isclose(lo, 95.45 * (1 - 2 * 0.048)) and np.isclose(hi, 95.45 * (1 + 2 * 0.048))


def test_diagrams_that_are_no_blend():
    """No band: the cluster reaches the top order; tracks on one side only; tracks broader
    than the cluster; poles new at the top order (no track); the tracks are modes found
    already; the cluster's bandwidth crosses the band's edge."""
    blend = _cluster(95.45, 0.048, range(9, 22))
    assert split_at_top(_diagram([_cluster(95.45, 0.048, range(9, 31))], _top()), F) == []
    assert split_at_top(_diagram([blend], _top(hi=(94.0, 0.027))), F) == []
    assert split_at_top(_diagram([blend], _top(lo=(90.1, 0.06), hi=(98.4, 0.06))), F) == []
    assert split_at_top(_diagram([blend], _top(status="new")), F) == []
    found = [_cluster(90.1, 0.034, range(20, 31)), _cluster(98.4, 0.027, range(20, 31))]
    assert split_at_top(_diagram([blend] + found, []), F) == []
    assert split_at_top(_diagram([blend], _top()), np.arange(96.0, 1250.0, 1.0)) == []


def _rescued(parts):
    """A diagram whose first cluster is the blend and whose rescued clusters are ``parts``."""
    blend = _cluster(95.45, 0.048, range(9, 22))
    other = _cluster(300.0, 0.02, range(5, 31))
    new = [_cluster(f, z, range(30, 61)) for f, z in parts]
    return _diagram([blend, other] + new, []), blend


def test_two_narrower_parts_either_side_set_the_blend_aside_without_changing_the_given_diagram():
    d, blend = _rescued([(90.36, 0.02), (98.32, 0.02)])
    band = (95.45 * (1 - 0.096), 95.45 * (1 + 0.096))
    out, resolved = without_blends(d, [band], 1.0, 2)
    assert [round(c.freq_hz, 2) for c in out.selected()] == [90.36, 98.32, 300.0]
    assert blend.adopted and "blend" not in blend.reason  # the input diagram is not modified
    assert len(resolved) == 1 and np.isclose(resolved[0][0], 95.45)


def test_bands_the_higher_order_does_not_resolve_into_two_stay_as_they_were():
    """Three parts (a crowd, leaks, noise), one side only, a part broader than the blend, a
    part within a line of it, a narrow part whose half-power band lies apart from the
    blend's (8.05 Hz off against half-widths of 4.58 and 0.31 Hz): no blend set aside (None)."""
    band = [(86.3, 104.6)]
    for parts in ([(88.0, 0.02), (92.0, 0.02), (99.0, 0.02)], [(90.36, 0.02), (93.0, 0.02)],
                  [(90.36, 0.02), (98.32, 0.06)], [(90.36, 0.02), (96.0, 0.02)], [(90.36, 0.02), (103.5, 0.003)]):
        d, _ = _rescued(parts)
        assert without_blends(d, band, 1.0, 2) is None


def test_the_blend_stands_unless_the_group_fit_keeps_a_part_on_each_side():
    resolved = [(95.45, [_pole(90.36, 0.02), _pole(98.32, 0.02)])]
    assert parts_kept(resolved, [_pole(90.36, 0.02), _pole(98.32, 0.02), _pole(300.0, 0.02)], 1.0)
    assert not parts_kept(resolved, [_pole(98.32, 0.02), _pole(300.0, 0.02)], 1.0)
