"""The classical flexible-tread model beside the paper's coupled model (the paper's own comparison)."""

import csv
from pathlib import Path

import numpy as np
import pytest

from tiremodal_cli.tyre.flexible_tread import errors_by_branch, fit_flexible_tread, flexible_tread_hz
from tiremodal_cli.tyre.fit import fit
from tiremodal_cli.tyre.fit_types import FitOptions
from tiremodal_cli.tyre.measured import MeasuredMode, modes_from_rows
from tiremodal_cli.tyre.model import TyreParameters, closed_form_hz

TABLE_A1 = Path(__file__).resolve().parents[1] / "sample_data" / "paper_table_a1.csv"


def test_massless_sidewall_limit_of_the_coupled_model():
    """With a massless sidewall the coupled model's same-direction branch is the tread on
    the two sidewall springs in series: the flexible tread with k = k_r1 k_r2/(k_r1 + k_r2)."""
    p = TyreParameters(m_s=1e-3)  # the closed form loses digits as m_s → 0 (B − √disc); 1e-3 kg/m moves f by < 1e-5
    ns = np.arange(1, 21)
    k = p.k_r1 * p.k_r2 / (p.k_r1 + p.k_r2)
    np.testing.assert_allclose(flexible_tread_hz(ns, p.EI, k, p), closed_form_hz(ns, p)[:, 0], rtol=3e-5)


def test_parameters_recovered_from_its_own_modes():
    """Modes of a known flexible tread with 0.1 % seeded scatter: EI and k within 3 SE."""
    p = TyreParameters()
    rng = np.random.default_rng(4)
    EI, k = 40.0, 2.0e6
    ns = np.arange(1, 13)
    f = flexible_tread_hz(ns, EI, k, p) * (1 + 1e-3 * rng.standard_normal(ns.size))
    res = fit_flexible_tread([MeasuredMode(int(n), "same", float(x)) for n, x in zip(ns, f)], p)
    assert abs(res.EI - EI) < 3 * res.std_errors["EI"] and abs(res.k - k) < 3 * res.std_errors["k"]
    assert res.rms_error_pct < 0.2 and not res.at_bound


def test_table_a1_the_flexible_tread_fails_the_opposite_branch_and_the_coupled_model_does_not():
    """The paper's claim in numbers: the flexible-tread model cannot follow the
    opposite-direction modes (180–300 Hz) — it has no second mode of any order — while
    the coupled model fitted to the same modes follows both branches."""
    modes, _ = modes_from_rows(list(csv.DictReader(open(TABLE_A1))))
    flex = fit_flexible_tread(modes)
    coupled = errors_by_branch(fit(modes, TyreParameters(), FitOptions(seed=0)).modes)
    assert flex.by_branch["opposite"]["rms_error_pct"] > 20
    assert coupled["opposite"]["rms_error_pct"] < 3
    assert coupled["same"]["rms_error_pct"] < flex.by_branch["same"]["rms_error_pct"]
    assert len(flex.modes) == len(modes) == 18
