"""Direct tests of the impact-testing windows (:mod:`tiremodal_cli.frf.windows`).

Truths used (not taken from the code): exp(−t/τ)·e^{λt} = e^{(λ − 1/τ)t}, so an exponential
window moves a pole left by exactly σ_w = 1/τ; a geometric sequence w[k] = r^k satisfies
w[k] = w[j]·w[k − j], so windowing force and response of a discrete convolution windows
the impulse response; the poles of a noise-free damped sinusoid are found exactly by a
second-order linear prediction (Prony 1795), independently of the code under test.
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.frf.windows import correct_damping, correct_poles, exponential_window, force_window

FS = 2048.0


def _prony2(x, fs):
    """Continuous-time poles of a noise-free real damped sinusoid: x[k+2] = a1 x[k+1] + a2 x[k]."""
    A = np.column_stack([x[1:-1], x[:-2]])
    a1, a2 = np.linalg.lstsq(A, x[2:], rcond=None)[0]
    z = np.roots([1.0, -a1, -a2])
    lam = fs * np.log(z.astype(complex))
    return lam[np.argmax(lam.imag)]  # the pole with ω_d > 0


def _damped(f_hz, zeta, n, fs, psi=0.3):
    wn = 2 * np.pi * f_hz
    sigma, wd = zeta * wn, wn * np.sqrt(1 - zeta**2)
    t = np.arange(n) / fs
    return np.exp(-sigma * t) * np.cos(wd * t + psi), complex(-sigma, wd)


def test_exponential_window_values_and_time_constant():
    n = 1000
    w, tau = exponential_window(n, FS, end_value=0.01)
    T = (n - 1) / FS
    assert w[0] == 1.0 and w[-1] == pytest.approx(0.01, rel=1e-12)
    assert tau == pytest.approx(T / np.log(100.0), rel=1e-12)
    # a geometric sequence: every step multiplies by exp(−1/(fs τ))
    assert np.allclose(w[1:] / w[:-1], np.exp(-1 / (FS * tau)), rtol=1e-12)
    w2, tau2 = exponential_window(n, FS, tau_s=0.05)
    assert tau2 == 0.05 and w2[int(0.05 * FS)] == pytest.approx(np.exp(-int(0.05 * FS) / FS / 0.05))


@pytest.mark.parametrize("f_hz, zeta, end", [(50.0, 0.02, 0.05), (120.0, 0.005, 0.01), (300.0, 0.002, 0.2)])
def test_window_adds_one_over_tau_and_the_correction_restores_the_damping(f_hz, zeta, end):
    """A decaying sinusoid of known f, ζ, windowed: its pole (by Prony) has moved left by
    1/τ exactly; correct_poles and correct_damping give back the known pole, f and ζ."""
    n = 2048
    x, lam_true = _damped(f_hz, zeta, n, FS)
    w, tau = exponential_window(n, FS, end_value=end)
    lam_w = _prony2(x * w, FS)
    assert lam_w.real == pytest.approx(lam_true.real - 1 / tau, rel=1e-8)
    assert lam_w.imag == pytest.approx(lam_true.imag, rel=1e-9)  # ω_d untouched
    assert correct_poles(lam_w, tau) == pytest.approx(lam_true, rel=1e-8)
    f_est, z_est = abs(lam_w) / (2 * np.pi), -lam_w.real / abs(lam_w)
    assert z_est > zeta * 1.2  # uncorrected, ζ is ≥ 20 % high: the check below can fail
    f_c, z_c = correct_damping(f_est, z_est, tau)
    assert f_c == pytest.approx(f_hz, rel=1e-8)
    assert z_c == pytest.approx(zeta, rel=1e-6)


def test_correct_damping_keeps_the_damped_frequency_and_removes_sigma():
    """σ = ζω − 1/τ and ω_d kept, vectorised; no window: unchanged."""
    f = np.array([10.0, 80.0, 200.0])
    z = np.array([0.1, 0.03, 0.01])
    tau = 0.5
    fc, zc = correct_damping(f, z, tau)
    w, wc = 2 * np.pi * f, 2 * np.pi * fc
    assert np.allclose(wc * zc, w * z - 1 / tau, rtol=1e-12)
    assert np.allclose(wc * np.sqrt(1 - zc**2), w * np.sqrt(1 - z**2), rtol=1e-12)
    f0, z0 = correct_damping(f, z, None)
    assert np.array_equal(f0, f) and np.array_equal(z0, z)
    assert np.array_equal(correct_poles([-1 + 2j], None), np.array([-1 + 2j]))


def test_windowing_force_and_response_windows_the_impulse_response():
    """y = f ∗ h; with w[k] = r^k, (w·y) = (w·f) ∗ (w·h) exactly: the FRF of the windowed
    records is the structure's with its pole moved by 1/τ (the module's premise)."""
    rng = np.random.default_rng(5)
    n = 1024
    h, lam = _damped(40.0, 0.01, n, FS, psi=-np.pi / 2)
    f = np.zeros(n)
    f[10:18] = np.sin(np.pi * np.arange(8) / 8) + 0.01 * rng.normal(size=8)
    y = np.convolve(f, h)[:n]
    w, tau = exponential_window(n, FS, end_value=0.05)
    assert np.allclose(w * y, np.convolve(w * f, w * h)[:n], atol=1e-12)
    assert _prony2(w * h, FS) == pytest.approx(lam - 1 / tau, rel=1e-8)


def _pulse_record(n=2048, start=300, width=9, noise=1e-3, seed=0, sign=1.0):
    rng = np.random.default_rng(seed)
    clean = np.zeros(n)
    clean[start:start + width] = sign * np.sin(np.pi * (np.arange(width) + 1) / (width + 1))
    return clean, clean + noise * rng.normal(size=n)


def test_force_window_keeps_the_pulse_and_zeros_the_tail():
    clean, noisy = _pulse_record()
    w = force_window(noisy, FS)
    support = np.flatnonzero(np.abs(clean) > 0.05 * np.abs(clean).max())
    assert np.all(w[support] == 1.0)  # the blow passes untouched
    # flat part ≤ 2 × the pulse (+1 sample before it), then a 4-sample taper, then zeros
    end = support[-1] + 1 + support.size + 2 + 4
    assert np.all(w[end:] == 0.0) and np.all(w[:support[0] - 1 - 4 - 1] == 0.0)
    assert np.all((w >= 0) & (w <= 1))
    # the tapers are monotone (cosine ramps)
    ones = np.flatnonzero(w == 1.0)
    assert np.all(np.diff(w[:ones[0] + 1]) >= 0) and np.all(np.diff(w[ones[-1]:]) <= 0)
    # the window removes the noise outside the pulse: far closer to the clean blow
    err_win = np.linalg.norm(w * noisy - clean)
    err_raw = np.linalg.norm(noisy - clean)
    assert err_win < 0.2 * err_raw


def test_force_window_flat_length_and_stacks():
    """length_s sets the flat part (ones) in samples from one sample before the pulse; a
    stack of records gets one window each, each on its own pulse."""
    clean, noisy = _pulse_record(start=500)
    w = force_window(noisy, FS, length_s=40 / FS, taper_s=8 / FS)
    ones = np.flatnonzero(w == 1.0)
    assert ones.size == 40 and ones[0] == 499 and np.all(np.diff(ones) == 1)
    assert np.count_nonzero((w > 0) & (w < 1)) <= 2 * 8
    recs = np.stack([_pulse_record(start=s, seed=s, sign=sg)[1]
                     for s, sg in ((100, 1), (700, -1), (1500, 1))]).reshape(3, 1, -1)
    W = force_window(recs, FS)
    assert W.shape == recs.shape
    for k, s in enumerate((100, 700, 1500)):
        ones = np.flatnonzero(W[k, 0] == 1.0)
        assert ones[0] <= s and ones[-1] >= s + 8


def test_bad_window_parameters_are_refused():
    with pytest.raises(ParameterError):
        exponential_window(100, FS)
    with pytest.raises(ParameterError):
        exponential_window(100, FS, end_value=0.1, tau_s=1.0)
    with pytest.raises(ParameterError):
        exponential_window(100, FS, end_value=1.5)
    with pytest.raises(ParameterError):
        exponential_window(100, FS, tau_s=-1.0)
    with pytest.raises(ParameterError):
        force_window(_pulse_record()[1], FS, length_s=0.0)
