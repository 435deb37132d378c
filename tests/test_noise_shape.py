"""The FRFs' noise over the lines: where the hammer's spectrum falls, the H1 estimate is noisier.

Truth here is sampling statistics, not the package: (1) the variance of an H1 estimate
built from seeded white sensor noise and a half-sine hammer pulse, measured by Monte
Carlo; (2) the noise test's false-alarm rate on seeded complex Gaussian noise whose
variance rises towards the band's top, against the α it is designed for.
"""

import numpy as np

from tiremodal_cli.modal.band import noise_shape, window_noise_gain
from tiremodal_cli.modal.gaps import weak_in_frfs
from tiremodal_cli.modal.groupfit import NOISE_ALPHA, _above_noise, _residual_terms_only
from tiremodal_cli.modal.lsfd import lsfd, synthesize
from tiremodal_cli.modal.merge import MergedMode
from tiremodal_cli.modal.spatial import grid_design

FREQ = np.arange(20.0, 420.0, 0.5)


def _half_sine(f, width_s):
    """|F(f)| of a unit half-sine pulse of ``width_s`` (its first zero at 1.5 / width)."""
    x = 2 * f * width_s
    with np.errstate(divide="ignore", invalid="ignore"):
        g = np.abs(np.cos(np.pi * f * width_s) / (1 - x**2))
    return np.where(np.isclose(x, 1), np.pi / 4, g)


def test_h1_variance_follows_the_force_spectrum():
    """Monte Carlo H1 over 3 hits of jittered half-sine pulses, white sensor noise: the
    variance of Ĥ − H per line, relative, is the shape noise_shape gives (within the
    sampling error of 4,000 draws: 5 % at 2 σ; checked over the lines where |F|² falls by
    up to 17 dB)."""
    rng = np.random.default_rng(3)
    f = FREQ
    widths = np.array([[3.0e-3, 3.1e-3, 3.2e-3], [2.9e-3, 3.05e-3, 3.15e-3]])  # (points, hits)
    H = 1.0 / (1 + 1j * f / 150.0)
    err = np.zeros((4000, 2, f.size), dtype=complex)
    for k in range(err.shape[0]):
        F = _half_sine(f[None, None, :], widths[:, :, None]) * np.exp(2j * np.pi * rng.uniform(size=(2, 3, 1)))
        N = 0.01 * (rng.standard_normal(F.shape) + 1j * rng.standard_normal(F.shape))
        X = H * F + N
        err[k] = np.sum(X * np.conj(F), axis=1) / np.sum(np.abs(F) ** 2, axis=1) - H
    measured = np.mean(np.mean(np.abs(err) ** 2, axis=0), axis=0)
    gff = np.mean(_half_sine(f[None, None, :], widths[:, :, None]) ** 2, axis=1)
    v = noise_shape(gff, np.array([3, 3]))
    g = gff.mean(axis=0)
    assert 10 * np.log10(g.max() / g.min()) > 15
    ratio = (measured / measured.mean()) / (v / v.mean())
    assert np.all(np.abs(ratio - 1) < 0.05), (ratio.min(), ratio.max())


def test_noise_shape_without_a_force_spectrum_is_none():
    assert noise_shape(None) is None


def _noise_rows(rng, v, n_rows=6):
    return np.sqrt(v / 2)[None, :] * (rng.standard_normal((n_rows, FREQ.size)) +
                                      1j * rng.standard_normal((n_rows, FREQ.size)))


def _best_noise_pole(rows, zeta=0.005):
    """The pole a sweep would fit to the noise near the top: of the candidate lines in the
    band's top tenth, the one whose fit removes the most power (a search, as a sweep is)."""
    base = rows - _residual_terms_only(FREQ, rows, "accelerance")
    best = None
    for fr in FREQ[FREQ > FREQ[-1] - 0.1 * (FREQ[-1] - FREQ[0])][::2]:
        s = np.array([-zeta * 2 * np.pi * fr + 2j * np.pi * fr])
        syn = lsfd(FREQ, rows, s).synthesis
        gain = np.sum(np.abs(base) ** 2) - np.sum(np.abs(rows - syn) ** 2)
        if best is None or gain > best[0]:
            best = (gain, s, syn)
    return best[1], best[2]


