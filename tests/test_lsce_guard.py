"""The guard band between the zoom band's ends (:mod:`tiremodal_cli.modal.guard`).

Truths used: the DFT's periodicity (a band's impulse responses are periodic in the lines,
so the sequence after the bridge must be continuous across both ends); the damped
exponential's spectrum (a pole's FRF, written here, not by the code under test); the ring
generator's truth modes (finite elements, :mod:`tiremodal_cli.tyre.ring`).
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.modal.guard import guard_lines
from tiremodal_cli.modal.lsce import bridge, principal_responses
from tiremodal_cli.modal.refine import EDGE_HALF_WIDTHS


def test_guard_keeps_poles_six_half_widths_apart_across_the_wrap():
    """Band 5.5–1,295.5 Hz (0.5 Hz lines): a 24.45 Hz pole and a 1,211 Hz pole of
    half-width ζ f = 0.02 × 1,211 = 24.22 Hz are 19 + 84.5 = 103.5 Hz apart across the wrap;
    6 half-widths are 145.32 Hz, so the guard is ⌈41.82 / 0.5⌉ = 84 lines. Poles 300 Hz
    from each edge need none; one pole, or none, needs none."""
    assert EDGE_HALF_WIDTHS == 6.0
    assert guard_lines([24.45, 1211.0], [0.03, 0.02], 5.5, 1295.5, 0.5) == 84
    assert guard_lines([305.5, 995.5], [0.02, 0.02], 5.5, 1295.5, 0.5) == 0
    assert guard_lines([24.45], [0.03], 5.5, 1295.5, 0.5) == 0
    assert guard_lines([], [], 5.5, 1295.5, 0.5) == 0


def test_bridge_makes_the_periodic_band_continuous():
    """The guard lines run straight from the top's value to the foot's: the largest step
    between neighbours of the periodic sequence (wrap included) is the bridge's slope, far
    below the band's step across the wrap without it."""
    f = np.arange(100.0, 200.0, 0.5)
    s = complex(-0.02 * 2 * np.pi * 190, 2 * np.pi * 190)
    H = ((2j * np.pi * f) ** 2 / (2j * np.pi * f - s))[None, :]  # a mode near the top, accelerance
    wrap_step = abs(H[0, -1] - H[0, 0])
    g = 40
    P = bridge(H, g)
    assert P.shape == (1, H.shape[1] + g)
    np.testing.assert_array_equal(P[:, :H.shape[1]], H)
    steps = np.abs(np.diff(np.concatenate([P[0], P[0, :1]])))
    assert steps[H.shape[1] - 1:].max() == pytest.approx(wrap_step / (g + 1), rel=1e-9)
    assert bridge(H, 0).shape == H.shape


def test_guarded_band_keeps_its_lines_and_widens_its_period():
    """The band's lines and principal responses are the unguarded ones; only the impulse
    responses' period (and dt) grow by the guard's lines."""
    rng = np.random.default_rng(7)
    f = np.arange(0.0, 400.0, 0.5)
    H = rng.normal(size=(3, f.size)) + 1j * rng.normal(size=(3, f.size))
    b0 = principal_responses(f, H, (10.0, 300.0))
    b1 = principal_responses(f, H, (10.0, 300.0), guard=50)
    np.testing.assert_array_equal(b0.freq_hz, b1.freq_hz)
    np.testing.assert_allclose(b0.prf, b1.prf)
    assert b1.irf.shape[-1] == b0.irf.shape[-1] + 50
    assert b1.width_hz == pytest.approx(b0.width_hz + 25.0)
    assert b1.dt == pytest.approx(1.0 / b1.width_hz)


