"""A strong pole alone in its window, refined in the FRFs (modal.refine, session 42).

Truth: an analytic modal sum (one mode, two channels) on 1 Hz lines, the mode's half-power
half-width 1.7 lines, complex Gaussian noise of known variance; the pole to refine starts
0.5 % off, as LSCE's estimate of such a mode was on the held-out ring with 1 s records.
"""

import numpy as np

from tiremodal_cli.modal.refine import _refine

F0, ZETA = 59.3, 0.028


def _pole(f, z):
    w = 2 * np.pi * f
    return complex(-z * w, w * np.sqrt(1 - z * z))


def _rows(freq, poles, residues):
    jw = 2j * np.pi * freq
    out = np.zeros((residues.shape[0], freq.size), dtype=complex)
    for s, r in zip(poles, residues.T):
        out += jw[None, :] ** 2 * (r[:, None] / (jw - s)[None, :] + np.conj(r)[:, None] / (jw - np.conj(s))[None, :])
    return out


def _case(extra: bool, seed: int = 3):
    freq = np.arange(20.0, 110.0, 1.0)
    res = np.array([[1.0 + 0.2j], [0.6 - 0.1j]])
    clean = _rows(freq, [_pole(F0, ZETA)], res)
    rng = np.random.default_rng(seed)
    sigma = 0.01 * np.abs(clean).max()
    noise = sigma * (rng.standard_normal(clean.shape) + 1j * rng.standard_normal(clean.shape)) / np.sqrt(2)
    rows = clean + noise
    if extra:  # a mode the set's model lacks, 3 half-widths above, 0.3 × as strong
        rows = rows + _rows(freq, [_pole(F0 * (1 + 3 * ZETA), ZETA)], 0.3 * res)
    return freq, rows, clean


def test_a_strong_pole_alone_comes_to_the_truth():
    """Started 0.5 % off, the refined pole is within 0.05 % of the truth and its damping
    within 5 %, over five noise draws."""
    for seed in range(5):
        freq, rows, clean = _case(False, seed)
        s0 = np.array([_pole(F0 * 1.005, ZETA * 1.3)])
        s, _ = _refine(freq, rows, clean, s0, None, "accelerance", np.array([True]), at_noise=True)
        f = s[0].imag / (2 * np.pi) / np.sqrt(1 - (s[0].real / abs(s[0])) ** 2)
        assert abs(f / F0 - 1) < 5e-4
        assert abs(-s[0].real / abs(s[0]) / ZETA - 1) < 0.05


def test_a_window_holding_a_mode_the_model_lacks_keeps_its_pole():
    """With an unmodelled mode in the window the refined residual is far above the noise:
    the pole keeps its start. Without the noise test it moves, pulled over 0.2 % below the
    truth by the mode it lacks."""
    freq, rows, clean = _case(True)
    s0 = np.array([_pole(F0 * 1.005, ZETA * 1.3)])
    s, _ = _refine(freq, rows, clean, s0, None, "accelerance", np.array([True]), at_noise=True)
    assert s[0] == s0[0]
    moved, _ = _refine(freq, rows, clean, s0, None, "accelerance", np.array([True]), at_noise=False)
    assert abs(moved[0]) / (2 * np.pi) < F0 * (1 - 2e-3)
