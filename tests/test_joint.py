"""A grid with missing points: an unfound order proposed from its branch's dispersion and
refined jointly in the physical FRFs (modal.joint).

Truth from a modal sum written here, not by the code under test: a branch of tread–sidewall
modes in opposite phase, order n at f(n) = 300 + 15 n Hz with ζ = 3 % (half-power bands
overlapping their neighbours', as the paper's opposite branch), residues cos(nθ + φ_n) at
19 of 24 points. The modes found are given without order 8 (the one the group sweeps
missed); the FRFs hold it, and the branch has no order 12, which the extrapolated
dispersion proposes too: the first must be found within 0.3 %, the second must not be.
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.modal.classify import classify
from tiremodal_cli.modal.joint import add_missing_orders, aliased_group, threshold
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import synthesize
from tiremodal_cli.modal.merge import MergedMode

N_GRID, FAILED = 24, [1, 14, 15, 17, 23]
ORDERS = range(4, 12)
ZETA = 0.03


def _f(n):
    return 300.0 + 15.0 * n


def _branch(seed, missing=8, drop_from_data=False):
    rng = np.random.default_rng(seed)
    th = 2 * np.pi * np.array([i for i in range(N_GRID) if i not in FAILED]) / N_GRID
    freq = np.arange(300.0, 560.0, 0.5)
    modes, poles, res = [], [], []
    for n in ORDERS:
        w = 2 * np.pi * _f(n)
        s = complex(-ZETA * w, w * np.sqrt(1 - ZETA**2))
        pattern = np.cos(n * th + rng.uniform(0, 2 * np.pi))
        R = (-1j * np.array([1.0, -0.8])[:, None] * pattern[None, :] / w).ravel()  # tread, sidewall opposite
        if not (drop_from_data and n == missing):
            poles.append(s)
            res.append(R)
        if n != missing:
            modes.append(MergedMode(s, aliased_group(n, N_GRID), R, 0.9, {aliased_group(n, N_GRID): 1.0}, 0.9, 0.0))
    H = synthesize(freq, np.array(res).T, np.array(poles))
    scale = np.sqrt(np.mean(np.abs(H) ** 2))
    H = H + 0.02 * scale * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    synth = synthesize(freq, np.array([m.residues for m in modes]).T, np.array([m.pole for m in modes]))
    return freq, H.reshape(2, th.size, -1), th, modes, synth


@pytest.mark.parametrize("seed", [0, 1])
def test_a_missed_order_is_found_where_the_dispersion_puts_it_and_an_absent_one_is_not(seed):
    freq, Hb, th, modes, synth = _branch(seed)
    out, synth2, rejected = add_missing_orders(freq, Hb, th, ["tread", "sidewall"], modes, synth)
    f, z = poles_to_modal(np.array([m.pole for m in out]))
    assert len(out) == len(modes) + 1
    new = [i for i, m in enumerate(out) if m.group == aliased_group(8, N_GRID)]  # the only mode of its group
    assert len(new) == 1 and abs(f[new[0]] / _f(8) - 1) < 0.003  # the truth, within the ruler's 0.3 %
    shapes = np.array([m.residues for m in out]).reshape(len(out), 2, th.size)
    c = classify(f, shapes, th, ["tread", "sidewall"], np.ones(len(out)), z)
    assert (c[new[0]].n, c[new[0]].branch) == (8, "opposite")
    assert not np.any(np.abs(f - _f(12)) < ZETA * _f(12))  # no order 12 in the FRFs: not kept
    assert any("n = 12" in r["reason"] for r in rejected)
    # the added mode's synthesis takes its response out of the residual
    assert np.linalg.norm(Hb.reshape(-1, freq.size) - synth2) < 0.5 * np.linalg.norm(Hb.reshape(-1, freq.size) - synth)


def test_threshold_is_the_chi2_quantile_of_a_fit_to_noise():
    """ΔE of p complex residues and a pole fitted to noise alone: χ²(2p + 2)/2; its 1 − α/K
    quantile, checked against a seeded draw of that distribution."""
    rng = np.random.default_rng(5)
    p, K = 4, 500
    draws = rng.chisquare(2 * p + 2, 200_000) / 2
    t = threshold(p, K, alpha=0.5 * K)  # α/K = 0.5: the median
    assert abs(np.mean(draws > t) - 0.5) < 0.01
    assert threshold(p, K) > threshold(p, K // 10) > np.median(draws)
