"""A weak mode in an order group of one reference (a grid's orders 0 and N/2, whose sine
column vanishes) is found by the stability of its pole, not of its shape
(:class:`~tiremodal_cli.modal.stabilization.StabilizationOptions` ``shapes``; docs/lsce.md,
"Session 52").

The truth is the pole–residue sum written here (two channels, accelerance; the 34-point
paper membrane's group 17: its in-phase n = 17 at 189.3 Hz, anti-phase n = 17 at 430.9 Hz
and the weak in-phase alias n = 51 at 325.7 Hz), not the estimator's model; the noise is
seeded complex Gaussian.
"""

import numpy as np

from tiremodal_cli.modal.groupfit import GroupData
from tiremodal_cli.modal.groupmodes import group_modes
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.options import ModalOptions

FREQ = np.arange(28.0, 800.0, 0.25)
#: (frequency Hz, ζ, tread, sidewall)
STRONG = [(189.3, 0.0376, 1.0, 0.8), (430.9, 0.0307, 1.0, -0.6)]
WEAK = (325.7, 0.0376, 0.012, 0.015)
SEEDS = range(8)


def _pole(f, zeta):
    w = 2 * np.pi * f
    return complex(-zeta * w, w * np.sqrt(1 - zeta**2))


def _rows(seed, level=0.01):
    """(2, K) accelerance rows; noise of std ``level`` × the rows' RMS."""
    jw = 2j * np.pi * FREQ
    out = np.zeros((2, FREQ.size), complex)
    for f, z, a, b in STRONG + [WEAK]:
        s = _pole(f, z)
        for c, amp in enumerate((a, b)):
            r = amp / (2j * s.imag) * 1e6
            out[c] += jw**2 * (r / (jw - s) + np.conj(r) / (jw - np.conj(s)))
    rng = np.random.default_rng(seed)
    sigma = level * np.sqrt(np.mean(np.abs(out) ** 2))
    return out + sigma * (rng.standard_normal(out.shape) + 1j * rng.standard_normal(out.shape)) / np.sqrt(2)


def _found(seed):
    rows = _rows(seed)
    data = GroupData(FREQ, rows, np.eye(2), rows, "accelerance", ModalOptions(band_hz=(28.0, 800.0)), 17, 1, 2)
    modes = group_modes(data, True, 40)[1]
    return np.array([poles_to_modal(np.array([m.pole]))[0][0] for m in modes])


def test_the_weak_alias_of_a_one_reference_group_is_found():
    """The weak mode's peak is 5 × the noise per line (its sidewall row): its pole is stable
    over the orders, its shape, fitted each order beside the poles the sweep spends on the
    noise, is not. Found within the ruler's 0.3 % in at least 7 of 8 seeded draws (with the
    shape test: 3 of 8, and one pole 0.66 % off), the strong modes in all, and no pole off
    every truth mode."""
    truth = np.array([STRONG[0][0], STRONG[1][0], WEAK[0]])
    hits = 0
    for seed in SEEDS:
        f = _found(seed)
        err = np.abs(f[:, None] / truth[None, :] - 1)
        assert np.all(err.min(axis=1) < 0.003), f  # no pole off every truth mode
        assert np.all(err[:, :2].min(axis=0) < 0.003), f  # the strong ones
        hits += bool(err[:, 2].min() < 0.003)
    assert hits >= 7
