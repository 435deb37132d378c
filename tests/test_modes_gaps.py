"""A roving-hammer test whose points failed (every hit of a point rejected) keeps its grid.

Truths of discrete Fourier analysis and of the simulated tyre, not of the code: the points
left of a uniform grid alias as the whole grid does (n and N − n on N points, whatever is
missing); the grid's harmonics are orthogonal over the whole grid, so over a subset the
minimum-norm fit keeps each order mostly in its own group and reproduces the data at the
points; and the modes of a simulated tyre with points removed are those of the tyre.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tiremodal_cli.frf.estimate import compute_frf
from tiremodal_cli.modal.classify import classify
from tiremodal_cli.modal.modes import ModalOptions, modal_table_from_frf
from tiremodal_cli.modal.spatial import decompose, grid_points, leakage
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

# the ring case of the validation matrix that read wholesale wrong: 9 of 40 points failed
FAILED_40 = [6, 12, 13, 16, 20, 21, 24, 30, 35]


def _subset(n_grid, failed, offset=0.0):
    keep = np.array([i for i in range(n_grid) if i not in failed])
    return offset + 2 * np.pi * keep / n_grid


@pytest.mark.parametrize("offset", [0.0, 0.3])
def test_the_grid_of_points_with_gaps_rolled_or_decreasing(offset):
    th = _subset(40, FAILED_40, offset)
    for angles in (th, np.roll(th, 7), th[::-1]):
        assert grid_points(angles) == 40
    assert grid_points(_subset(24, [1, 14, 15, 17, 23])) == 24
    assert grid_points(np.sort(np.random.default_rng(3).uniform(0, 2 * np.pi, 10))) == 10  # on no grid
    # 48 points every 7.5° stored in whole degrees lie on the 360-point grid: no failed points
    assert grid_points(np.radians(np.round(np.arange(48) * 7.5))) == 48


def test_gaps_keep_each_order_in_its_group_and_reproduce_the_data():
    """31 of 40 points: a pattern of order m ≤ 20 is reproduced exactly at the points, its
    own group holds most of it, and no other group more than the stated leakage; on the
    complete grid the leakage is zero."""
    th = _subset(40, FAILED_40)
    leak = leakage(th)
    rng = np.random.default_rng(4)
    for m in (0, 3, 11, 19):
        phi = rng.uniform(0, 2 * np.pi)
        H = np.cos(m * th + phi)[None, :, None] * np.ones((1, 1, 2))
        groups = decompose(H, th)
        assert sorted(groups) == list(range(21))
        total = sum(back @ rows for rows, back in groups.values()).reshape(H.shape)
        np.testing.assert_allclose(total, H, atol=1e-10)
        amp = {n: np.linalg.norm(rows[:, 0]) for n, (rows, _) in groups.items()}
        assert amp[m] > 0.6 * max(abs(np.cos(phi)), abs(np.sin(phi)), 0.7)  # its own group holds most of it
        for n in amp:
            if n != m:
                assert amp[n] <= leak[(n, m)] * amp[m] * (1 + 1e-9)
    assert max(leakage(2 * np.pi * np.arange(40) / 40).values()) < 1e-12
    assert 0.05 < max(leak.values()) < 0.5


def test_aliases_of_a_grid_with_gaps_are_those_of_the_whole_grid():
    """On 31 of 40 points the same branch's n = 4 … 20 then 36 (spatial order 4) reads as
    n = 36 = 40 − 4, not 27 = 31 − 4."""
    th = _subset(40, FAILED_40)
    orders = list(range(4, 21)) + [36]
    freq = 100.0 + 3.0 * np.arange(len(orders))
    shapes = np.array([[np.cos(n * th), 0.8 * np.cos(n * th)] for n in orders], dtype=complex)
    c = classify(freq, shapes, th, ["tread", "sidewall"], significance=np.ones(len(orders)))
    assert [x.n for x in c] == orders
    assert c[-1].aliased and c[-1].n_spatial == 4


@pytest.fixture(scope="module")
def gappy():
    """The seed model on 24 points, one hit, five points failed (as a bounced or clipped
    hit leaves them), through frf and lsce in 40–250 Hz."""
    s = simulate(SimulationConfig(n_points=24, n_hits=1, sample_rate=1024.0, n_samples=2048, noise=0.005, seed=5,
                                  params=TyreParameters(m_w=1000.0)))
    r = compute_frf(s.measurement)
    keep = np.array([i for i in range(24) if i not in (1, 14, 15, 17, 23)])
    # the sensors' angles withheld: the gaps stay gaps (with them, three of the five are read
    # from their mirror images, modal.mirror, and the grid path is another one)
    r = dataclasses.replace(r, H=r.H[:, keep], coherence=r.coherence[:, keep], n_averages=r.n_averages[keep],
                            point_index=r.point_index[keep], point_angle=r.point_angle[keep], channel_angle=None)
    table, res = modal_table_from_frf(r, ModalOptions(band_hz=(40, 250)))
    return s.truth, table, res


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_modes_of_a_test_with_failed_points(gappy):
    """Every same n ≤ 7 and opposite n = 4 … 8 mode in the band found once within 0.3 %
    with its n and branch (no copy seen through the gaps in another order group is
    reported beside it). Known limit: the opposite n = 0 … 3, four modes within 3 Hz (less
    than half a bandwidth), are not all resolved with 5 of 24 points missing."""
    truth, t, res = gappy
    cos = [m for m in truth["modes"] if m["harmonic"] == "cos"]
    want = [m for m in cos if 45 <= m["frequency_hz"] <= 245
            and ((m["branch"] == "same" and m["n"] <= 7) or (m["branch"] == "opposite" and 4 <= m["n"] <= 8))]
    assert len(want) == 8 + 5
    for m in want:
        near = np.flatnonzero(np.abs(t.frequency_hz / m["frequency_hz"] - 1) <= 3e-3)
        ok = [k for k in near if t.n[k] == m["n"] and t.branch[k] == m["branch"]]
        assert len(ok) == 1 and len(near) == 1, (m["n"], m["branch"], m["frequency_hz"], t.frequency_hz[near], t.n[near])
    assert any("missing points" in d["reason"] for d in res.rejected)


def test_found_modes_are_read_out_of_the_leaks():
    """19 of 24 points, four modes of orders 2, 3, 5 and 12 within a bandwidth of each
    other: given their poles and orders, each group's rows are the true harmonic
    coefficients of its own modes (cos(mθ + α) = cos α cos mθ − sin α sin mθ), to the
    noise; the plain minimum-norm rows differ from them by the leaks of the others."""
    from tiremodal_cli.modal.gaps import cleaned_groups, order_lsfd
    from tiremodal_cli.modal.lsfd import synthesize
    from tiremodal_cli.modal.spatial import grid_design

    th = _subset(24, [1, 14, 15, 17, 23])
    rng = np.random.default_rng(11)
    freq = np.arange(150.0, 250.0, 0.25)
    orders, fn = [2, 3, 5, 12], [195.0, 198.0, 200.0, 203.0]
    s = np.array([-0.02 * 2 * np.pi * f + 2j * np.pi * f * np.sqrt(1 - 0.02**2) for f in fn])
    phi = rng.normal(size=(len(orders), 2)) + 1j * rng.normal(size=(len(orders), 2)) * 0.1  # (mode, channel)
    alpha = rng.uniform(0, 2 * np.pi, len(orders))
    D, names = grid_design(th)
    truth = np.zeros((len(names), 2, freq.size), dtype=complex)  # (grid column, channel, K)
    H = np.zeros((2, th.size, freq.size), dtype=complex)
    for r, m in enumerate(orders):
        B = synthesize(freq, phi[r][:, None], s[[r]])  # (channel, K), unit pattern
        H += np.cos(m * th + alpha[r])[None, :, None] * B[:, None, :]
        for k, (n, kind) in enumerate(names):
            if n == m:
                truth[k] += (np.cos(alpha[r]) if kind == "cos" else -np.sin(alpha[r])) * B
    scale = np.abs(H).max()
    H_noisy = H + 1e-3 * scale * (rng.normal(size=H.shape) + 1j * rng.normal(size=H.shape))
    X = order_lsfd(freq, H, th, s, [{m} for m in orders])
    assert X.shape == (4, len(names), 2)
    plain = decompose(H_noisy, th)
    for H_, tol in ((H, 1e-8), (H_noisy, 1e-2)):
        clean = cleaned_groups(freq, H_, th, s, [{m} for m in orders])
        for n, (rows, _) in clean.items():
            ks = [k for k, (m, _) in enumerate(names) if m == n]
            want = truth[ks].reshape(len(ks) * 2, -1)
            assert np.linalg.norm(rows - want) <= tol * scale * np.sqrt(rows.size), n
    # the leaks the second reading removes are large (the test can fail)
    ks = [k for k, (m, _) in enumerate(names) if m == 5]
    assert np.linalg.norm(plain[5][0] - truth[ks].reshape(len(ks) * 2, -1)) > 0.1 * np.linalg.norm(truth[ks])


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_overlapping_modes_of_a_test_with_failed_points(gappy):
    """With the found modes read out of the leaks, the same branch's n ≤ 11 and the
    opposite n = 2 … 8 are found within 0.3 % with their n and branch (with the leaks
    left in, the same n = 11, 2.5 Hz from n = 10 and 12, and the opposite n = 2, 1.2 Hz
    from n = 3, were lost)."""
    truth, t, _ = gappy
    want = [m for m in truth["modes"] if m["harmonic"] == "cos" and 45 <= m["frequency_hz"] <= 245
            and ((m["branch"] == "same" and m["n"] <= 11) or (m["branch"] == "opposite" and 2 <= m["n"] <= 8))]
    assert len(want) == 12 + 7
    for m in want:
        near = np.flatnonzero(np.abs(t.frequency_hz / m["frequency_hz"] - 1) <= 3e-3)
        assert any(t.n[k] == m["n"] and t.branch[k] == m["branch"] for k in near), (m["n"], m["branch"])


def test_poles_fitted_to_noise_are_dropped_by_the_noise_floor():
    """31 of 40 points, three channels, FRFs of complex Gaussian noise plus one order-3 mode
    at 120 Hz. A pole fitted to the noise of an order group's rows (fixed, not searched)
    explains about √(p / N) of the physical response in its window — p residues of its
    group's rows against N values there (least squares on noise is a projection) — often
    more than the 5 % share rule asks; its energy there against the noise (the generator's)
    is χ²(2p)/2, under the 1 − 10⁻³/K quantile: every one is dropped; the mode, 10 × the
    noise, is kept."""
    from tiremodal_cli.modal.gaps import weak_in_frfs
    from tiremodal_cli.modal.lsfd import lsfd, significance, synthesize
    from tiremodal_cli.modal.merge import MergedMode

    th = _subset(40, FAILED_40)
    rng = np.random.default_rng(21)
    freq = np.arange(0.5, 200.0, 0.5)
    n_c = 3
    H = (rng.normal(size=(n_c, th.size, freq.size)) + 1j * rng.normal(size=(n_c, th.size, freq.size))) / np.sqrt(2)
    zeta = 0.01
    s_mode = -zeta * 2 * np.pi * 120.0 + 2j * np.pi * 120.0 * np.sqrt(1 - zeta**2)
    unit = synthesize(freq, np.ones((1, 1)), [s_mode])[0]
    H_mode = 10 * np.cos(3 * th + 0.4)[None, :, None] * rng.normal(size=n_c)[:, None, None] * (unit / np.abs(unit).max())
    H = H + H_mode
    groups = decompose(H, th)
    flat = H.reshape(-1, freq.size)
    poles = [(3, s_mode)] + [(g, -0.01 * 2 * np.pi * f + 2j * np.pi * f) for g in (0, 1, 7) for f in (15, 40, 65, 90, 170)]
    modes = []
    for g, s in poles:
        rows, back = groups[g]
        phys = back @ lsfd(freq, rows, np.array([s])).residues[:, 0]
        sig = float(significance(freq, flat, phys[:, None], np.array([s]))[0])
        modes.append(MergedMode(s, g, phys, sig, {g: 1.0}, sig, 0.0))
    kept, dropped = weak_in_frfs(modes, 0.05, freq, th, (H - H_mode).reshape(-1, freq.size))
    assert [m.pole for m in kept] == [s_mode]
    assert len(dropped) == len(poles) - 1
    assert sum(m.significance >= 0.05 for m in modes[1:]) >= 3  # the share rule alone keeps noise poles


def test_a_mode_held_to_more_orders_than_there_are_points_keeps_bounded_residues():
    """19 of 24 points: a mode merged from many groups holds orders 0…11 (23 of the grid's
    columns), more than the 19 points can tell apart, so its residues have a null space. The
    order-held LSFD must return the minimum-norm residues, of the data's size and
    reproducing the FRFs — not residues ~10¹¹ × the data's that cancel at the points
    (session 14: the cleaned groups of the paper's failed-points combination at other seeds
    held 10²⁶ × the data's energy, and every mode was lost)."""
    from tiremodal_cli.modal.gaps import order_lsfd
    from tiremodal_cli.modal.lsfd import synthesize
    from tiremodal_cli.modal.spatial import grid_design

    rng = np.random.default_rng(0)
    ang = _subset(24, [2, 4, 7, 14, 22])
    freq = np.arange(100.0, 300.0, 0.5)
    w = 2 * np.pi * np.array([150.0, 180.0, 220.0])
    s = -0.02 * w + 1j * w
    orders = [{2}, set(range(12)), {5}]
    H = np.zeros((2, ang.size, freq.size), complex)
    for r, o in enumerate(orders):
        res = np.outer([1.0, -0.5], np.cos(min(o) * ang)) * (1 + 0.3j)
        H += synthesize(freq, res.reshape(-1, 1), [s[r]]).reshape(2, ang.size, -1)
    H += 1e-3 * np.abs(H).max() * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    X = order_lsfd(freq, H, ang, s, orders)
    assert np.abs(X).max() < 10  # the true residues are ≤ 1.05 on each column
    D, _ = grid_design(ang)
    fit = np.einsum("pk,kcf->cpf", D, synthesize(freq, X.transpose(1, 2, 0).reshape(-1, 3), s).reshape(-1, 2, freq.size))
    assert np.linalg.norm(fit - H) / np.linalg.norm(H) < 0.05  # the modes reproduce the FRFs
