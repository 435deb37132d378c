"""A peak an order group's fit leaves unexplained, and the sweep at twice the order
(:mod:`tiremodal_cli.modal.rescue`).

Truths used: a single-degree-of-freedom pole's FRF and complex Gaussian noise, written here
(not by the code under test); the ring generator's truth modes (finite elements,
:mod:`tiremodal_cli.tyre.ring`) for the validation case where the default sweep missed a mode.
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.modal.rescue import far_bands, unexplained_bands

F = np.arange(0.5, 1320.0, 0.5)  # the 5,120 Hz front end's band, 0.5 Hz lines


def _pole(f0, zeta):
    return complex(-zeta * 2 * np.pi * f0, 2 * np.pi * f0 * np.sqrt(1 - zeta**2))


def _mode(f0, zeta, amp, n_rows=6):
    """(n_rows, K): one mode's accelerance, a different complex residue per row."""
    s = _pole(f0, zeta)
    jw = 2j * np.pi * F
    res = amp * np.exp(1j * np.linspace(0, 2, n_rows))[:, None]
    return res * jw**2 / (jw - s) * abs(s.real) / abs(s) ** 2


def _noise(rng, level, n_rows=6):
    """Complex Gaussian noise whose std drifts over the band by ``level(F)`` (as H1's noise
    follows the force spectrum)."""
    return level(F)[None, :] * (rng.normal(size=(n_rows, F.size)) + 1j * rng.normal(size=(n_rows, F.size))) / np.sqrt(2)


def test_a_mode_the_fit_left_out_is_one_unexplained_band_about_it():
    """A 24.45 Hz mode (ζ 0.03) 1,000 × the noise at its peak, with a 600 Hz mode, on noise
    rising tenfold over the band: fitted without the low mode (its synthesis and pole left
    out), the low mode is one band that holds 24.45 Hz; fitted with both, no band."""
    rng = np.random.default_rng(20)
    level = lambda f: 1e-3 * (1 + 9 * f / f[-1])  # noqa: E731
    low, high = _mode(24.45, 0.03, 1.0), _mode(600.0, 0.02, 5.0)
    rows = low + high + _noise(rng, level)
    bands = unexplained_bands(F, rows, high, [_pole(600.0, 0.02)])
    assert len(bands) == 1 and bands[0][0] <= 24.45 <= bands[0][1]
    assert unexplained_bands(F, rows, low + high, [_pole(24.45, 0.03), _pole(600.0, 0.02)]) == []


def test_a_peak_beside_a_kept_pole_is_no_unexplained_band():
    """A mode fitted 1 % off its frequency leaves a residual peak inside its half-power band
    (ζ f = 6 Hz at 300 Hz): misfit of a kept pole, not a peak no pole stands for."""
    rng = np.random.default_rng(21)
    rows = _mode(300.0, 0.02, 1.0) + _noise(rng, lambda f: np.full(f.size, 1e-3))
    off = _mode(303.0, 0.02, 1.0)
    assert unexplained_bands(F, rows, off, [_pole(303.0, 0.02)]) == []


def test_a_band_another_group_s_pole_reaches_is_not_re_swept():
    """An unexplained band at 165–169 Hz (the same-direction crowd under the sidewall
    resonance, which every order group holds) beside another group's 167.4 Hz pole (ζ 0.02:
    half-width 3.3 Hz) is that mode seen in the group; a band at 14–35 Hz with the nearest
    pole at 53.4 Hz (half-width 1.1 Hz) is no pole's. A pole just out of reach (its
    half-width short of the band by a line) leaves the band far."""
    poles = [_pole(53.4, 0.02), _pole(167.4, 0.02)]
    bands = [(14.0, 35.0), (165.0, 169.0)]
    assert far_bands(bands, poles, 0.5) == [(14.0, 35.0)]
    assert far_bands([(14.0, 35.0)], [_pole(35.0 + 0.02 * 36.0 + 0.5, 0.02)], 0.5) == [(14.0, 35.0)]
    assert far_bands([(14.0, 35.0)], [_pole(35.5, 0.02)], 0.5) == []


