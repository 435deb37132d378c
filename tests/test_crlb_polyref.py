"""The poly-reference Cramér–Rao bound (benchmarks/crlb_polyref.py) against its definition: the
spread of a maximum-likelihood estimator over noise realisations (Monte Carlo, seeded),
which attains the bound at high signal-to-noise; and the classical limits of what the
circumferential decomposition can and cannot resolve."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import least_squares

_spec = importlib.util.spec_from_file_location("crlb_polyref",
                                               Path(__file__).parents[1] / "benchmarks" / "crlb_polyref.py")
_mod = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_mod)
frequency_bounds, harmonic_basis = _mod.frequency_bounds, _mod.harmonic_basis

TRIALS = 300  # the spread's relative standard error is 1/√(2·300) = 4 %


def _poles(fn, zeta):
    wn = 2 * np.pi * np.asarray(fn)
    zeta = np.asarray(zeta)
    return -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)


def _accelerance(f, lam, L, P):
    """H_cp(f) = −ω² Σ_r [l_rc ψ_rp / (iω − λ_r) + c.c.], (n_ch, n_p, K)."""
    w, jw = -(2 * np.pi * f) ** 2, 2j * np.pi * f
    a = w[:, None] / (jw[:, None] - lam[None])
    b = w[:, None] / (jw[:, None] - np.conj(lam)[None])
    R = L[:, :, None] * P[:, None, :]
    return np.einsum("mcp,km->cpk", R, a) + np.einsum("mcp,km->cpk", np.conj(R), b)


def _ml_spread(f, lam, sig, unpack, x0, seed):
    """Relative std of the ML estimates of Im λ over TRIALS noise realisations."""
    rng = np.random.default_rng(seed)
    H0 = _accelerance(f, lam, *unpack(x0)[1:])

    def res(x, Y):
        lam_, L_, P_ = unpack(x)
        r = (_accelerance(f, lam_, L_, P_) - Y) / sig
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    est = []
    for _ in range(TRIALS):
        noise = (rng.standard_normal(H0.shape) + 1j * rng.standard_normal(H0.shape)) / np.sqrt(2)
        sol = least_squares(res, x0, args=(H0 + sig * noise,), x_scale=np.abs(x0) + 1e-3, method="lm")
        est.append(unpack(sol.x)[0].imag)
    return np.std(est, axis=0) / lam.imag


def test_bound_is_the_spread_of_maximum_likelihood_for_two_close_modes():
    """Two modes 1.1 half-power bandwidths apart, two channels, four points, free complex
    shapes and participations, a noise level rising across the band: the ML estimator's
    spread of each damped frequency is the bound (within the Monte Carlo's error)."""
    f = np.arange(95.25, 106.3, 0.25)  # exactly the lines of both poles' windows
    lam = _poles([99.0, 101.5], [0.01, 0.012])
    L = np.array([[1.0, 0.6 + 0.2j], [0.4, -0.9 + 0.1j]])
    P = np.array([[1, 0.5, -0.3, 0.8], [0.2, -1, 0.7, 0.5]]) * (1 + 0.3j)
    scale = np.array([2e3, 3e3])
    shape = 1 + 0.5 * (f - 95) / 11
    sig = scale[:, None, None] * shape[None, None, :]

    def unpack(x):  # poles, the second channel's participations (the first held), shapes
        L_ = L.copy()
        L_[:, 1] = x[4:6] + 1j * x[6:8]
        return x[0:2] + 1j * x[2:4], L_, (x[8:16] + 1j * x[16:24]).reshape(2, 4)

    x0 = np.concatenate([lam.real, lam.imag, L[:, 1].real, L[:, 1].imag, P.real.ravel(), P.imag.ravel()])
    spread = _ml_spread(f, lam, sig, unpack, x0, seed=11)
    bound = frequency_bounds(f, lam, L, P, scale[:, None] * shape[None, :])
    assert np.all(spread / bound > 0.85) and np.all(spread / bound < 1.15), (spread, bound)
    # a wider window sees more lines: the bound can only fall
    wide = np.arange(80.0, 120.0, 0.25)
    assert np.all(frequency_bounds(wide, lam, L, P, scale[:, None] * np.interp(wide, f, shape)[None, :])
                  <= bound * (1 + 1e-9))


def test_bound_with_harmonic_shapes_is_the_spread_of_maximum_likelihood():
    """Orders 2 and 3 on 12 equispaced points, 0.2 bandwidths apart, one channel: with the
    shapes known to be one harmonic each, the ML estimator of (poles, the harmonic's
    complex amplitude) spreads as the bound says."""
    th = 2 * np.pi * np.arange(12) / 12
    f = np.arange(190.0, 210.0, 0.25)
    lam = _poles([200.0, 200.8], [0.01, 0.01])
    L = np.ones((2, 1), complex)
    P = np.array([np.cos(2 * th), np.cos(3 * th)]) * np.array([[1 + 0.5j], [0.7 - 0.2j]])
    scale, shape = np.array([3e3]), np.ones_like(f)
    sig = scale[0]
    Q = harmonic_basis(th)
    k = [int(np.argmax(np.abs(P[0] @ Q))), int(np.argmax(np.abs(P[1] @ Q)))]

    def unpack(x):
        c = x[4:6] + 1j * x[6:8]
        return x[0:2] + 1j * x[2:4], L, c[:, None] * Q[:, k].T

    c0 = np.array([(P[0] @ Q)[k[0]], (P[1] @ Q)[k[1]]])
    x0 = np.concatenate([lam.real, lam.imag, c0.real, c0.imag])
    spread = _ml_spread(f, lam, sig, unpack, x0, seed=12)
    bound = frequency_bounds(f, lam, L, P, scale[:, None] * shape[None, :], point_angle_rad=th)
    assert np.all(spread / bound > 0.85) and np.all(spread / bound < 1.15), (spread, bound)


@pytest.mark.parametrize("orders, resolvable", [((2, 3), True), ((2, 2 + 12), False)])
def test_orders_are_told_apart_by_the_points_but_aliases_are_not(orders, resolvable):
    """Two modes 0.1 bandwidth apart, the same participation: of different orders the
    circumferential decomposition separates them (the bound is that of a lone mode, well
    under 0.1 %); of one order and its alias on 12 points (n and n + 12) nothing does."""
    th = 2 * np.pi * np.arange(12) / 12
    f = np.arange(180.0, 220.0, 0.25)
    lam = _poles([200.0, 200.4], [0.01, 0.01])
    L = np.ones((2, 1), complex)
    P = np.array([np.cos(orders[0] * th), 0.8 * np.cos(orders[1] * th)]) / (2j * lam.imag[:, None])
    peak = 200.0**2 * 4 * np.pi**2 / (2 * 0.01 * 2 * np.pi * 200.0 * 2 * np.pi * 200.0)  # |w| / ζω · 1/(2ω_d)
    scale = np.array([peak / 100.0])  # peak signal-to-noise ≈ 100 at the best point
    noise = scale[:, None] * np.ones_like(f)[None, :]
    bound = frequency_bounds(f, lam, L, P, noise, point_angle_rad=th)
    lone = frequency_bounds(f, lam[:1], L[:1], P[:1], noise, point_angle_rad=th)
    if resolvable:
        assert bound[0] == pytest.approx(lone[0], rel=0.05)
    else:
        assert bound[0] > 20 * lone[0]
