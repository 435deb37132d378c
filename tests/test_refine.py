"""The variable-projection refinement of a group's poles (modal/refine.py), on analytic sums
of modes with known poles and seeded noise."""

import numpy as np
import pytest

from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import lsfd, synthesize
from tiremodal_cli.modal.refine import MAX_SHIFT_HALF_WIDTHS, overlapping_sets, refine_poles

FREQ = np.arange(50.0, 450.0, 0.5)  # Hz, 0.5 Hz lines


def _pole(f_hz, zeta):
    wn = 2 * np.pi * f_hz
    return -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)


def _test_data(f_true, zeta, n_rows=6, noise=0.02, seed=0, L=None):
    """Rows (n_rows, K) of accelerance FRFs of the modes, with complex Gaussian noise of
    ``noise`` × the rows' RMS; with ``L`` ((m, 2)) the rows are two references' (cos,
    sin: harmonic-major) with residues ψ_c L_h."""
    rng = np.random.default_rng(seed)
    s = np.array([_pole(f, z) for f, z in zip(f_true, zeta)])
    m = s.size
    if L is None:
        R = (rng.normal(size=(n_rows, m)) + 1j * rng.normal(size=(n_rows, m))) * np.abs(s.real)
    else:
        psi = rng.normal(size=(n_rows // 2, m)) * np.abs(s.real)
        R = np.concatenate([psi * L[:, 0], psi * L[:, 1]], axis=0)
    H = synthesize(FREQ, R, s)
    rms = np.sqrt(np.mean(np.abs(H) ** 2))
    H = H + noise * rms * (rng.normal(size=H.shape) + 1j * rng.normal(size=H.shape)) / np.sqrt(2)
    return H, s


def _biased(s, shift_half_widths):
    """The poles moved by the given shifts in half-power half-widths (an estimator's bias)."""
    return s + 1j * np.abs(s.real) * np.asarray(shift_half_widths)


def _error_half_widths(s_est, s_true):
    f_e, _ = poles_to_modal(s_est)
    f_t, z_t = poles_to_modal(s_true)
    return np.abs(f_e - f_t) / (z_t * f_t)


def _refined(H, s0, L=None):
    fit = lsfd(FREQ, H, s0) if L is None else None
    synth = fit.synthesis if fit is not None else _poly_synthesis(H, s0, L)
    return refine_poles(FREQ, H, synth, s0, L)


def _poly_synthesis(H, s, L):
    from tiremodal_cli.modal.lsfd import lsfd_participation
    n_c = H.shape[0] // 2
    Y = H.reshape(2, n_c, -1).transpose(1, 0, 2)
    return lsfd_participation(FREQ, Y, s, L)[1].transpose(1, 0, 2).reshape(2 * n_c, -1)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_biased_poles_move_to_the_truth(seed):
    """Three separate modes, each estimated 0.3 half-widths off (the matrix's "biased"
    modes): the refined frequencies lie within 0.05 half-widths of the truth (the noise's
    scatter at 2 % noise on six rows is ~0.01), closer than the start."""
    f_true, zeta = [120.0, 230.0, 340.0], [0.02, 0.03, 0.025]
    H, s = _test_data(f_true, zeta, seed=seed)
    s0 = _biased(s, [0.3, -0.3, 0.3])
    s1 = _refined(H, s0)
    e0, e1 = _error_half_widths(s0, s), _error_half_widths(s1, s)
    assert np.all(e1 < 0.05), e1
    assert np.all(e1 < e0)
    _, z1 = poles_to_modal(s1)
    assert np.allclose(z1, zeta, rtol=0.05)


def test_poly_reference_poles_refined_with_their_participation():
    """A cos/sin group (two references, residues ψ L): the same, with L held fixed."""
    f_true, zeta = [150.0, 300.0], [0.025, 0.03]
    L = np.array([[1.0, 0.4], [0.3, 1.0]], dtype=complex)
    H, s = _test_data(f_true, zeta, n_rows=8, L=L, seed=3)
    s0 = _biased(s, [-0.3, 0.3])
    e1 = _error_half_widths(_refined(H, s0, L), s)
    assert np.all(e1 < 0.05), e1


@pytest.mark.parametrize("bandwidths", [1.5, 0.75])
def test_two_close_modes_both_kept_and_refined(bandwidths):
    """Two modes ``bandwidths`` half-power bandwidths (2 ζ f) apart, both started 0.3
    half-widths off towards each other: both are kept, in their order, each nearer its own
    truth (at 0.75 bandwidths their bands overlap and they are fitted jointly)."""
    zeta, f1 = 0.02, 200.0
    f2 = f1 * (1 + 2 * zeta * bandwidths)
    H, s = _test_data([f1, f2], [zeta, zeta], seed=4)
    s0 = _biased(s, [0.3, -0.3])
    fn0 = poles_to_modal(s0)[0]
    assert len(overlapping_sets(fn0, zeta * fn0)) == (2 if bandwidths > 1 else 1)
    s1 = _refined(H, s0)
    assert s1.size == 2 and poles_to_modal(s1)[0][0] < poles_to_modal(s1)[0][1]
    e0, e1 = _error_half_widths(s0, s), _error_half_widths(s1, s)
    assert np.all(e1 < e0) and np.all(e1 < 0.05), (e0, e1)


def test_no_jump_onto_another_mode():
    """A pole whose best fit lies beyond its half-power band (here a pole 1.6 half-widths
    below a mode, with that mode's own pole absent) is not moved there: the refinement's
    minimum sits on the box's edge and the original pole is kept."""
    H, s = _test_data([200.0], [0.02], seed=5)
    s0 = _biased(s, [-(MAX_SHIFT_HALF_WIDTHS + 0.6)])
    s1 = _refined(H, s0)
    assert s1[0] == s0[0]