def test_noise_test_holds_its_false_alarm_rate_where_the_noise_rises():
    """Noise alone, its variance rising 50 × over the band's top fifth (a hammer's spectrum
    falling 17 dB): the pole a search fits there passes the noise test in none of 40 seeded
    trials with the noise's shape given (the test is designed for α = 1e-3 per band;
    measured: its statistic at 0.14–0.63 of the threshold, median 0.33); with the noise
    taken as white, as before, it passes in most (measured: 4.6–18 ×, median 10) — the case
    the shape is for. With the shape but unweighted fits it passed in 2 of the 40."""
    v = 1 + 49 * np.clip((FREQ - 340.0) / 80.0, 0, 1) ** 2
    passed = {True: 0, False: 0}
    for seed in range(40):
        rows = _noise_rows(np.random.default_rng(seed), v)
        s, syn = _best_noise_pole(rows)
        for shaped in (True, False):
            ok, _ = _above_noise(FREQ, rows, syn, s, lambda keep, weight=None: lsfd(FREQ, rows, s[keep],
                                                                                    weight=weight).synthesis,
                                 "accelerance", noise=v / np.median(v) if shaped else None)
            passed[shaped] += bool(ok[0])
    assert NOISE_ALPHA <= 1e-3
    assert passed[True] == 0
    assert passed[False] >= 20


def test_weighted_lsfd_is_the_better_estimator_where_the_noise_rises():
    """Gauss–Markov: with noise of known shape, least squares weighted by 1 / its RMS has
    the smaller variance. One mode at 400 Hz (ζ 1 %), the noise's variance rising 50 × over
    the band's top fifth, 300 seeded draws: the residue's scatter weighted is under that of
    the unweighted fit (measured: 0.92 × it), and both are unbiased within 4 standard errors; a constant weight
    gives the unweighted fit exactly."""
    v = 1 + 49 * np.clip((FREQ - 340.0) / 80.0, 0, 1) ** 2
    s = np.array([-0.01 * 2 * np.pi * 400.0 + 2j * np.pi * 400.0 * np.sqrt(1 - 1e-4)])
    r_true = 1e3 + 500j
    H0 = synthesize(FREQ, np.array([[r_true]]), s, form="accelerance")
    rng = np.random.default_rng(7)
    est = {"weighted": [], "unweighted": []}
    for _ in range(300):
        H = H0 + 0.02 * np.abs(H0).max() * np.sqrt(v / 2) * (rng.standard_normal(FREQ.size) +
                                                            1j * rng.standard_normal(FREQ.size))
        est["weighted"].append(lsfd(FREQ, H, s, weight=1 / np.sqrt(v)).residues[0, 0])
        est["unweighted"].append(lsfd(FREQ, H, s).residues[0, 0])
    w, u = np.array(est["weighted"]), np.array(est["unweighted"])
    assert np.std(w) < np.std(u)
    for e in (w, u):
        assert abs(e.mean() - r_true) < 4 * np.std(e) / np.sqrt(e.size)
    H = H0 + 0.01 * (rng.standard_normal(FREQ.size) + 1j * rng.standard_normal(FREQ.size))
    assert np.allclose(lsfd(FREQ, H, s, weight=np.full(FREQ.size, 3.0)).residues, lsfd(FREQ, H, s).residues)


def _windowed_noise_rows(rng, n_rows, fs=1024.0, record_s=1.0, end=0.05):
    """Rows of the DFT of white time noise under an exponential window ending at ``end``,
    on the lines 20–400 Hz; and the window's τ."""
    n = int(fs * record_s)
    t = np.arange(n) / fs
    tau = -t[-1] / np.log(end)
    f = np.fft.rfftfreq(n, 1 / fs)
    sel = (f >= 20) & (f <= 400)
    return f[sel], np.fft.rfft(rng.standard_normal((n_rows, n)) * np.exp(-t / tau), axis=1)[:, sel], tau