def test_on_an_orthogonal_grid_only_a_crowd_of_other_groups_excuses_a_band():
    """Where the order groups are orthogonal a mode shows in no other group: a band beside
    one other group's pole (the n = 0 at 51.97 Hz, ζ 0.02, beside group 1's band about the
    n = 1 at 51.46 Hz) is swept again; a band that poles of two other groups reach (the
    crowd under the sidewall resonance) is not; a band the group's own pole reaches is not;
    with one group enough (a grid whose symmetry is broken: leaks) the band is not."""
    band = [(50.25, 53.0)]
    assert far_bands(band, [_pole(51.97, 0.02)], 0.25, [0], 2, own=1) == band
    assert far_bands(band, [_pole(51.97, 0.02), _pole(52.2, 0.02)], 0.25, [0, 3], 2, own=1) == []
    assert far_bands(band, [_pole(51.97, 0.02), _pole(52.2, 0.02)], 0.25, [0, 0], 2, own=1) == band
    assert far_bands(band, [_pole(51.97, 0.02)], 0.25, [1], 2, own=1) == []
    assert far_bands(band, [_pole(51.97, 0.02)], 0.25, [0], 1, own=1) == []
    assert far_bands(band, [_pole(60.0, 0.02)], 0.25, [0], 1, own=1) == band


@pytest.mark.parametrize("rows", [2, 6])
def test_noise_alone_gives_an_unexplained_band_rarely(rows):
    """Noise alone, its level drifting tenfold over the band: over 200 seeded draws, the
    share with any band is at the rule's false-alarm level (α = 1e-3 over the band,
    Bonferroni over its lines, a peak at least two lines wide: measured 0 of 1,000 draws
    for 2, 6 and 12 rows; one line over the level was 3.5 % of the draws with 6 rows, and a
    single level for the band, without the running median, flags most)."""
    level = lambda f: 1e-3 * (1 + 9 * f / f[-1])  # noqa: E731
    hits = sum(bool(unexplained_bands(F, _noise(np.random.default_rng(100 + k), level, rows), 0.0, []))
               for k in range(200))
    assert hits <= 2


@pytest.fixture(scope="module")
def ring_5120_rim(tmp_path_factory):
    """The validation matrix's 5,120 Hz ring combination (24 points, one hit, 2 % noise,
    mobility, Timoshenko belt and a free rim; seeded), its FRFs as ``run`` computes them,
    and its modal stage by default and without the rescue. Returns the generator's lower
    n = 1 rim mode (Hz) and the frequencies (Hz) of the two tables: default, without."""
    from unittest import mock

    from conftest import matrix_case_frfs

    from tiremodal_cli.modal import groupmodes, modes
    sim, r = matrix_case_frfs("ring:combo: sample_rate=5120.0, n_points=24, n_hits=1, noise=0.02, form=mobility, "
                              "physics=timoshenko+rim", tmp_path_factory.mktemp("ring_5120_rim"))
    default = modes.modal_table_from_frf(r)[0]
    with mock.patch.object(groupmodes, "unexplained_bands", lambda *a, **k: []):
        without = modes.modal_table_from_frf(r)[0]
    rim = min(m["frequency_hz"] for m in sim.truth["modes"] if m["branch"] == "rim" and m["n"] == 1)
    return rim, default, without


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_the_rim_mode_the_default_sweep_missed_is_found(ring_5120_rim):
    """The generator's rim n = 1 at 24.45 Hz (its peak 1,184 × the noise floor; the band
    0.5–1,320 Hz) got no pole up to order 30 of its group's sweep (main at f848314: no row
    within 50 % of it); the rescue's sweep at twice the order finds it within 0.3 %, read as
    n = 1 and not aliased (the ruler's rim mode). Without the rescue it is still lost."""
    rim, default, without = ring_5120_rim
    assert 24.0 < rim < 25.0
    f = np.asarray(default.frequency_hz, float)
    k = int(np.argmin(np.abs(f / rim - 1)))
    assert abs(f[k] / rim - 1) <= 0.003
    assert default.n[k] == 1 and default.n_spatial[k] == 1
    assert np.min(np.abs(np.asarray(without.frequency_hz, float) / rim - 1)) > 0.003


def test_no_re_sweep_when_the_lines_allow_no_higher_order():
    """A band of 90 lines holds a poly-reference sweep of order (90 − 2) / 3 = 29 at most and
    a single-reference one of 44: a group already swept that far is not swept again (the
    sweep would be the same), and nothing is added."""
    from dataclasses import replace

    from tiremodal_cli.modal.groupfit import GroupData
    from tiremodal_cli.modal.options import ModalOptions
    from tiremodal_cli.modal.rescue import with_rescued

    f = F[:90]
    data = GroupData(f, np.zeros((2, f.size), complex), np.eye(2), np.zeros((2, f.size), complex), "accelerance",
                     replace(ModalOptions(), poly_order=29), 1, 1, 2)

    def sweep(*a):
        raise AssertionError("swept again")

    assert with_rescued(data, None, [(10.0, 20.0)], sweep, 44) is None
