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


def test_the_rising_rule_names_only_the_proposals_of_a_falling_pair():
    """Found opposite orders 4, 6, 9 at 360, 390, 435 Hz; proposals n = 5 at 375 Hz (between
    its neighbours) and n = 10 at 430 Hz (below n = 9): only the second breaks the rise."""
    from tiremodal_cli.modal.joint import Proposal, _falling, _Problem

    def pole(f):
        w = 2 * np.pi * f
        return complex(-ZETA * w, w * np.sqrt(1 - ZETA**2))

    found = np.array([pole(360.0), pole(390.0), pole(435.0)])
    prob = _Problem(np.arange(300.0, 500.0), None, None, {}, found, [], [(4, "opposite"), (6, "opposite"),
                    (9, "opposite")], 2, 200)
    props = [Proposal(5, "opposite", 5, pole(375.0)), Proposal(10, "opposite", 10, pole(430.0))]
    poles = np.concatenate([found, [p.pole for p in props]])
    assert _falling(prob, poles, np.arange(3), props) == {1}
    props[1] = Proposal(10, "opposite", 10, pole(445.0))
    assert _falling(prob, np.concatenate([found, [p.pole for p in props]]), np.arange(3), props) == set()


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_a_crowd_frees_the_found_mode_its_response_biased():
    """A flat stretch of the branch, f(n) = 300 + 3 n Hz (ζ = 3 %): orders 11 and 13 (one
    aliased group on 24 points) lie within a bandwidth of each other and are both unfound — a
    crowd, held where the dispersion puts it. The found n = 10 is given 0.4 % high (the bias their
    unmodelled response puts on it); refined about the held crowd it must come within 0.3 % of
    the truth, and no crowd is reported."""
    rng = np.random.default_rng(0)
    th = 2 * np.pi * np.array([i for i in range(N_GRID) if i not in FAILED]) / N_GRID
    freq = np.arange(280.0, 400.0, 0.5)

    def pole(f):
        w = 2 * np.pi * f
        return complex(-ZETA * w, w * np.sqrt(1 - ZETA**2))

    modes, poles, res = [], [], []
    for n in range(4, 21):
        s = pole(300.0 + 3.0 * n)
        pattern = np.cos(n * th + rng.uniform(0, 2 * np.pi))
        R = (-1j * np.array([1.0, -0.8])[:, None] * pattern[None, :] / s.imag).ravel()
        poles.append(s)
        res.append(R)
        if n not in (11, 13):
            g = aliased_group(n, N_GRID)
            modes.append(MergedMode(pole((300.0 + 3.0 * n) * (1.004 if n == 10 else 1)), g, R, 0.9, {g: 1.0}, 0.9, 0.0))
    H = synthesize(freq, np.array(res).T, np.array(poles))
    H = H + 0.02 * np.sqrt(np.mean(np.abs(H) ** 2)) * (rng.standard_normal(H.shape)
                                                        + 1j * rng.standard_normal(H.shape)) / np.sqrt(2)
    synth = synthesize(freq, np.array([m.residues for m in modes]).T, np.array([m.pole for m in modes]))
    out = add_missing_orders(freq, H.reshape(2, th.size, -1), th, ["tread", "sidewall"], modes, synth)[0]
    assert len(out) == len(modes)  # the crowd is never reported
    f = poles_to_modal(np.array([m.pole for m in out]))[0]
    n10 = [f[i] for i, m in enumerate(out) if m.group == 10 and abs(f[i] - 330.0) < 3.0]
    assert len(n10) == 1 and abs(n10[0] / 330.0 - 1) < 0.003
