"""Shared fixtures: small simulated tests (seeded) and a CLI runner."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from tiremodal_cli.cli.main import cli
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate


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
