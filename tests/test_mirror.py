"""A grid's missing points read from their mirror images about the sensors' plane
(``modal.mirror``; docs/lsce.md, session 22), when the test's own mirrored points show the
symmetry, and only then."""

import dataclasses

import numpy as np
import pytest

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.modal.mirror import mirror_filled
from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.validation import config_for, matrix

FAILED_POINTS = "paper:combo: sample_rate=2560.0, n_points=24, n_hits=1, noise=0.02, faults=bounced+overload, " \
                "physics=timoshenko+rim"


def _test_without(case, drop):
    """The case's simulation (its faults off), its FRFs as ``run`` estimates them, the points ``drop`` left out."""
    sim = simulate(config_for(case))
    r = compute_frf(sim.measurement, FRFOptions(band_hz=(0.0, 0.390625 * case.sample_rate), exp_end=0.05))
    keep = np.setdiff1d(np.arange(r.point_index.size), drop)
    return sim, dataclasses.replace(r, H=r.H[:, keep], coherence=r.coherence[:, keep],
                                    n_averages=r.n_averages[keep], point_index=r.point_index[keep],
                                    point_angle=r.point_angle[keep], force_autospectrum=r.force_autospectrum[keep])


@pytest.fixture(scope="module")
def failed_points_case():
    return dataclasses.replace(next(c for c in matrix() if c.name == FAILED_POINTS), faults="none")


def test_a_missing_point_is_its_mirror_and_the_truth_agrees(failed_points_case):
    """An axisymmetric tyre, the sensors at 0°: the point at 75° missing is read from the one
    at 285°, exactly, and that is the generator's FRF at 75° within the test's noise (the
    median error of a measured point's FRF); the point at 0°, on the sensors' plane, is its
    own mirror and stays a gap."""
    sim, r = _test_without(failed_points_case, [0, 5])
    full, measured, info = mirror_filled(r, (0.5, 1000.0))
    assert info["gaps_deg"] == [0.0] and [f["angle_deg"] for f in info["filled"]] == pytest.approx([75.0])
    assert info["antisymmetric_share"] < 0.05
    assert measured.tolist() == [True] * 4 + [False] + [True] * 18
    j = int(np.flatnonzero(~measured)[0])
    src = int(np.flatnonzero(r.point_index == 19)[0])  # 285°
    assert np.array_equal(full.H[:, j], r.H[:, src]) and full.point_index[j] == -1
    sel = (sim.freq_hz >= 20) & (sim.freq_hz <= 900)
    lines = (r.freq_hz >= 20) & (r.freq_hz <= 900)
    err = lambda H, p: np.median(np.abs(H[:2, lines] - sim.frf[:2, p, sel]) / np.abs(sim.frf[:2, p, sel]))
    assert err(full.H[:, j], 5) < 2 * np.median([err(r.H[:, k], p) for k, p in enumerate(r.point_index)])


def test_an_asymmetric_tyre_keeps_its_gaps():
    """The ring with a lumped mass off the sensors' plane: its mirrored points differ (an
    antisymmetric part of 0.17 of the symmetric one), so nothing is filled and the reason
    says so."""
    case = next(c for c in matrix() if c.name == "ring:physics=mass")
    _, r = _test_without(case, [3, 20])
    full, measured, info = mirror_filled(r, (0.5, 700.0))
    assert full is r and measured is None
    assert info["filled"] == [] and info["gaps_deg"] == pytest.approx([3 * 360 / 34, 20 * 360 / 34]) and info["antisymmetric_share"] > 0.1
    assert "differ" in info["reason"]


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_failed_points_read_from_their_mirrors_give_every_expected_mode(failed_points_case):
    """Five of the 24 points of the one-hit 2 % noise Timoshenko + rim test missing, each
    with its mirror measured: the modal stage finds every expected truth mode of the full
    grid (the validation ruler; the gappy-grid path found 47 of 65, ``benchmarks/gaps_sweep.py``,
    before session 29's ruler left out the opposite n = 56 … 59, in crowds with aliases the
    generator does not list, above its n ≤ 60, on the Timoshenko-flattened branch), and its table holds the 19 measured points only."""
    from tiremodal_cli.modal.modes import modal_table_from_frf
    from tiremodal_cli.modal.options import ModalOptions
    from tiremodal_cli.workflow.validation_scoring import expected_groups, score_modes

    import sys
    from pathlib import Path
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    from gaps_sweep import rows_of

    drop = [1, 8, 10, 11, 20]
    sim, r = _test_without(failed_points_case, drop)
    table, _ = modal_table_from_frf(r, ModalOptions(order_within_band=True))
    assert len(table.meta["mirrored_points"]["filled"]) == 5 and table.meta["mirrored_points"]["gaps_deg"] == []
    assert table.point_index.tolist() == [p for p in range(24) if p not in drop] and table.shapes.shape[-1] == 19
    sc = score_modes(expected_groups(sim, config_for(failed_points_case)), rows_of(table), sim.truth["modes"])
    assert sc["found"] == sc["expected"] == 61, [d for d in sc["detail"] if d["status"] != "found"]
    assert sc["spurious"] <= 0.05 * sc["adopted"]


def test_a_sensor_whose_angle_is_unknown_fills_nothing(failed_points_case):
    """One channel's angle not known (NaN, as a UFF response without geometry gives): the
    other channels show the symmetry, but that channel has no mirror image, so no point is
    filled — and nothing fails."""
    _, r = _test_without(failed_points_case, [5])
    ang = np.array(r.channel_angle, dtype=float)
    ang[1] = np.nan
    full, measured, info = mirror_filled(dataclasses.replace(r, channel_angle=ang), (0.5, 1000.0))
    assert measured is None and info["filled"] == [] and info["gaps_deg"] == [75.0]
