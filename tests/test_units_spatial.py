"""Direct tests of the circumferential decomposition (:mod:`tiremodal_cli.modal.spatial`).

The truths are those of discrete Fourier analysis, not of the code: harmonics of different
order are orthogonal on an equally spaced grid; a shape cos(nθ + φ) = cos φ cos nθ − sin φ
sin nθ is fitted exactly by its own order whatever the grid, the order of the points or the
direction of the angles; on N equally spaced points the orders N − n and N + n take the
same values as n (aliasing); and on a uniform grid the harmonics up to ⌊N/2⌋ span every
function of the points (the DFT is invertible).
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.modal.spatial import decompose, harmonic_design, max_order


def _uniform(n_p, offset=0.0):
    return offset + 2 * np.pi * np.arange(n_p) / n_p


def _share(groups, n_c, n_p):
    """Each order's part of the physical FRFs: (n_c, n_p, n_f) arrays, Σ_n back_n @ rows_n."""
    return {n: (back @ rows).reshape(n_c, n_p, -1) for n, (rows, back) in groups.items()}


def _order_signal(th, n, phi, amp):
    """(1, n_p, n_f) FRF whose every line has the spatial pattern cos(nθ + φ)."""
    return (np.cos(n * th + phi)[None, :, None] * amp[None, None, :])


def test_max_order_is_nyquist_of_the_grid():
    for n_p, top in ((3, 1), (4, 2), (7, 3), (12, 6), (13, 6)):
        assert max_order(n_p) == top


