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


def test_a_dead_channel_is_stored_as_a_documented_null_not_nan(tmp_path):
    """The clamped rim's silent channel: frf.h5 holds no NaN (issue 14) — its FRFs and
    coherence are the fill value 0, named with their reason in the datasets' attributes and
    in ``channel_live`` — and reading the file gives the estimate's NaN back."""
    import h5py
    import numpy as np

    from tiremodal_cli.io.frffile import read_frf, write_frf

    sim = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=1024, sample_rate=1024.0, noise=0.005, seed=5))
    r = compute_frf(sim.measurement, FRFOptions(band_hz=(0.0, 400.0)))
    dead = [i for i, c in enumerate(r.channel_name) if c in r.dead_channels]
    assert dead and np.isnan(r.H[dead]).all()
    write_frf(tmp_path / "frf.h5", r)
    with h5py.File(tmp_path / "frf.h5", "r") as h:
        for name in ("frf", "coherence"):
            assert np.isfinite(h[name][()]).all()
            assert (h[name][()][dead] == 0).all() and h[name].attrs["null_reason"].startswith("dead channel")
        assert list(np.flatnonzero(~h["channel_live"][()])) == dead
    back = read_frf(tmp_path / "frf.h5")
    np.testing.assert_array_equal(back.H, r.H)  # NaN where the estimate has NaN, the rest exact
    np.testing.assert_array_equal(back.coherence, r.coherence)
