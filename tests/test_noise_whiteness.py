"""benchmarks/noise_whiteness.py: its statistic against the complex Gaussian's known tail."""

import importlib.util
from pathlib import Path

import numpy as np

_spec = importlib.util.spec_from_file_location(
    "noise_whiteness", Path(__file__).resolve().parents[1] / "benchmarks" / "noise_whiteness.py")
nw = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(nw)


def _cgauss(rng, shape, sd):
    return sd * (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) / np.sqrt(2)


def test_white_noise_exceeds_the_level_on_a_tenth_of_a_percent_of_lines():
    # |e|² of a complex Gaussian is exponential: P(|e|² > ln(1000) σ²) = 1e-3 exactly
    rng = np.random.default_rng(7)
    flat, local, ratio = nw.exceedance([_cgauss(rng, (6, 40_000), 1.0)], 101)
    # 240,000 lines: the count's standard deviation is √240 ≈ 15.5 of 240 (0.0065 %)
    assert abs(flat - 0.1) < 0.03
    assert abs(local - 0.1) < 0.05  # the running median's own scatter adds a little
    assert abs(ratio - 1.0) < 0.02


def test_a_level_changing_over_the_band_is_told_from_white_noise():
    # noise whose σ falls by 20 dB over the band (a hammer's force roll-off): one flat σ²
    # puts the loud part far over its level; the local σ² follows it
    rng = np.random.default_rng(8)
    sd = np.logspace(0, -1, 40_000)[None, :]
    flat, local, ratio = nw.exceedance([_cgauss(rng, (6, 40_000), 1.0) * sd], 101)
    assert flat > 1.0  # ten times the white level at least
    assert abs(local - 0.1) < 0.05
    assert ratio > 1.5