@pytest.mark.parametrize("n", [0, 1, 2, 3, 4, 5, 6])
def test_a_pure_order_on_a_uniform_grid_falls_in_its_own_group(n):
    """cos(nθ + φ) on 12 equally spaced points: orthogonality of the discrete harmonics
    puts all of it in order n and nothing in any other."""
    rng = np.random.default_rng(100 + n)
    n_p = 12
    th = _uniform(n_p)
    amp = rng.normal(size=5) + 1j * rng.normal(size=5)
    phi = 0.0 if n in (0, n_p // 2) else 0.7  # at n = 0 and N/2 the sine is zero on the grid
    H = _order_signal(th, n, phi, amp)
    parts = _share(decompose(H, th), 1, n_p)
    assert np.allclose(parts[n], H, atol=1e-12)
    for m, part in parts.items():
        if m != n:
            assert np.max(np.abs(part)) < 1e-12, m


@pytest.mark.parametrize("n_p", [7, 12])
def test_coefficients_are_the_cosine_and_sine_amplitudes(n_p):
    """cos(3θ + φ) = cos φ·cos 3θ − sin φ·sin 3θ: the order-3 rows are (cos φ, −sin φ)·a."""
    th = _uniform(n_p, offset=0.3)
    phi = 1.1
    amp = np.array([2.0 - 1.0j, 0.5 + 0.25j])
    rows, _ = decompose(_order_signal(th, 3, phi, amp), th)[3]
    assert np.allclose(rows[0], np.cos(phi) * amp, atol=1e-12)
    assert np.allclose(rows[1], -np.sin(phi) * amp, atol=1e-12)


@pytest.mark.parametrize("n, alias", [(7, 5), (9, 3), (10, 2), (13, 1), (15, 3), (24, 0)])
def test_orders_above_half_the_grid_alias_to_n_minus_or_plus_N(n, alias):
    """On N = 12 equally spaced points cos(nθ_k) = cos((N − n)θ_k) = cos((n − N)θ_k):
    sampling theory says order n is seen as |n mod N| folded to ≤ N/2."""
    n_p = 12
    th = _uniform(n_p)
    H = _order_signal(th, n, 0.4 if alias not in (0, 6) else 0.0, np.ones(3, dtype=complex))
    parts = _share(decompose(H, th), 1, n_p)
    assert np.allclose(parts[alias], H, atol=1e-12)
    assert sum(np.max(np.abs(p)) for m, p in parts.items() if m != alias) < 1e-11


def test_a_sum_of_two_orders_is_split():
    rng = np.random.default_rng(7)
    n_p = 16
    th = _uniform(n_p, offset=0.05)
    a, b = rng.normal(size=(2, 4)) + 1j * rng.normal(size=(2, 4))
    Ha, Hb = _order_signal(th, 2, 0.3, a), _order_signal(th, 5, -1.2, b)
    parts = _share(decompose(Ha + Hb, th), 1, n_p)
    assert np.allclose(parts[2], Ha, atol=1e-12)
    assert np.allclose(parts[5], Hb, atol=1e-12)
    assert all(np.max(np.abs(p)) < 1e-12 for m, p in parts.items() if m not in (2, 5))


def test_unequal_spacing_missing_points_rolled_and_decreasing_angles():
    """Least squares recovers cos φ·a, −sin φ·a of an order ≤ the fitted top order exactly on
    any grid that resolves it: unequally spaced (points missing), the points listed from any
    start, or the angles decreasing (the sensor walking the other way round)."""
    rng = np.random.default_rng(3)
    th0 = np.sort(rng.uniform(0, 2 * np.pi, 10))  # 10 unequal points: top order fitted is 4
    n, phi = 2, -0.8
    amp = rng.normal(size=3) + 1j * rng.normal(size=3)
    for th in (th0, np.roll(th0, 4), th0[::-1], np.mod(-th0, 2 * np.pi) + 2 * np.pi):
        H = _order_signal(th, n, phi, amp)
        groups = decompose(H, th)
        rows, _ = groups[n]
        assert np.allclose(rows[0], np.cos(phi) * amp, atol=1e-10)
        assert np.allclose(rows[1], -np.sin(phi) * amp, atol=1e-10)
        parts = _share(groups, 1, th.size)
        assert np.allclose(parts[n], H, atol=1e-10)
        assert all(np.max(np.abs(p)) < 1e-10 for m, p in parts.items() if m != n)


def test_uniform_grid_reconstructs_any_data_per_channel():
    """On a uniform grid the harmonics up to ⌊N/2⌋ are a basis (the DFT is invertible): the
    groups add back to any H, every channel kept apart."""
    rng = np.random.default_rng(11)
    for n_p in (8, 9):
        th = _uniform(n_p)
        H = rng.normal(size=(3, n_p, 6)) + 1j * rng.normal(size=(3, n_p, 6))
        total = sum(_share(decompose(H, th), 3, n_p).values())
        assert np.allclose(total, H, atol=1e-12)


def test_the_grid_nyquist_sine_is_left_out_and_columns_are_square_on_a_uniform_grid():
    """sin(Nθ/2) vanishes at θ_k = 2πk/N: N columns remain for N points (even N)."""
    D, names = harmonic_design(_uniform(12), 6)
    assert (6, "sin") not in names and (6, "cos") in names
    assert D.shape == (12, 12)
    assert np.linalg.matrix_rank(D) == 12


def test_fewer_than_three_points_is_refused():
    with pytest.raises(DataFormatError, match="≥ 3 points"):
        decompose(np.ones((1, 2, 4), complex), _uniform(2))


def test_uniform_grid_from_any_start_reconstructs_any_data():
    """The DFT's completeness does not depend on where the first point is: 12 equally
    spaced points from 0.2 rad span every function of the points, order 6 included."""
    rng = np.random.default_rng(12)
    th = _uniform(12, offset=0.2)
    H = rng.normal(size=(2, 12, 3)) + 1j * rng.normal(size=(2, 12, 3))
    total = sum(_share(decompose(H, th), 2, 12).values())
    assert np.allclose(total, H, atol=1e-12)


def test_grid_top_order_on_a_uniform_grid_from_any_start():
    th = _uniform(12, offset=0.2)
    H = _order_signal(th, 6, 0.0, np.ones(2, dtype=complex))
    groups = decompose(H, th)
    assert 6 in groups
    assert np.allclose(_share(groups, 1, 12)[6], H, atol=1e-12)
