"""An aliased order is a model's reading of its alias class: the base fit re-reads it."""

import numpy as np

from tiremodal_cli.diagnose.loop import DiagnoseOptions, base_fit
from tiremodal_cli.tyre.measured import MeasuredMode
from tiremodal_cli.tyre.robust import with_sigma
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

N = 34  # points on the circumference: orders above 17 are aliases of 0 … 17


def _truth_modes():
    """The paper model's own modes (the generator's labels): opposite n = 0 … 45, same n = 0 … 10
    (above, the same branch crowds under its sidewall resonance)."""
    cfg = SimulationConfig(n_points=N, n_hits=1, sample_rate=5120.0, n_samples=256, noise=0.0, seed=5, n_max=60)
    sim = simulate(cfg)
    out = {}
    for m in sim.truth["modes"]:
        b, n = m["branch"], int(m["n"])
        if (b == "opposite" and n <= 45) or (b == "same" and n <= 10):
            out.setdefault((n, b), m["frequency_hz"])
    return cfg.params, [MeasuredMode(n, b, f, aliased=n > N // 2) for (n, b), f in sorted(out.items())]


def test_an_order_read_from_the_wrong_member_of_its_class_is_re_read():
    """The modal stage read the opposite branch's n = 31 … 43 as n + 34 (the same alias class
    n' ≡ ±n mod 34, the order taken from a starting model's dispersion). With the test's
    point count the base fit re-reads each from the model the measured orders determine:
    every order back to the generator's, the fit at the generator's own parameters. Without
    it, the misread orders drag the fit."""
    params, truth = _truth_modes()
    misread = [MeasuredMode(m.n + N, m.branch, m.frequency_hz, aliased=True)
               if m.branch == "opposite" and 31 <= m.n <= 43 else m for m in truth]
    opt = DiagnoseOptions()
    modes = with_sigma(misread, opt.noise_floor_pct)
    wrong = base_fit(modes, params, opt)
    right = base_fit(modes, params, opt, N)
    got = sorted((m.n, m.branch, round(m.frequency_hz, 6)) for m in right.modes)
    assert got == sorted((m.n, m.branch, round(m.frequency_hz, 6)) for m in truth)
    assert right.fit.rms_error_pct < 0.01 and not right.set_aside
    assert wrong.fit.rms_error_pct > 10 * right.fit.rms_error_pct or wrong.set_aside
    for name in ("k_r1", "k_r2"):
        assert abs(getattr(right.fit.parameters, name) / getattr(params, name) - 1) < 1e-3


def test_orders_read_right_are_left_alone():
    """The generator's own labels (aliased ones included): nothing is re-read, and the fit is
    the one without the point count."""
    params, truth = _truth_modes()
    opt = DiagnoseOptions()
    modes = with_sigma(truth, opt.noise_floor_pct)
    a, b = base_fit(modes, params, opt), base_fit(modes, params, opt, N)
    assert [(m.n, m.branch) for m in a.modes] == [(m.n, m.branch) for m in b.modes]
    assert np.allclose(a.fit.values, b.fit.values)


def test_a_model_does_not_re_read_orders_it_cannot_tell_apart():
    """The finite-element ring with a sidewall coupling, as ``run`` measured it at the matrix's
    seed + 3000 (tests/data/ring_coupling): its in-phase n = 19 at 265.61 Hz lies 25 % above
    the base model's flat top, where that model puts every order of the class alike (n = 87
    0.4 Hz nearer than n = 19). Re-read as n = 87 and kept in every candidate's fit, that
    label held the membrane out (the diagnosis adopted nothing, 9.4 % RMS left). A model
    does not choose between two orders it places closer together than its own misfit: the
    row keeps its order and the diagnosis finds the physics the generator holds."""
    import csv
    from pathlib import Path

    from tiremodal_cli.diagnose.loop import diagnose
    from tiremodal_cli.tyre.model import TyreParameters

    path = Path(__file__).parent / "data" / "ring_coupling" / "modes_seed3018.csv"
    with path.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    d = diagnose(rows, TyreParameters(), DiagnoseOptions(rim="clamped"), n_points=34)
    assert not any(abs(c["frequency_hz"] - 265.61) < 0.1 for c in d.relabelled), d.relabelled
    assert d.adopted == ("sidewall_membrane",)
    assert d.augmented.rms_error_pct < 0.05
