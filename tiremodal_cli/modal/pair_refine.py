"""Split pairs where the orders mix, refined in their order group's rows with the other
groups' modes as copies, and kept only where the mass's splitting agrees (docs/lsce.md,
"Session 50").

Where a lumped mass mixes the orders (:mod:`~tiremodal_cli.modal.mixing`), an order group's
rows hold copies of the other orders' modes, and a pair's weaker member is fitted between its
own frequency and a copy (:mod:`~tiremodal_cli.modal.mass_splits`). Here each anti-phase pair
of n ≥ 2 is fitted again in its group's rows over a window of its members ± 
:data:`WINDOW_HALF_WIDTHS` half-power half-widths, every other table pole in the window held
as a copy (a residue of its own on every row), the pair's two poles moved within one
half-width and a factor e of their decay rate (variable projection: the residues and the
window's residual terms by least squares, the poles by ``scipy.optimize.least_squares``).

The fit alone is no judge: in the same windows it also moves right pairs (measured on the
kept mass tests of session 49: 8 of 45 right pairs broken, 6 of 7 biased ones brought within
0.3 % of the truth). The physics is: a lumped mass splits every anti-phase order by about
one fraction (:mod:`~tiremodal_cli.modal.mass_splits`), so the refined pair is kept only
where its relative splitting lies closer to the median of the test's anti-phase pairs than
the table's — on the same pairs 5 of the 7 biased ones end right and none of the 45 right
ones ends off. A kept pair's two modes get the refined poles and their residues fitted
again in the physical FRFs over the window (every other pole there held); their
significance stays the table's.

The window (± 3 half-widths) and the box (one half-width) are the first values tried, as in
:mod:`~tiremodal_cli.modal.refine`; they were not tuned. Measured in the pipeline on the 27
tests whose orders mix in eight rulers: spurious 66 → 63, cases over 5 % 11 → 9, no mode lost;
one diagnosis turns wrong, its added mass no longer evidenced by a biased splitting
(docs/lsce.md, "Session 50").
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.optimize

from tiremodal_cli.frf.windows import correct_poles
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import lsfd, pole_basis
from tiremodal_cli.modal.mass_splits import MIN_PAIRS, anti_phase_pairs
from tiremodal_cli.modal.spatial import decompose
from tiremodal_cli.modal.varpro import forward_jacobian, moved_poles

__all__ = ["WINDOW_HALF_WIDTHS", "refined_pairs"]

#: the refit's window: the pair's members ± this many half-power half-widths
WINDOW_HALF_WIDTHS = 3.0

#: the lines a window needs beyond the fit's parameters
MIN_SPARE_LINES = 8


def refined_pairs(res, classes, freq_hz, H_acc, point_angle, noise=None, exp_tau_s=None):
    """``res`` with each anti-phase split pair of n ≥ 2 refined where the refit brings its
    splitting closer to the test's median, and the list of the moves (dicts).

    Parameters
    ----------
    res : ModalResult ; classes : list of Classification (one per mode)
    freq_hz : (K,) Hz, the analysis band's lines ; H_acc : (n_live, n_points, K) complex,
        the live channels' FRFs there in accelerance ; point_angle : (n_points,) rad
    noise : (K,) relative noise variance per line (:func:`~tiremodal_cli.modal.band.noise_shape`) or None
    exp_tau_s : the FRFs' exponential window, s (its decay is taken out of the reported values)
    """
    pairs = anti_phase_pairs(classes)
    if len(pairs) < MIN_PAIRS:
        return res, []
    f = res.poles.imag / (2 * np.pi)
    rel = np.array([abs(f[a] - f[b]) / (0.5 * (f[a] + f[b])) for a, b in pairs])
    median = float(np.median(rel))
    groups = decompose(H_acc, point_angle)
    weight = np.ones(freq_hz.size) if noise is None else 1 / np.sqrt(np.maximum(noise, np.finfo(float).tiny))
    poles, shapes, moves = res.poles.copy(), res.shapes.copy(), []
    live = ~np.all(np.isnan(res.shapes[0]), axis=1) if res.shapes.size else np.zeros(0, bool)
    for (a, b), r0 in zip(pairs, rel):
        if res.group[a] != res.group[b] or res.group[a] not in groups:
            continue
        new = _refit(poles, np.array([a, b]), freq_hz, groups[res.group[a]][0], weight)
        if new is None:
            continue
        r1 = abs(new[1].imag - new[0].imag) / (0.5 * (new[0].imag + new[1].imag))
        if not abs(r1 - median) < abs(r0 - median):
            continue
        old = poles[[a, b]]
        poles[[a, b]] = new
        shapes[[a, b]] = _residues(poles, np.array([a, b]), freq_hz, H_acc, weight, shapes[[a, b]], live)
        moves.append({"from_hz": [float(x) for x in old.imag / (2 * np.pi)],
                      "to_hz": [float(x) for x in new.imag / (2 * np.pi)],
                      "splitting_pct": [100 * float(r0), 100 * float(r1)], "median_pct": 100 * median})
    if not moves:
        return res, []
    fn, zeta = poles_to_modal(correct_poles(poles, exp_tau_s))
    return dataclasses.replace(res, poles=poles, freq_hz=fn, damping_ratio=zeta, shapes=shapes), moves


def _window(poles, idx, freq_hz):
    """The refit's lines (bool over ``freq_hz``) and the other poles it holds (indices)."""
    f, hw = poles.imag / (2 * np.pi), -poles.real / (2 * np.pi)
    lo = np.min(f[idx] - WINDOW_HALF_WIDTHS * hw[idx])
    hi = np.max(f[idx] + WINDOW_HALF_WIDTHS * hw[idx])
    lines = (freq_hz >= lo) & (freq_hz <= hi)
    near = (f > lo - hw) & (f < hi + hw)
    near[idx] = False
    return lines, np.flatnonzero(near)


