"""Shared fixtures: small simulated tests (seeded) and a CLI runner."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from tiremodal_cli.cli.main import cli
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate


def matrix_case_frfs(name: str, folder):
    """A validation-matrix case's simulation and its FRFs as ``run`` computes them (the
    measurement written and read back, FRFs up to ``RunOptions().frf_top`` × fs with its
    exponential window, in the case's form) — ``run``'s FRF stage without its model stages.
    Returns (Simulation, FRFResult)."""
    from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
    from tiremodal_cli.io.measurement import open_measurement, write_measurement
    from tiremodal_cli.workflow.run_options import RunOptions
    from tiremodal_cli.workflow.validation import config_for, matrix
    case = next(c for c in matrix() if c.name == name)
    sim = simulate(config_for(case))
    write_measurement(folder / "test.h5", sim.measurement, overwrite=True)
    opt = RunOptions(form=case.form)
    with open_measurement(folder / "test.h5") as m:
        r = compute_frf(m, FRFOptions(band_hz=(0.0, opt.frf_top * float(m.sample_rate)), exp_end=opt.exp_end,
                                      form=opt.form))
    return sim, r


def run_cli(args, **kw):
    """Invoke the ``tiremodal`` group as the console script would (its own exit handling)."""
    runner = CliRunner()
    return runner.invoke(cli, [str(a) for a in args], catch_exceptions=False, standalone_mode=True, **kw)


@pytest.fixture(scope="session")
def exact_sim():
    """A noise-free float64 test with a finite rim mass (rim channel live)."""
    return simulate(SimulationConfig(n_points=12, n_hits=2, n_samples=4096, dtype="float64",
                                     params=TyreParameters(m_w=1000.0), seed=1))


@pytest.fixture(scope="session")
def noisy_sim():
    return simulate(SimulationConfig(n_points=12, n_hits=4, n_samples=2048, noise=0.02,
                                     params=TyreParameters(m_w=1000.0), seed=2))


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
