"""Double hits whose bounce overlaps the first pulse (the force spectrum's notch), and the
checks that cannot run being said."""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import pytest

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.frf.hits import bounce_in_pulse, clipped_samples, double_hit, is_clipped, pulse_extent
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

CFG = SimulationConfig(params=TyreParameters(m_w=1000.0), n_points=12, n_hits=2, sample_rate=1024.0,
                       n_samples=1024, pulse_width_s=0.002, noise=0.005, seed=11)


def _bounce(x, fs, dt, a2):
    X = np.fft.rfft(x, axis=-1)
    f = np.fft.rfftfreq(x.shape[-1], 1 / fs)
    return np.fft.irfft(X * (1 + a2 * np.exp(-2j * np.pi * f * dt)), n=x.shape[-1], axis=-1)


@pytest.fixture(scope="module")
def clean():
    return simulate(CFG).measurement


def test_short_bounces_at_1024_hz_are_rejected_and_clean_hits_kept(clean):
    """Bounces 2.2 and 3 ms after a 2 ms blow at 1,024 Hz merge with its tail (the check
    after the pulse misses them); the notch finds them; no clean hit is rejected."""
    fs = clean.sample_rate
    force, resp = np.array(clean.force, float), np.array(clean.response, float)
    faults = {(2, 0): (2.2e-3, 0.4), (7, 1): (3.0e-3, 0.35)}
    for (p, h), (dt, a2) in faults.items():
        force[p, h] = _bounce(force[p, h], fs, dt, a2)
        resp[p, h] = _bounce(resp[p, h], fs, dt, a2)
        assert not double_hit(force[p, h], fs)  # merged: no second blow after the pulse
    m = dataclasses.replace(clean, force=force.astype(np.float32), response=resp.astype(np.float32))
    r = compute_frf(m, FRFOptions(band_hz=(0, 320.0), exp_end=0.05))
    rejected = {(x.point, x.hit) for x in r.rejections if x.hit is not None}
    assert rejected == set(faults)
    for x in r.rejections:
        if x.hit is not None:
            notch = float(x.reason.split("notch at ")[1].split(" Hz")[0])
            dt = faults[(x.point, x.hit)][0]
            assert abs(notch - 1 / (2 * dt)) < 0.15 / (2 * dt)  # the notch where a bounce puts it


def test_clean_tests_raise_no_alarm():
    """Seeded clean tests at each rate, two noise levels: no hit flagged (the wider sweep,
    80 tests, is in benchmarks/bench_hits.py)."""
    for fs, w in ((1024.0, 0.002), (2048.0, 0.001)):
        for seed in range(2):
            for noise in (0.005, 0.05):
                m = simulate(dataclasses.replace(CFG, sample_rate=fs, n_samples=int(fs), pulse_width_s=w,
                                                 noise=noise, seed=seed, n_hits=3)).measurement
                flags, _, ran = bounce_in_pulse(np.asarray(m.force, float).reshape(-1, m.n_samples), fs)
                assert ran and not flags.any(), (fs, seed, noise)


def test_a_check_that_cannot_run_is_said(clean, caplog):
    one = dataclasses.replace(clean, force=clean.force[:4, :1], response=clean.response[:4, :1],
                              point_angle=clean.point_angle[:4])
    with caplog.at_level(logging.WARNING):
        r = compute_frf(one, FRFOptions(band_hz=(0, 320.0)))
    said = " ".join(r.meta["checks_not_run"])
    assert "consistency of the hits: needs at least 3 hits per point, the test has 1" in said
    assert "needs at least 5 usable hits in the test (finite, non-zero force), it has 4 of 4" in said
    assert "hit check not run" in caplog.text
    r = compute_frf(clean, FRFOptions(band_hz=(0, 320.0)))
    assert r.meta["checks_not_run"] == ["consistency of the hits: needs at least 3 hits per point, the test has 2"]


