"""The closed-form first estimate (tiremodal_cli/tyre/closed_form.py).

Truth built here, not by the package: the frequencies of the paper's 2 × 2 pencil
(docs/model.md, M = diag(ρA, m_s), K_n as written out below) from scipy.linalg.eigh, for
the paper's identified parameters (MODEL.md: EI = 25.697 N·m², k_r1 = 6.686e6,
k_r2 = 4.431e6 N/m²). From exact frequencies the estimate recovers them to rounding; from
the paper's measured Table A1 the local search started at it lands on the full search's
optimum.
"""

import csv
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from tiremodal_cli.tyre.closed_form import first_estimate
from tiremodal_cli.tyre.fit import fit
from tiremodal_cli.tyre.fit_types import FitOptions
from tiremodal_cli.tyre.measured import MeasuredMode, modes_from_rows
from tiremodal_cli.tyre.model import TyreParameters

ROOT = Path(__file__).resolve().parents[1]
PAPER = dict(EI=25.697, k_r1=6.686e6, k_r2=4.431e6)


def _pencil_modes(orders, rhoA=19.64, m_s=10.0, R=0.65, T=8e5 * 0.35 * 0.65, **k):
    out = []
    for n in orders:
        Kn = k["EI"] * n**4 / R**4 + T * n**2 / R**2 + k["k_r1"]
        K = np.array([[Kn, -k["k_r1"]], [-k["k_r1"], k["k_r1"] + k["k_r2"]]])
        lam = scipy.linalg.eigh(K, np.diag([rhoA, m_s]), eigvals_only=True)
        out += [MeasuredMode(n, b, float(np.sqrt(x) / (2 * np.pi))) for b, x in zip(("same", "opposite"), lam)]
    return out


def test_exact_frequencies_give_the_parameters():
    est = first_estimate(_pencil_modes([0, 2, 3, 4, 5, 6], **PAPER), TyreParameters(m_w=1000.0))
    for k, v in PAPER.items():
        assert est[k] == pytest.approx(v, rel=1e-8)


def test_other_parameters_and_a_clamped_rim_with_n_1():
    truth = dict(EI=80.0, k_r1=2e6, k_r2=9e6)
    est = first_estimate(_pencil_modes([1, 2, 4, 7], **truth), TyreParameters(m_w=None))
    for k, v in truth.items():
        assert est[k] == pytest.approx(v, rel=1e-8)


def test_where_it_does_not_apply_it_says_so():
    modes = _pencil_modes([0, 2, 3, 4], **PAPER)
    base = TyreParameters(m_w=1000.0)
    assert first_estimate(modes, base, free=("k_r1", "k_r2", "EI", "m_s")) is None  # another parameter free
    assert first_estimate(modes[:4], base) is None  # two orders on both branches: fewer than three
    assert first_estimate([m for m in modes if m.branch == "same"], base) is None  # one branch only
    # n = 1 with a free rim is a 3 × 3 order: not used, so three orders remain here
    assert first_estimate(_pencil_modes([1, 2, 3], **PAPER), base) is None


def test_table_a1_local_search_from_it_lands_on_the_full_search_optimum():
    with (ROOT / "sample_data" / "paper_table_a1.csv").open() as fh:
        modes, _ = modes_from_rows(list(csv.DictReader(fh)))
    base = TyreParameters()
    full = fit(modes, base, FitOptions(search="global"))
    fast = fit(modes, base, FitOptions(search="local"))
    assert fast.options.start_from == "closed form"
    assert fast.rms_error_pct == pytest.approx(full.rms_error_pct, rel=1e-6)
    assert np.all(np.abs(fast.values - full.values) <= 0.01 * full.std_errors)
