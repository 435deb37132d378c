"""A weak mode beside a strong one of its order group (modal.beside): found where it is, and
no pole added for noise, for a strong pole's bias or for a second pole of the same shape.

The truth is the pole–residue sum written here (two references, two channels, accelerance),
not the estimator's model; the noise is seeded complex Gaussian.
"""

import numpy as np
import pytest

from tiremodal_cli.modal.beside import beside_poles
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import lsfd_participation

FREQ = np.arange(200.0, 420.0, 0.5)
STRONG = dict(f=300.0, zeta=0.03, psi=np.array([1.0, 0.3]), L=np.array([1.0, 0.2j]))
# half a bandwidth above the strong mode (its half-power half-width is 9 Hz): 6 Hz, 0.67 half-widths;
# a sidewall-dominated shape (the in-phase mode beside the tread's anti-phase one)
WEAK = dict(f=306.0, zeta=0.035, psi=0.06 * np.array([0.15, -1.0]), L=np.array([1.0, 0.3]))


def _pole(f, zeta):
    w = 2 * np.pi * f
    return complex(-zeta * w, w * np.sqrt(1 - zeta**2))


def _rows(*modes):
    """Reference-major rows (2 references · 2 channels, K) of accelerance."""
    jw = 2j * np.pi * FREQ
    out = np.zeros((4, FREQ.size), dtype=complex)
    for m in modes:
        s = _pole(m["f"], m["zeta"])
        for h in range(2):
            for c in range(2):
                r = m["psi"][c] * m["L"][h]
                out[2 * h + c] += jw**2 * (r / (jw - s) + np.conj(r) / (jw - np.conj(s)))
    return out


def _noisy(rows, seed, level=2e-3):
    rng = np.random.default_rng(seed)
    sigma = level * np.max(np.abs(rows))
    return rows + sigma * (rng.standard_normal(rows.shape) + 1j * rng.standard_normal(rows.shape)) / np.sqrt(2)


def _fit(rows, s, L):
    """The group's fit with the kept poles ``s`` (participations ``L``)."""
    Y = rows.reshape(2, 2, -1).transpose(1, 0, 2)
    return lsfd_participation(FREQ, Y, np.atleast_1d(s), np.atleast_2d(L))[1].transpose(1, 0, 2).reshape(rows.shape)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_weak_mode_beside_a_strong_one_is_found_within_its_standard_error(seed):
    rows = _noisy(_rows(STRONG, WEAK), seed)
    s, L = _pole(STRONG["f"], STRONG["zeta"]), STRONG["L"][None, :]
    new = beside_poles(FREQ, rows, _fit(rows, s, L), np.array([s]), L)
    assert len(new) == 1
    p, part, sigma = new[0]
    f, z = poles_to_modal(np.array([p]))
    assert 0 < sigma < 1.0  # Hz: the data locate it (a line is 0.5 Hz)
    assert abs(f[0] - WEAK["f"]) <= 3 * sigma
    assert abs(z[0] / WEAK["zeta"] - 1) < 0.25
    # its participation: the cos/sin pattern of the truth, up to a complex factor
    assert abs(np.vdot(part, WEAK["L"])) ** 2 / (np.vdot(part, part).real * np.vdot(WEAK["L"], WEAK["L"]).real) > 0.95


def test_no_pole_for_noise_or_for_the_strong_poles_bias():
    """20 seeded draws of the strong mode alone, its kept pole 0.3 half-widths off (the
    sweep's bias): the nested fits move it, and add nothing."""
    s_biased = _pole(STRONG["f"] + 0.3 * STRONG["zeta"] * STRONG["f"], STRONG["zeta"])
    L = STRONG["L"][None, :]
    added = 0
    for seed in range(20):
        rows = _noisy(_rows(STRONG), 100 + seed)
        added += len(beside_poles(FREQ, rows, _fit(rows, s_biased, L), np.array([s_biased]), L))
    assert added == 0


def test_no_second_pole_of_the_same_shape():
    """A weak mode with its strong neighbour's shape, half a bandwidth away: to the data one
    mode's line shape (module doc, MAX_MAC) — no pole added."""
    twin = dict(WEAK, psi=0.06 * STRONG["psi"], L=STRONG["L"])
    rows = _noisy(_rows(STRONG, twin), 7)
    s, L = _pole(STRONG["f"], STRONG["zeta"]), STRONG["L"][None, :]
    assert beside_poles(FREQ, rows, _fit(rows, s, L), np.array([s]), L) == []