@pytest.fixture(scope="module")
def ring_rim_5120(tmp_path_factory):
    """The validation matrix's 5,120 Hz ring with a free rim, 40 points, bounced and
    overloaded hits (seeded), its FRFs as ``run`` computes them; its modal stage over
    ``run``'s default band, without the guard (``ModalOptions(guard=False)``) and as by
    default. Returns the generator's truth modes and the frequencies (Hz) of the two
    tables: without, default."""
    from conftest import matrix_case_frfs

    from tiremodal_cli.modal.band import default_band
    from tiremodal_cli.modal.modes import modal_table_from_frf
    from tiremodal_cli.modal.options import ModalOptions
    sim, r = matrix_case_frfs("ring:combo: sample_rate=5120.0, n_points=40, faults=bounced+overload, physics=rim",
                              tmp_path_factory.mktemp("ring_rim_5120"))
    band, _ = default_band(r.freq_hz, r.coherence, r.n_averages, np.mean(r.force_autospectrum, axis=0))
    assert ModalOptions().guard  # the default path
    tables = [modal_table_from_frf(r, ModalOptions(band_hz=band, guard=False))[0],
              modal_table_from_frf(r, ModalOptions(band_hz=band))[0]]
    freqs = [np.asarray(t.frequency_hz, float) for t in tables]
    return sim.truth["modes"], freqs


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_the_rim_mode_at_the_foot_is_found_within_the_ruler_by_default(ring_rim_5120):
    """The generator's n = 1 rim mode (24.45 Hz, 19 Hz above the band's foot, its group's
    1,211 Hz pole 4.2 of that pole's half-widths away across the wrap) is in the table
    within 0.3 % by default (its pole re-estimated in the guarded sweep); without the guard LSCE's nearest row is more than 0.3 % off
    (main at d9abc36: 24.30 Hz, −0.59 %)."""
    truth, (plain, guarded) = ring_rim_5120
    rim = {round(m["frequency_hz"], 6) for m in truth if m["branch"] == "rim" and m["n"] == 1}
    f_true = min(rim)  # the lower n = 1 rim mode (cos and sin members: one frequency)
    assert 24.0 < f_true < 25.0
    assert np.min(np.abs(guarded / f_true - 1)) <= 0.003
    assert np.min(np.abs(plain / f_true - 1)) > 0.003


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_no_truth_mode_found_without_the_guard_is_lost_by_default(ring_rim_5120):
    """Only the wrap-biased pole is re-estimated: every generator truth mode in the band that
    the unguarded table finds within 0.3 % the default table finds within 0.3 % too, and the
    default table has no more rows (the guard adds no mode)."""
    truth, (plain, guarded) = ring_rim_5120
    f_true = np.array(sorted({round(m["frequency_hz"], 6) for m in truth}))
    hit = lambda table: np.array([np.min(np.abs(table / f - 1)) <= 0.003 for f in f_true])  # noqa: E731
    assert np.all(hit(guarded)[hit(plain)])
    assert hit(guarded).sum() > hit(plain).sum()
    assert guarded.size <= plain.size


def test_the_wrap_biases_the_pole_within_the_other_poles_image_flank():
    """24.45 Hz (ζ 0.03, half-width 0.73 Hz) and 1,211 Hz (ζ 0.02, half-width 24.22 Hz) in
    5.5–1,295.5 Hz: 103.5 Hz apart across the wrap, under 6 × 24.22 = 145.3 Hz (the wide
    pole's image reaches the narrow one) but far over 6 × 0.73 Hz: only the 24.45 Hz pole is
    biased. A pole in the middle (650 Hz) is never named; poles 300 Hz from the edges neither."""
    from tiremodal_cli.modal.guard import wrap_biased
    got = wrap_biased([24.45, 650.0, 1211.0], [0.03, 0.02, 0.02], 5.5, 1295.5)
    np.testing.assert_array_equal(got, [True, False, False])
    np.testing.assert_array_equal(wrap_biased([305.5, 995.5], [0.02, 0.02], 5.5, 1295.5), [False, False])
    np.testing.assert_array_equal(wrap_biased([24.45], [0.03], 5.5, 1295.5), [False])
