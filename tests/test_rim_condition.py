"""The rim's condition from the data (pipeline.rim_condition): clamped when the rim channel
is silent, free when it moves, the parameters' when there is no rim channel."""

from types import SimpleNamespace

import pytest

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.tyre.model import NOMINAL_RIM_KG, TyreParameters
from tiremodal_cli.workflow.pipeline import rim_condition
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate


def _r(dead=(), locations=("tread", "sidewall", "rim")):
    names = tuple(f"c{i}" if loc != "rim" else "rim" for i, loc in enumerate(locations))
    return SimpleNamespace(channel_name=names, channel_location=locations, dead_channels=tuple(dead))


def test_rules():
    p, why = rim_condition(_r(dead=("rim",)), TyreParameters(m_w=500.0))
    assert p.m_w is None and why.startswith("clamped")
    p, why = rim_condition(_r(), TyreParameters())
    assert p.m_w == NOMINAL_RIM_KG and why.startswith("free")
    p, why = rim_condition(_r(), TyreParameters(m_w=500.0))
    assert p.m_w == 500.0
    p, why = rim_condition(_r(locations=("tread", "sidewall")), TyreParameters(m_w=500.0))
    assert p.m_w == 500.0 and "no rim channel" in why


@pytest.mark.parametrize("m_w, clamped", [(None, True), (60.0, False)])
def test_simulated_rim_is_read_from_its_channel(m_w, clamped):
    """A clamped rim (simulate's default) leaves the rim accelerometer silent; a 60 kg free
    rim moves it. The FRF stage's dead-channel rule tells them apart."""
    sim = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=1024, sample_rate=1024.0, noise=0.005,
                                    params=TyreParameters(m_w=m_w), seed=5))
    r = compute_frf(sim.measurement, FRFOptions(band_hz=(0.0, 400.0)))
    p, why = rim_condition(r, TyreParameters())
    assert (p.m_w is None) == clamped, why
