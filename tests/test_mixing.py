"""The order-mixing test (``modal.mixing``): a lumped mass on the sensors' plane, which
keeps every mirror symmetry, is seen by the clear modes' copies in the other order groups,
symmetric about that plane; an axisymmetric tyre's copies (its test's noise) are not; and
the test's false alarms are its nominal rate."""

import dataclasses

import numpy as np
import pytest

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.modal.merge import COPY_MAX_AMPLITUDE
from tiremodal_cli.modal.mixing import MIXED_LOSS, mixed_orders_note, symmetric_copy_pvalue
from tiremodal_cli.modal.modes import modal_table_from_frf
from tiremodal_cli.modal.options import ModalOptions
from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.validation import config_for, matrix


def _rows(rng, copy, phase, n_w=41, level=3.0):
    """A group's rows over a window round a 100 Hz mode (ζ = 2 %), three channels at the
    planes ``phase`` (rad, the group's order × the angle): the group's own modes at 80 and
    130 Hz, symmetric about each plane; the 100 Hz mode's copy with random complex
    amplitudes (``copy`` = "noise": independent on the cos and sin rows, as a point's force
    noise puts it; "symmetric": one amplitude per channel, on its plane; "none") at
    ``level`` × the white noise's amplitude at its peak; and the noise."""
    f = np.linspace(96.0, 104.0, n_w)
    jw = 2j * np.pi * f
    pole = lambda fn, z: 2 * np.pi * fn * (-z + 1j * np.sqrt(1 - z * z))
    own, lam = [pole(80.0, 0.02), pole(130.0, 0.03)], pole(100.0, 0.02)
    cn = lambda *shape: rng.standard_normal(shape) + 1j * rng.standard_normal(shape)
    u = sum(np.outer(1 / (jw - s), 50 * cn(3)) for s in own)  # symmetric: u (cos φ, sin φ)
    Y = np.hstack([u * np.cos(phase), u * np.sin(phase)])
    peak = 1 / abs(lam.real)
    if copy == "noise":
        Y += np.outer(1 / (jw - lam), level * cn(6) / peak)
    elif copy == "symmetric":
        v = level * cn(3) / peak
        Y += np.outer(1 / (jw - lam), np.concatenate([v * np.cos(phase), v * np.sin(phase)]))
    return jw, Y + cn(n_w, 6), own, lam


@pytest.mark.parametrize("copy", ["none", "noise"])
def test_no_symmetric_copy_false_alarm_rate_is_nominal(copy):
    """No copy, or the test's own noise copy (as strong in the antisymmetric part as in the
    symmetric): the F(6, 6) test finds a symmetric copy at p < 0.01 in 1 % of 600 seeded
    draws (binomial 3 σ: 0–2.2 %), at p < 0.05 in 5 % (2.3–7.7 %)."""
    rng = np.random.default_rng(7)
    phase = np.array([0.0, 1.5, 1.5])
    p = np.array([symmetric_copy_pvalue(*_rows(rng, copy, phase), phase) for _ in range(600)])
    assert np.mean(p < 0.01) <= 0.022 and 0.023 <= np.mean(p < 0.05) <= 0.077


def test_a_symmetric_copy_is_found():
    """The copy on the channels' planes (the mass's copies, symmetric about the sensors'
    plane) at 3 × the noise at its peak: found at p < 0.01 in at least 30 % of 200 seeded
    draws; at 10 ×, in at least 95 % (three channels: the F(6, 6) test's power)."""
    rng = np.random.default_rng(8)
    phase = np.array([0.0, 1.5, 1.5])
    p = np.array([symmetric_copy_pvalue(*_rows(rng, "symmetric", phase), phase) for _ in range(200)])
    assert np.mean(p < 0.01) >= 0.3
    p = np.array([symmetric_copy_pvalue(*_rows(rng, "symmetric", phase, level=10.0), phase) for _ in range(200)])
    assert np.mean(p < 0.01) >= 0.95


def _ring(masses):
    case = next(c for c in matrix() if c.name == "ring:reference")
    cfg = config_for(case)
    cfg = dataclasses.replace(cfg, ring=cfg.ring.replace(masses=masses))
    sim = simulate(cfg)
    r = compute_frf(sim.measurement, FRFOptions(band_hz=(0.0, 400.0), exp_end=0.05))
    return modal_table_from_frf(r, ModalOptions(band_hz=(20.0, 400.0)))[1]


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
@pytest.mark.parametrize("masses, mixed", [((), False), (((0.0, 0.5),), True)])
def test_a_mass_on_the_sensors_plane_mixes_the_orders(masses, mixed):
    """The finite-element ring, its sensors at 0°: without a mass the orders do not mix
    (under a tenth of the tests find a symmetric copy; the matrix's symmetric cases:
    0.01–0.05); with 0.5 kg at 0° — the mirror test's blind spot, its antisymmetric share
    as small as the symmetric ring's — most of them do (the matrix's masses: 0.79–0.85)."""
    res = _ring(masses)
    assert res.meta["antisymmetric_share"] < 0.05
    mix = res.meta["order_mixing"]
    assert mix["tests"] >= 50 and mix["mixed"] is mixed
    assert (mix["fraction"] > 0.4) if mixed else (mix["fraction"] < 0.1)
    note = res.meta["orders_mix"]  # what such a test cannot promise, said (modal.mixing.mixed_orders_note)
    assert (note is not None and "orders mix" in note["statement"]) if mixed else note is None


def test_the_note_names_what_mixed_the_orders():
    """A mass off the sensors' planes (its antisymmetric share at or above the copy limit)
    and one on them (symmetric copies in most tests) each give the note with its reason;
    a symmetric test (neither) gives none."""
    assert mixed_orders_note(0.01, {"tests": 100, "found": 3, "fraction": 0.03, "mixed": False}) is None
    assert mixed_orders_note(None, None) is None
    off = mixed_orders_note(2 * COPY_MAX_AMPLITUDE, None)
    assert "antisymmetric share" in off["why"] and off["symmetric_copy_fraction"] is None
    on = mixed_orders_note(0.002, {"tests": 574, "found": 300, "fraction": 0.52, "mixed": True})
    assert "300 of 574" in on["why"] and on["symmetric_copy_fraction"] == 0.52
    assert f"{100 * MIXED_LOSS['weak']:.0f} %" in on["statement"]
