"""The simulator: its records reproduce the analytic FRF, its truth the model's closed form."""

import json
import re

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.tyre.model import TyreParameters, closed_form_hz
from tiremodal_cli.tyre.simulate import Faults, SimulationConfig, half_sine_spectrum, simulate

from conftest import run_cli


def test_half_sine_spectrum_matches_numerical_integral():
    w, f = 1.3e-3, np.array([0.0, 100.0, 1 / (2 * 1.3e-3), 900.0])
    t = np.linspace(0, w, 200001)
    x = np.sin(np.pi * t / w)
    num = [np.trapezoid(x * np.exp(-2j * np.pi * fi * t), t) for fi in f]
    assert_allclose(half_sine_spectrum(f, w), num, rtol=1e-6, atol=1e-12)


def test_h1_of_noise_free_records_equals_analytic_frf(exact_sim):
    r = compute_frf(exact_sim.measurement, FRFOptions(force_window=False, check_hits=False))
    fs = exact_sim.measurement.sample_rate
    lines = (r.freq_hz > 0) & (r.freq_hz < 0.45 * fs)  # not DC (accelerance 0), not Nyquist (real line)
    err = np.abs(r.H[..., lines] - exact_sim.frf[..., lines]) / np.abs(exact_sim.frf[..., lines])
    assert err.max() < 1e-6


def test_truth_table_equals_closed_form_and_3x3(exact_sim):
    t = exact_sim.truth
    p = TyreParameters(**t["parameters"])
    modes = [m for m in t["modes"] if m["harmonic"] == "cos"]
    for branch, col in (("same", 0), ("opposite", 1)):
        got = {m["n"]: m["frequency_hz"] for m in modes if m["branch"] == branch and m["n"] >= 2}
        ns = np.array(sorted(got))
        assert ns.size > 5
        assert_allclose([got[n] for n in ns], closed_form_hz(ns, p)[:, col], rtol=1e-10)
    n1 = sorted(m["frequency_hz"] for m in modes if m["n"] == 1)
    import scipy.linalg

    K1 = p.EI / p.R**4 + p.P0 * p.b / p.R + p.k_r1
    M = np.diag([p.rhoA, p.m_s, p.m_w / (np.pi * p.R)])
    K = np.array([[K1, -p.k_r1, 0], [-p.k_r1, p.k_r1 + p.k_r2, -p.k_r2], [0, -p.k_r2, p.k_r2]])
    assert_allclose(n1, np.sqrt(scipy.linalg.eigvalsh(K, M)) / (2 * np.pi), rtol=1e-10)
    # default damping: the paper's order
    z = [m["damping_ratio"] for m in t["modes"]]
    assert 0.016 <= min(z) and max(z) <= 0.038


def test_seed_makes_it_deterministic():
    cfg = SimulationConfig(n_points=8, n_hits=2, n_samples=512, noise=0.01, seed=7)
    a, b = simulate(cfg), simulate(cfg)
    c = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=512, noise=0.01, seed=8))
    assert np.array_equal(a.measurement.response, b.measurement.response)
    assert not np.array_equal(a.measurement.response, c.measurement.response)


def test_noise_is_a_floor_relative_to_the_channel_rms():
    clean = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=2048, seed=3, dtype="float64"))
    noisy = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=2048, seed=3, noise=0.05, dtype="float64"))
    d = noisy.measurement.response[:, :, 0] - clean.measurement.response[:, :, 0]
    rms = np.sqrt(np.mean(clean.measurement.response[:, :, 0] ** 2))  # the channel over the test
    assert_allclose(np.std(d, axis=-1) / rms, 0.05, rtol=0.1)


def test_missing_point_and_faults_in_truth():
    s = simulate(SimulationConfig(n_points=10, n_hits=2, n_samples=512, seed=1,
                                  faults=Faults(missing_point=3, double_hits=((1, 1),), dead_channel="rim")))
    assert s.measurement.n_points == 9
    assert not np.any(np.isclose(s.measurement.point_angle, 2 * np.pi * 3 / 10))
    kinds = sorted(f["kind"] for f in s.truth["faults"])
    assert kinds == ["dead_channel", "double_hit", "missing_point"]


def test_cli_simulate_then_info_round_trips_sizes(tmp_path):
    out = tmp_path / "t.h5"
    res = run_cli(["simulate", out, "--points", 9, "--hits", 2, "--samples", 512, "--sample-rate", 1000,
                   "--noise", 0.01, "--seed", 4, "--param", "m_w=800", "--effect", "sidewall_membrane:T_s=1e4"])
    assert res.exit_code == 0, res.output
    info = json.loads(run_cli(["info", "--json", out]).stdout)
    assert (info["n_points"], info["n_hits"], info["n_channels"], info["n_samples"], info["sample_rate"]) == \
        (9, 2, 3, 512, 1000.0)
    truth = json.loads((tmp_path / "t.truth.json").read_text())
    assert truth["parameters"]["m_w"] == 800.0 and truth["effects"] == {"sidewall_membrane": {"T_s": 1e4}}
    # refuses to overwrite, and leaves nothing half-written
    res = run_cli(["simulate", out, "--points", 9])
    assert res.exit_code == 2 and "--overwrite" in res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["t.h5", "t.truth.json"]


@pytest.mark.parametrize("args, msg", [
    (["--effect", "nope"], "unknown effect 'nope'"),
    (["--param", "k_r1=-5"], r"k_r1=-5\.0 must be a positive"),
    (["--param", "zeta=1"], "unknown model parameter 'zeta'"),
    (["--double-hit", "99:0"], r"double hit \(99, 0\) is out of range"),
    (["--dead-channel", "hub"], "dead channel 'hub'"),
])
def test_cli_simulate_bad_options(tmp_path, args, msg):
    res = run_cli(["simulate", tmp_path / "x.h5", *args])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and re.search(msg, lines[0])
    assert not list(tmp_path.iterdir())


def test_cli_simulate_config_file(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text('seed = 3\nn_points = 8\nn_hits = 1\nn_samples = 256\n[params]\nk_r2 = 4e6\n'
                   '[effects.added_mass]\nm_a = 0.3\n[faults]\nmissing_point = 2\n')
    res = run_cli(["simulate", tmp_path / "t.h5", "--config", cfg, "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    assert d["n_points"] == 7 and d["faults"] == [{"kind": "missing_point", "point": 2}]
    cfg.write_text("n_pointz = 3\n")
    res = run_cli(["simulate", tmp_path / "u.h5", "--config", cfg])
    assert res.exit_code == 2 and "unknown key 'n_pointz'" in res.stderr