# --- direct unit tests of the record checks (clipping, second blow, pulse extent) -------------
# Truths: an ADC in overload holds its full-scale value (a clipped record sits at its extreme
# for several samples); a hammer pushes, so a bounce is a second pulse of the blow's sign
# after the first has ended; a half-sine pulse sin(πt/T) exceeds a fraction c of its peak
# for the middle (1 − 2 arcsin(c)/π) of its duration.

FS_U = 10240.0


def _half_sine(n, at_s, width_s, amp=1.0, fs=FS_U):
    t = np.arange(n) / fs - at_s
    return np.where((t > 0) & (t < width_s), amp * np.sin(np.pi * t / width_s), 0.0)


def _response(n, fs=FS_U, seed=0):
    """A noisy two-mode decay (no sample ties at its peak)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    x = np.exp(-8 * t) * np.sin(2 * np.pi * 97.3 * t) + 0.4 * np.exp(-15 * t) * np.sin(2 * np.pi * 311.1 * t + 1)
    return x + 1e-3 * rng.normal(size=n)


def test_a_clipped_response_is_found_and_its_held_samples_counted():
    x = _response(4096)
    limit = 0.6 * np.abs(x).max()
    clipped = np.clip(x, -limit, limit)
    held = np.count_nonzero(np.abs(x) >= limit)  # the samples the converter held at full scale
    assert held >= 3
    assert clipped_samples(clipped) == held
    assert is_clipped(clipped)
    assert clipped_samples(x) == 0 and not is_clipped(x)


def test_clipping_counts_per_record_along_any_axis():
    recs = np.stack([_response(2048, seed=s) for s in range(4)])  # (4, 2048)
    recs[2] = np.clip(recs[2], -0.5, 0.5)
    assert list(is_clipped(recs)) == [False, False, True, False]
    assert list(is_clipped(recs.T, axis=0)) == [False, False, True, False]


def test_two_separate_ties_at_the_peak_are_not_clipping_but_an_adjacent_pair_is():
    """min_run = 2 adjacent, or min_count = 3 anywhere (documented defaults)."""
    x = _response(1024)
    pk = np.abs(x).max()
    two_apart = x.copy()
    two_apart[[100, 500]] = [pk * 1.1, -pk * 1.1]
    assert clipped_samples(two_apart) == 0
    adjacent = x.copy()
    adjacent[[100, 101]] = pk * 1.1
    assert clipped_samples(adjacent) == 2
    three = x.copy()
    three[[100, 400, 800]] = pk * 1.1
    assert clipped_samples(three) == 3


def test_pulse_extent_of_a_half_sine_matches_its_analytic_width():
    n, at, w = 4096, 0.05, 0.002
    f = _half_sine(n, at, w)
    start, stop = pulse_extent(f, FS_U, threshold=0.05)
    above = w * (1 - 2 * np.arcsin(0.05) / np.pi)  # time above 5 % of the peak
    assert abs((stop - start) / FS_U - above) <= 2 / FS_U
    assert abs(start / FS_U - (at + w * np.arcsin(0.05) / np.pi)) <= 1.5 / FS_U


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_second_blow_after_the_pulse_is_a_double_hit_a_clean_hit_passes(sign):
    rng = np.random.default_rng(8)
    n = 8192
    first = _half_sine(n, 0.02, 0.001, sign)
    noise = 2e-3 * rng.normal(size=n)
    clean = first + noise
    bounce = first + _half_sine(n, 0.032, 0.001, 0.35 * sign) + noise  # 35 % blow 12 ms later
    small = first + _half_sine(n, 0.032, 0.001, 0.10 * sign) + noise  # 10 % < min_relative 20 %
    flags = double_hit(np.stack([clean, bounce, small]), FS_U)
    assert list(flags) == [False, True, False]


def test_ringing_of_the_opposite_sign_is_not_a_second_blow():
    """A pull of 50 % after a push is filter ringing, not a hammer (which only pushes)."""
    n = 4096
    f = _half_sine(n, 0.02, 0.001) + _half_sine(n, 0.0215, 0.001, -0.5)
    assert not double_hit(f, FS_U)
    g = _half_sine(n, 0.02, 0.001) + _half_sine(n, 0.0215, 0.001, +0.5)
    assert double_hit(g, FS_U)
