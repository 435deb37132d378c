"""identify, predict, sensitivity: parameters back from modal data, predictions, sensitivities."""

import json
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tiremodal_cli.tyre.fit import fit

from tiremodal_cli.tyre.fit_types import FitOptions

from tiremodal_cli.tyre.frequencies import model_frequencies

from tiremodal_cli.tyre.measured import MeasuredMode, modes_from_rows

from tiremodal_cli.tyre.predict import predict_table
from tiremodal_cli.tyre.model import PAPER_PARAMETERS, TyreParameters, closed_form_hz
from tiremodal_cli.tyre.sensitivity import coefficients, single_variable

from conftest import run_cli

ROOT = Path(__file__).resolve().parents[1]
TABLE_A1 = ROOT / "sample_data" / "paper_table_a1.csv"
TRUE = TyreParameters(k_r1=7.2e6, k_r2=4.0e6, EI=40.0)


def truth_modes(p, same=range(1, 9), opposite=range(1, 11)):
    ns = list(same) + list(opposite)
    br = ["same"] * len(same) + ["opposite"] * len(opposite)
    f = model_frequencies(p, ns, br)
    return [MeasuredMode(n, b, float(x)) for n, b, x in zip(ns, br, f)]


def test_paper_parameters_give_model_md_examples():
    f = model_frequencies(PAPER_PARAMETERS, [2, 3, 4, 5, 2, 10], ["same"] * 4 + ["opposite"] * 2)
    assert_allclose(f, [68.1, 82.5, 98.3, 114.0, 185.4, 263.8], rtol=5e-4)
    assert_allclose(f[:4], closed_form_hz([2, 3, 4, 5], PAPER_PARAMETERS)[:, 0], rtol=1e-4 * 0.01)


def test_recovers_truth_and_predicts_higher_orders():
    """The modal table of a simulate truth file, n ≤ 6 of both branches in: k_r1, k_r2 within
    2 % (here: to rounding) and the unmeasured n = 7 … 10 within 0.5 %."""
    from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

    truth = simulate(SimulationConfig(n_points=8, n_hits=1, n_samples=256, params=TRUE, seed=0)).truth
    rows = [{"frequency_hz": m["frequency_hz"], "n": m["n"], "branch": m["branch"]} for m in truth["modes"]
            if m["harmonic"] == "cos" and 1 <= m["n"] <= 6]
    modes, _ = modes_from_rows(rows)
    assert len(modes) == 12
    res = fit(modes, PAPER_PARAMETERS, FitOptions(seed=3))
    got = dict(zip(res.free, res.values))
    assert got["k_r1"] == pytest.approx(TRUE.k_r1, rel=0.02)
    assert got["k_r2"] == pytest.approx(TRUE.k_r2, rel=0.02)
    assert res.rms_error_pct < 1e-3
    pred = predict_table(res, 10)
    for row in pred:
        if row["n"] >= 7:
            true_f = model_frequencies(TRUE, [row["n"]], [row["branch"]])[0]
            assert row["model_hz"] == pytest.approx(true_f, rel=0.005)


def test_same_seed_same_result_and_history():
    modes = truth_modes(TRUE)
    a = fit(modes, PAPER_PARAMETERS, FitOptions(seed=11, generations=40))
    b = fit(modes, PAPER_PARAMETERS, FitOptions(seed=11, generations=40))
    assert np.array_equal(a.values, b.values) and a.history == b.history
    assert a.history[0][1] >= a.history[-1][1]  # the search improves


def test_bending_is_flagged_when_the_data_cannot_see_it():
    """EI barely moves n ≤ 3 (the tension term dominates): its error bar says so."""
    modes = truth_modes(TRUE, same=range(1, 4), opposite=range(1, 4))
    res = fit(modes, PAPER_PARAMETERS, FitOptions(seed=1))
    assert "EI" in res.undetermined


def test_table_a1_fit_is_no_worse_than_the_paper_and_names_misfits():
    res = run_cli(["identify", TABLE_A1, "--json", "--seed", 2])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    rows = [r for r in __import__("csv").DictReader(open(TABLE_A1))]
    f = np.array([float(r["frequency_hz"]) for r in rows])
    paper = model_frequencies(PAPER_PARAMETERS, [int(r["n"]) for r in rows], [r["branch"] for r in rows])
    paper_rms = float(np.sqrt(np.mean((100 * (paper - f) / f) ** 2)))
    assert paper_rms == pytest.approx(3.80, abs=0.01)
    assert d["rms_error_pct"] <= paper_rms
    assert {"parameters", "rms_error_pct", "max_error_pct", "modes", "predictions"} <= set(d)
    assert all({"n", "branch", "measured_hz", "model_hz", "error_pct"} <= set(m) for m in d["modes"])
    assert any(m["n"] == 8 and m["branch"] == "same" for m in d["not_followed"])


def test_paper_ga_settings_are_an_option():
    res = run_cli(["identify", TABLE_A1, "--json", "--paper-ga"])
    d = json.loads(res.stdout)
    assert d["search"]["population"] == 20 and d["search"]["generations"] == 300
    assert d["search"]["crossover"] == 0.7 and d["search"]["mutation"] == 0.1


