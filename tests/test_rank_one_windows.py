"""The rank-one window test of benchmarks/rank_one_windows.py on FRFs made here from the
poly-reference model's definition (not from the tool's code): a weak mode beside a strong
one whose copies lie on every harmonic is recovered from a start 0.3 half-widths off, and in
white noise with no weak mode the nested test's false-alarm rate is the χ² quantile's."""

import importlib.util
import types
from pathlib import Path

import numpy as np

_spec = importlib.util.spec_from_file_location("rank_one_windows",
                                               Path(__file__).parents[1] / "benchmarks" / "rank_one_windows.py")
_mod = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_mod)

N_POINTS, F_STRONG, F_WEAK, ZETA = 12, 100.0, 103.0, 0.02  # the weak mode 1.5 half-widths above
LINE_HZ = 0.1


def _pole(f, z=ZETA):
    w = 2 * np.pi * f
    return complex(-z * w, w * np.sqrt(1 - z**2))


def _harmonic_frfs(seed, weak_amplitude, noise):
    """(n_c, n_k, K) accelerances on the grid's normalised harmonics: a strong mode on harmonic
    column 1 with copies on every column (a mass's mixing, 5 % each), a weak one on order 3's."""
    rng = np.random.default_rng(seed)
    th = 2 * np.pi * np.arange(N_POINTS) / N_POINTS
    D, names = _mod.grid_design(th)
    n_k = D.shape[1]
    freq = np.arange(80.0, 125.0, LINE_HZ)
    jw = 2j * np.pi * freq
    psi_strong = 0.05 * (rng.standard_normal(n_k) + 1j * rng.standard_normal(n_k))
    psi_strong[1] = 1.0
    psi_weak = np.array([weak_amplitude * (nm[0] == 3) for nm in names], dtype=complex)
    H = np.zeros((2, n_k, freq.size), dtype=complex)
    for s, L, psi in ((_pole(F_STRONG), np.array([1.0, 0.6j]), psi_strong),
                      (_pole(F_WEAK), np.array([0.4, 1.0]), psi_weak)):
        R = L[:, None] * psi[None, :]
        H += jw**2 * (R[:, :, None] / (jw - s) + np.conj(R)[:, :, None] / (jw - np.conj(s)))
    scale = noise * np.sqrt(np.mean(np.abs(H) ** 2))
    H += scale * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    return types.SimpleNamespace(freq_hz=freq, form="accelerance"), H, names


def test_a_weak_mode_beside_a_strong_one_with_copies_is_recovered():
    r, H, names = _harmonic_frfs(1, weak_amplitude=0.05, noise=1e-4)
    hw = ZETA * F_WEAK
    x = _mod.window_test(r, H, names, np.array([_pole(F_STRONG)]), F_WEAK + 0.3 * hw, ZETA, [3])[0]
    assert x["gain"] > 1 and x["edge"] < 0.9
    assert abs(x["f"] - F_WEAK) < 0.02 * hw  # high signal-to-noise: the fit's scatter is far below
    assert abs(x["z"] - ZETA) < 0.05 * ZETA


def test_no_weak_mode_no_false_alarm_in_white_noise():
    """α = 10⁻³ over the window's lines: ten seeded windows of pure noise beside the strong
    mode pass the proposal none of the times (expected 0.01 false alarms in all)."""
    gains = []
    for seed in range(10):
        r, H, names = _harmonic_frfs(seed, weak_amplitude=0.0, noise=1e-3)
        gains.append(_mod.window_test(r, H, names, np.array([_pole(F_STRONG)]), F_WEAK, ZETA, [3])[0]["gain"])
    assert max(gains) < 1
    assert max(gains) > 0.02  # the statistic is alive: the noise's own χ² reaches a few % of the quantile
