"""Blends of one order group refitted with real-mode copies (:mod:`tiremodal_cli.modal.group_blends`).

The FRFs are made from the modal model's definition — real modes (each residue imaginary:
φφᵀ/(2jω_d m)), a lumped mass's coupling giving the neighbouring orders' modes a share of
the group's harmonic — not by the estimator; the truth is the poles they were made with."""

from types import SimpleNamespace

import numpy as np
import pytest

from tiremodal_cli.modal.group_blends import refined_blends, suspect_clusters
from tiremodal_cli.modal.lsfd import synthesize
from tiremodal_cli.modal.modes import ModalResult

ZETA = 0.02
N_POINTS = 20


def _pole(f_hz, zeta=ZETA):
    w = 2 * np.pi * f_hz
    return complex(-zeta * w, w * np.sqrt(1 - zeta**2))


#: (frequency Hz, order, the share of harmonic 9 in its shape): the 20-point grid's group 9
#: holds n = 9 and its alias n = 11; the mass gives n = 8 and 10 a share of harmonic 9, and
#: anti-phase pairs elsewhere give the test a median splitting (0.5 %)
MODES = [(147.7, 8, 0.25), (153.2, 9, 0.0), (156.9, 10, 0.25), (159.4, 11, 0.0),
         (300.0, 4, 0.0), (301.5, 4, 0.0), (400.0, 6, 0.0), (402.0, 6, 0.0), (500.0, 7, 0.0), (502.5, 7, 0.0)]


def _frfs(seed):
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * np.arange(N_POINTS) / N_POINTS
    chan = np.array([1.0, 0.7])  # tread and sidewall, in phase
    s = np.array([_pole(f) for f, _, _ in MODES])
    shapes = [np.cos(n * theta) + c9 * np.cos(9 * theta) for _, n, c9 in MODES]
    R = np.array([1e3j * np.outer(chan, shape).ravel() / (2 * sk.imag) * 1e3 for sk, shape in zip(s, shapes)]).T
    freq = np.arange(120.0, 560.0, 0.25)
    H = synthesize(freq, R, s).reshape(2, N_POINTS, -1)
    H = H + 1e-3 * np.abs(H).max() * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    return freq, H, theta, s, R


def _table(table_poles, groups, ns, pairs, R_guess):
    f = np.array([p.imag for p in table_poles]) / (2 * np.pi)
    res = ModalResult(freq_hz=f, damping_ratio=np.array([-p.real / abs(p) for p in table_poles]),
                      poles=np.array(table_poles), shapes=R_guess, mpc=np.ones(f.size),
                      significance=np.full(f.size, 0.5), group=np.array(groups),
                      fit_error=np.zeros((2, N_POINTS)), synthesis=np.zeros((2, N_POINTS, 1)), band_freq_hz=f)
    classes = [SimpleNamespace(n=n, branch="same" if n in (8, 9, 10) else "opposite", pair=p)
               for n, p in zip(ns, pairs)]
    return res, classes


def _blended(truth, R):
    """The table's rows: n = 8 and 10 right in their groups, group 9 as three blends read n = 9
    (152.48, 154.95 at ζ 3.4 % and 158.63 Hz at 4.2 %, as the held-out 20-point ring + mass
    was read), the pairs right."""
    poles = [truth[0], _pole(152.48), _pole(154.95, 0.034), truth[2], _pole(158.63, 0.042)] + list(truth[4:])
    shapes = np.zeros((len(poles), 2, N_POINTS), complex)
    return _table(poles, [8, 9, 9, 10, 9, 4, 4, 6, 6, 7, 7], [8, 9, 9, 10, 9, 4, 4, 6, 6, 7, 7],
                  [None] * 5 + [1, 1, 2, 2, 3, 3], shapes)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_three_blends_become_the_groups_two_modes(seed):
    """Group 9's three blended rows end as two rows within 0.05 % of n = 9 and n = 11, the
    third dropped as redundant; the other rows do not move."""
    freq, H, theta, truth, R = _frfs(seed)
    res, classes = _blended(truth, R)
    out, moves = refined_blends(res, classes, freq, H, theta)
    assert len(moves) == 1 and len(moves[0]["dropped_hz"]) == 1
    g9 = np.sort(out.poles[out.group == 9].imag)
    assert g9.size == 2
    assert np.all(np.abs(g9 / truth[[1, 3]].imag - 1) < 5e-4), g9 / (2 * np.pi)
    others = out.poles[out.group != 9]
    assert np.allclose(others, truth[[0, 2, 4, 5, 6, 7, 8, 9]])
    assert len(out.rejected) == len(res.rejected) + 1


@pytest.mark.parametrize("seed", [0, 1])
def test_a_right_table_stays(seed):
    """Group 9 read right (n = 9 and n = 11 both read as n = 9, as a 20-point grid may): the
    rule fires on two rows split beyond the mass's fraction, and the refit leaves them within
    0.05 % of the truth, dropping none."""
    freq, H, theta, truth, R = _frfs(seed)
    res, classes = _table(list(truth), [8, 9, 10, 9, 4, 4, 6, 6, 7, 7], [8, 9, 10, 9, 4, 4, 6, 6, 7, 7],
                          [None] * 4 + [1, 1, 2, 2, 3, 3], np.zeros((truth.size, 2, N_POINTS), complex))
    assert [list(c) for c in suspect_clusters(res.freq_hz, -truth.real / (2 * np.pi), res.group, classes)] == [[1, 3]]
    out, moves = refined_blends(res, classes, freq, H, theta)
    assert out.poles.size == truth.size
    assert np.all(np.abs(out.poles.imag / truth.imag - 1) < 5e-4)


def test_rows_a_mass_could_split_are_not_suspects():
    """Two rows of one order split by no more than twice the test's median pair, or two rows
    on a test with fewer than three pairs to take a median from, are left alone; a pair's
    members never form a cluster."""
    f = np.array([153.2, 153.9, 300.0, 301.5, 400.0, 402.0, 500.0, 502.5])
    hw = 0.02 * f
    group = np.array([9, 9, 4, 4, 6, 6, 7, 7])
    cls = [SimpleNamespace(n=n, branch="opposite", pair=p)
           for n, p in zip([9, 9, 4, 4, 6, 6, 7, 7], [None, None, 1, 1, 2, 2, 3, 3])]
    assert suspect_clusters(f, hw, group, cls) == []  # 0.46 % against a median 0.5 %
    f2 = f.copy()
    f2[1] = 156.5  # 2.1 %: beyond twice the median
    assert [list(c) for c in suspect_clusters(f2, 0.02 * f2, group, cls)] == [[0, 1]]
    few = [c if c.pair != 3 else SimpleNamespace(n=7, branch="opposite", pair=None) for c in cls]
    few[7] = SimpleNamespace(n=8, branch="opposite", pair=None)
    assert suspect_clusters(f2, 0.02 * f2, group, few) == []  # two pairs: no median
    crowded = [SimpleNamespace(n=c.n, branch=c.branch, pair=c.pair, crowd=i < 2) for i, c in enumerate(cls)]
    assert suspect_clusters(f2, 0.02 * f2, group, crowded) == []  # a crowd's rows stand for other orders
    one = [SimpleNamespace(n=c.n, branch=c.branch, pair=c.pair, crowd=i == 1) for i, c in enumerate(cls)]
    assert [list(c) for c in suspect_clusters(f2, 0.02 * f2, group, one)] == [[0]]  # in the chain, never free