def test_modes_from_rows_rules():
    rows = [{"frequency_hz": "60", "n": "2", "branch": "same", "n_confidence": "0.9"},
            {"frequency_hz": "61", "n": "2", "branch": "same"},  # split pair member: mean
            {"frequency_hz": "70", "n": "", "branch": "same"},
            {"frequency_hz": "80", "n": "3", "branch": "rim"},
            {"frequency_hz": "90", "n": "4", "branch": "opposite", "n_confidence": "0.2"},
            {"frequency_hz": "95", "n": "5", "branch": "opposite", "mpc": "0.1"},
            {"frequency_hz": "100", "n": "6", "branch": "same", "significance": "0.9"},
            {"frequency_hz": "130", "n": "6", "branch": "same", "significance": "0.2"}]  # a misread order
    modes, skipped = modes_from_rows(rows)
    assert [(m.n, m.branch, m.frequency_hz) for m in modes] == [(2, "same", 60.5), (6, "same", 100.0)]
    assert len(skipped) == 5 and "not a split pair" in skipped[-1]["reason"]


@pytest.mark.parametrize("csv_text, args, msg", [
    ("frequency_hz,n,branch\n", [], "no usable modes"),
    ("frequency_hz,n,branch\n60,,same\n70,3,\n", [], "no usable modes"),
    ("frequency_hz,n,branch\n60,2,same\n70,3,same\n", [], "2 usable modes for 3 free parameters"),
    ("frequency_hz,n,branch\n60,2,same\n70,3,same\n80,4,same\n", ["--bounds", "k_r1=-1:5"], "must be positive"),
    ("frequency_hz,n,branch\n60,2,same\n70,3,same\n80,4,same\n", ["--free", "k_r1,zeta"], "cannot fit 'zeta'"),
])
def test_identify_bad_input(tmp_path, csv_text, args, msg):
    p = tmp_path / "m.csv"
    p.write_text(csv_text)
    res = run_cli(["identify", p, *args])
    assert res.exit_code == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and msg in lines[0], lines


def test_end_to_end_from_time_records():
    """simulate → frf → lsce → identify: k_r1, k_r2 within 2 %, unmeasured orders within 0.5 %."""
    from tiremodal_cli.frf.estimate import compute_frf
    from tiremodal_cli.modal.table import to_rows
    from tiremodal_cli.modal.modes import ModalOptions, modal_table_from_frf
    from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

    p = TRUE.replace(m_w=None)
    s = simulate(SimulationConfig(n_points=34, n_hits=3, sample_rate=1024.0, n_samples=4096, noise=0.01, seed=5,
                                  params=p))
    table, _ = modal_table_from_frf(compute_frf(s.measurement), ModalOptions(band_hz=(40, 200)))
    modes, _ = modes_from_rows(to_rows(table))
    modes = [m for m in modes if m.n <= 6]  # measure the low orders, predict the rest
    res = fit(modes, PAPER_PARAMETERS, FitOptions(seed=0))
    got = dict(zip(res.free, res.values))
    assert got["k_r1"] == pytest.approx(p.k_r1, rel=0.02)
    assert got["k_r2"] == pytest.approx(p.k_r2, rel=0.02)
    for row in predict_table(res, 10):
        if row["n"] >= 8:
            assert row["model_hz"] == pytest.approx(model_frequencies(p, [row["n"]], [row["branch"]])[0], rel=0.005)


def test_sensitivity_study_and_coefficients():
    rows = single_variable(PAPER_PARAMETERS, ("k_r2", "m_s"), (0.8, 1.0, 1.2), 6)
    up = [r for r in rows if r["parameter"] == "k_r2" and r["factor"] == 1.2]
    assert all(r["change_pct"] > 0 for r in up)
    ns, br, S = coefficients(PAPER_PARAMETERS, ("m_s", "k_r1", "k_r2", "rhoA"), 8)
    # mass scaling: f ∝ 1/sqrt(m) when every mass scales, so Σ over masses ≈ −½ (here m_s, ρA)
    assert_allclose(S[:, 0] + S[:, 3], -0.5, atol=1e-6)
    # opposite n = 1 hangs on the springs more than the same branch does
    same1 = (ns == 1) & (br == "same")
    opp1 = (ns == 1) & (br == "opposite")
    assert S[opp1, 1] + S[opp1, 2] > S[same1, 1] + S[same1, 2]


def test_cli_predict_and_sensitivity(tmp_path):
    res = run_cli(["predict", "--json", "--n-max", 10, "--plot", tmp_path / "d.png", "--csv", tmp_path / "d.csv"])
    d = json.loads(res.stdout)
    same = {m["n"]: m["frequency_hz"] for m in d["modes"] if m["branch"] == "same"}
    assert same[2] == pytest.approx(68.1, abs=0.05) and (tmp_path / "d.png").exists()
    res = run_cli(["sensitivity", "--json", "--n-max", 6, "--plot", tmp_path / "s.png"])
    d = json.loads(res.stdout)
    assert len(d["study"]) == 6 * 3 * 12 and len(d["coefficients"]) == 12
    res = run_cli(["sensitivity", "--parameters", "zeta"])
    assert res.exit_code == 2 and "no sensitivity to 'zeta'" in res.stderr


def test_predict_compares_model_and_measured_frfs(tmp_path):
    from tiremodal_cli.frf.estimate import compute_frf
    from tiremodal_cli.io.frffile import write_frf
    from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

    s = simulate(SimulationConfig(n_points=8, n_hits=1, sample_rate=512.0, n_samples=1024, seed=2,
                                  params=TyreParameters(m_w=1000.0)))
    write_frf(tmp_path / "f.h5", compute_frf(s.measurement))
    res = run_cli(["predict", "--param", "m_w=1000", "--compare-frf", tmp_path / "f.h5", "--plot-frf",
                   tmp_path / "c.png", "--point", 2])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "c.png").read_bytes()[:4] == b"\x89PNG"
    res = run_cli(["predict", "--compare-frf", tmp_path / "f.h5", "--plot-frf", tmp_path / "d.png", "--point", 9])
    assert res.exit_code == 2 and "--point 9 is not in 1…8" in res.stderr