def test_window_noise_gain_is_what_a_pole_takes_up_of_windowed_noise():
    """The noise a pole's column takes up (its projection's power over the lines' variance),
    averaged over 300 seeded windowed records, is κ_r of the closed form within 7 % (ζ 0.5 %
    and 2 % at 200 Hz; 1 without the window)."""
    rng = np.random.default_rng(11)
    f, _, tau = _windowed_noise_rows(rng, 1)
    for zeta in (0.005, 0.02):
        s = -zeta * 2 * np.pi * 200.0 + 2j * np.pi * 200.0
        col = 1.0 / (2j * np.pi * f - s)
        col = col / np.linalg.norm(col)
        X = np.concatenate([_windowed_noise_rows(rng, 30)[1] for _ in range(10)])
        taken = np.mean(np.abs(X @ np.conj(col)) ** 2) / np.mean(np.abs(X) ** 2)
        assert abs(taken / window_noise_gain(-s.real, tau, 1.0)[0] - 1) < 0.07, (zeta, taken)
    assert np.all(window_noise_gain([5.0, 50.0], None, 1.0) == 1.0)


def test_noise_test_holds_its_rate_under_the_exponential_window():
    """Windowed noise alone (the FRF stage's window, ending at 5 %): the pole a search fits
    passes the noise test in none of 20 seeded trials with each pole's threshold scaled by
    κ_r (its statistic then at 0.45 of the threshold, median; the unwindowed noise's 0.48),
    and in most without (measured: 20 of 20, 2.2–3.7 × the threshold)."""
    passed = {True: 0, False: 0}
    for seed in range(20):
        f, Y, tau = _windowed_noise_rows(np.random.default_rng(seed), 6)
        best = None
        for fr in f[10:-10:6]:
            s = np.array([-0.02 * 2 * np.pi * fr + 2j * np.pi * fr])
            syn = lsfd(f, Y, s).synthesis
            gain = np.sum(np.abs(Y) ** 2) - np.sum(np.abs(Y - syn) ** 2)
            if best is None or gain > best[0]:
                best = (gain, s, syn)
        _, s, syn = best
        for scaled in (True, False):
            ok, _ = _above_noise(f, Y, syn, s, lambda keep, weight=None: lsfd(f, Y, s[keep], weight=weight).synthesis,
                                 "accelerance", window=(tau, 1.0) if scaled else None)
            passed[scaled] += bool(ok[0])
    assert passed[True] == 0
    assert passed[False] >= 15


def test_gappy_grid_noise_test_holds_its_rate_under_the_exponential_window():
    """A grid with missing points (19 of 24): each FRF windowed noise alone (ending at 5 %).
    The mode a search fits to it — of one order's two harmonic columns, at the line whose
    fit removes the most power — is kept by the physical FRFs' noise test
    (:func:`~tiremodal_cli.modal.gaps.weak_in_frfs`) in none of 20 seeded trials with its
    threshold scaled by κ_r, and in several without (measured: 7 of 20, at 0.41–0.97 × the
    threshold when dropped; scaled, 0.08–0.22 ×)."""
    ang = np.delete(np.arange(24) * 2 * np.pi / 24, [3, 8, 13, 17, 21])
    D, names = grid_design(ang)
    cols = [k for k, (m, _) in enumerate(names) if m == 5]
    kept = {True: 0, False: 0}
    for seed in range(20):
        f, Y, tau = _windowed_noise_rows(np.random.default_rng(seed), ang.size)
        best = None
        for fr in f[20:-20:4]:
            s = -0.02 * 2 * np.pi * fr + 2j * np.pi * fr
            G = np.kron(D[:, cols], synthesize(f, np.ones((1, 1)), [s])[0][:, None])  # (points × lines, 2)
            x = np.linalg.lstsq(G, Y.reshape(-1), rcond=None)[0]
            gain = np.sum(np.abs(Y) ** 2) - np.sum(np.abs(Y.reshape(-1) - G @ x) ** 2)
            if best is None or gain > best[0]:
                best = (gain, s, D[:, cols] @ x)
        mode = MergedMode(complex(best[1]), 5, best[2], 1.0, {5: 1.0}, 1.0, 0.1)
        for scaled in (True, False):
            kept[scaled] += len(weak_in_frfs([mode], 0.05, f, ang, Y, window=(tau, 1.0) if scaled else None)[0])
    assert kept[True] == 0
    assert kept[False] >= 3
