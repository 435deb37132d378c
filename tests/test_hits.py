"""Double hits whose bounce overlaps the first pulse (the force spectrum's notch), and the
checks that cannot run being said."""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import pytest

from tiremodal_cli.frf import FRFOptions, compute_frf
from tiremodal_cli.hits import bounce_in_pulse, double_hit
from tiremodal_cli.model import TyreParameters
from tiremodal_cli.simulate import SimulationConfig, simulate

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
    assert "needs at least 5 usable hits in the test, it has 4" in said
    assert "hit check not run" in caplog.text
    r = compute_frf(clean, FRFOptions(band_hz=(0, 320.0)))
    assert r.meta["checks_not_run"] == ["consistency of the hits: needs at least 3 hits per point, the test has 2"]
