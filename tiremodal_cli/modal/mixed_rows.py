"""The passes that run only where the orders mix (a lumped mass or another asymmetry,
:mod:`~tiremodal_cli.modal.mixing`): an order group's rows then hold copies of the other
orders' modes, and the group's own fit can blend them with its modes.

In order: a split pair's member split far beyond the others (:mod:`~tiremodal_cli.modal.mass_splits`,
dropped); the remaining anti-phase pairs refitted with the copies held where that brings their
splitting nearer the others' (:mod:`~tiremodal_cli.modal.pair_refine`); rows of one order in one
group beyond a mass's splitting refitted with the copies as real modes, a redundant pole dropped
(:mod:`~tiremodal_cli.modal.group_blends`). docs/lsce.md, sessions 50 and 51.
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.band import noise_shape
from tiremodal_cli.modal.group_blends import refined_blends
from tiremodal_cli.modal.mass_splits import without_outlying_splits
from tiremodal_cli.modal.pair_refine import refined_pairs

__all__ = ["band_of", "where_orders_mix"]


def where_orders_mix(res, classes, classify_modes, r, live):
    """``res`` and its classifications after the three passes (module docstring); what the
    refits did in ``res.meta["pairs_refined"]`` and ``res.meta["blends_refitted"]``.

    Parameters
    ----------
    res : ModalResult ; classes : its Classification list ; classify_modes : ModalResult → classes
    r : FrfResult, the FRFs the table was fitted to ; live : indices of its live channels
    """
    res, classes = without_outlying_splits(res, classes, classify_modes)
    f, H_acc, noise = band_of(res, r, live)
    res, moves = refined_pairs(res, classes, f, H_acc, r.point_angle, noise, r.exp_tau_s)
    res.meta["pairs_refined"] = moves
    classes = classify_modes(res) if moves else classes
    res, blends = refined_blends(res, classes, f, H_acc, r.point_angle, noise, r.exp_tau_s)
    res.meta["blends_refitted"] = blends
    return res, (classify_modes(res) if blends else classes)


def band_of(res, r, live) -> tuple:
    """The analysis band's lines (Hz), the live channels' FRFs there in accelerance
    ((n_live, n_points, K) complex) and their noise variance per line (relative; None without
    a force spectrum)."""
    lines = (r.freq_hz >= res.band_freq_hz[0] - 1e-9) & (r.freq_hz <= res.band_freq_hz[-1] + 1e-9)
    f, noise = r.freq_hz[lines], noise_shape(r.force_autospectrum, r.n_averages)
    return (f, np.asarray(r.H)[live][:, :, lines] * (2j * np.pi * f) ** (2 - FORM_POWER[r.form]),
            None if noise is None else noise[lines])