def _refit(poles, idx, freq_hz, rows, weight):
    """The poles ``idx`` refitted in ``rows`` (an order group's, (n_rows, K)) with every other
    pole of the window held (a residue of its own on every row): the new poles, or None (too
    few lines, no better fit, or a pole on its box's edge)."""
    lines, held = _window(poles, idx, freq_hz)
    n_par = 2 * (held.size + idx.size) + 2
    if lines.sum() < n_par + MIN_SPARE_LINES:
        return None
    f, w = freq_hz[lines], weight[lines]
    Y = rows[:, lines].T * w[:, None]
    Yr = np.concatenate([Y.real, Y.imag], axis=0)
    W = np.concatenate([w, w])[:, None]
    s0 = np.concatenate([poles[held], poles[idx]])
    m = idx.size
    at = np.arange(held.size, held.size + m)

    def fun(theta):
        A = pole_basis(f, moved_poles(theta, s0, at), 2, True, True)
        Ar = np.concatenate([A.real, A.imag], axis=0) * W
        scale = np.linalg.norm(Ar, axis=0)
        scale[scale == 0] = 1
        x = np.linalg.lstsq(Ar / scale, Yr, rcond=None)[0]
        return (Yr - (Ar / scale) @ x).ravel()

    bound = np.ones(2 * m)
    r0 = fun(np.zeros(2 * m))
    sol = scipy.optimize.least_squares(fun, np.zeros(2 * m), jac=lambda t: forward_jacobian(fun, t),
                                       bounds=(-bound, bound), x_scale=0.1, max_nfev=40 * m)
    if np.any(np.abs(sol.x) >= 0.98 * bound) or 2 * sol.cost >= float(r0 @ r0):
        return None
    return moved_poles(sol.x, s0, at)[at]


def _residues(poles, idx, freq_hz, H_acc, weight, old, live):
    """The residues of the modes ``idx`` at their (moved) poles, fitted in the physical FRFs
    over their window with every other pole there held: (m, n_channels, n_points), NaN on the
    dead channels as ``old``."""
    lines, held = _window(poles, idx, freq_hz)
    use = np.concatenate([idx, held])
    fit = lsfd(freq_hz[lines], H_acc[:, :, lines].reshape(-1, lines.sum()), poles[use], weight=weight[lines])
    out = old.copy()
    n_live, n_p = H_acc.shape[:2]
    out[:, live] = fit.residues[:, :idx.size].T.reshape(idx.size, n_live, n_p)
    return out
