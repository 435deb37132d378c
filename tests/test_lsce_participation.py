"""Poly-reference LSCE returns each mode's participation factor (the truth is built in).

Impulse responses of four modes seen from two references, h_o(m) = Σ_r a_or z_r^m L_r,
with L_r chosen (not taken from the code); the sweep must return, at each true pole, a
participation parallel to L_r (|cos| = 1: a unit vector, any phase), and the poles
themselves to machine precision. A split pair (two modes 0.4 % apart, independent L) must
keep its two participations apart.
"""

import numpy as np

from tiremodal_cli.modal.lsce import sweep_poly


def _irf(rng, f_hz, zeta, L, n_out=12, n_samp=512, dt=1 / 1024):
    s = -zeta * 2 * np.pi * f_hz + 1j * 2 * np.pi * f_hz * np.sqrt(1 - zeta**2)
    z = np.exp(s * dt)
    a = rng.standard_normal((n_out, len(f_hz))) + 1j * rng.standard_normal((n_out, len(f_hz)))
    m = np.arange(n_samp)
    h = np.zeros((n_out, L.shape[1], n_samp), dtype=complex)
    for r in range(len(f_hz)):
        h += a[:, r, None, None] * L[r][None, :, None] * z[r] ** m[None, None, :]
    return h, s


def test_participation_factors_of_known_modes():
    rng = np.random.default_rng(7)
    f = np.array([60.0, 100.0, 100.4, 180.0])
    zeta = np.array([0.01, 0.02, 0.02, 0.015])
    L = np.array([[1.0, 0.3], [0.2, 1.0], [1.0, -0.7], [0.6, 0.6j]], dtype=complex)
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    h, s_true = _irf(rng, f, zeta, L)
    op = sweep_poly(h, [2], dt=1 / 1024, f_lo=0.0, width_hz=1024.0)[0]  # 2 orders × 2 refs = 4 poles
    assert op.participation.shape == (4, 2)
    for r in range(4):
        k = np.argmin(np.abs(op.s - s_true[r]))
        assert abs(op.s[k] - s_true[r]) < 1e-6 * abs(s_true[r])
        cos = abs(np.vdot(op.participation[k], L[r])) / np.linalg.norm(op.participation[k])
        assert cos > 1 - 1e-8, (r, cos)


def test_participation_of_true_poles_at_overspecified_orders_with_noise():
    """Orders above the modes' count (noise poles too) and 1e-4 noise: at the poles nearest
    the true ones the participation stays parallel to the true L (|cos| ≥ 0.999)."""
    rng = np.random.default_rng(11)
    f = np.array([60.0, 100.0, 180.0])
    L = rng.standard_normal((3, 2)) + 1j * rng.standard_normal((3, 2))
    L /= np.linalg.norm(L, axis=1, keepdims=True)
    h, s_true = _irf(rng, f, np.array([0.01, 0.02, 0.015]), L)
    h = h + 1e-4 * (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape))
    for op in sweep_poly(h, [4, 7], dt=1 / 1024, f_lo=0.0, width_hz=1024.0):
        assert np.allclose(np.linalg.norm(op.participation, axis=1), 1)
        for r in range(3):
            k = np.argmin(np.abs(op.s - s_true[r]))
            assert abs(op.s[k] - s_true[r]) < 1e-4 * abs(s_true[r])
            assert abs(np.vdot(op.participation[k], L[r])) > 0.999, (op.order, r)
