"""Blends of one order group where the orders mix, refitted with the other orders' modes as
real-mode copies (docs/lsce.md, "Session 51").

Where a lumped mass mixes the orders (:mod:`~tiremodal_cli.modal.mixing`), an order group's
rows hold, beside the group's own modes, copies of the other orders' modes, and the group's
own sweep (which models its rows alone) can stand two or three poles between its modes and
the copies: on the 20-point ring + mass of held-out draw 9000, group 9 holds the in-phase
n = 9 (153.2 Hz) and its alias n = 11 (159.4 Hz), with copies of n = 8 (147.7) and n = 10
(156.9), and the table read three rows of n = 9 at 152.48, 154.95 and 158.63 Hz, none within
0.3 % of a mode.

**Which rows** (:func:`suspect_clusters`): in one order group, rows read with one order n,
none a split pair's member, whose half-power bands overlap in a chain — three or more of them (one order holds one mode, or a
pair its broken symmetry splits), or two whose relative splitting exceeds
:data:`~tiremodal_cli.modal.mass_splits.SPLIT_MAX_RATIO` × the median of the test's
anti-phase pairs (more than a lumped mass splits an order; without three pairs to take a
median from, two rows are not judged). A crowd's row (several orders within a bandwidth:
each group's row there stands for other orders, another mode at the same frequency) counts
in the chain but is never refitted nor dropped: the cluster is the chain's other rows.

**The model**: the group's rows over the cluster ± :data:`WINDOW_HALF_WIDTHS` half-power
half-widths; the cluster's poles free; the group's other poles there held where the table has them (a
residue of their own on each row); every other group's pole there, and the group's crowd
rows, held as copies whose residue on each row is a real
mode's — a light, proportional damping (a lumped mass adds none) leaves the modes real, and
the rows are real (cos and sin) combinations of the physical FRFs, so a copy's residue on a
row is imaginary (the receptance's φφᵀ/(2jω_d m)). Free complex residues let two copies
either side of a mode stand for it (measured: with them, group 9's pole at 159.4 Hz ran off
its box; with real copies it lands at 159.41). Each free pole's frequency is searched on a
grid (:data:`GRID_STEP` half-widths, within :data:`BOX_HALF_WIDTHS` of its start, each pole
in turn, three sweeps: the cost has local minima that a gradient from the table's poles
falls into), then refined with its decay by ``scipy.optimize.least_squares`` (variable
projection: residues and the window's residual terms by linear least squares) within the
same box.

**A redundant pole**: one that ends on its box's edge, within :data:`DUPLICATE_HALF_WIDTHS`
of a held pole (it models another order's copy again), or whose removal (the others searched
again) the fit does not resist by the nested F-test at :data:`ALPHA`, is dropped and the fit
repeated without it (each such pole tried, the lowest cost kept). A fit with fewer poles is
kept only if it fits the window better than the table's poles did; a fit with all of them
whenever none is redundant. The kept poles replace the rows' and their residues are fitted
again in the physical FRFs over the window; a dropped row goes to ``rejected`` with its
reason.

*Premises, stated:* the modes are real (a tyre's rubber damping is not proportional, and
where its modes are markedly complex the copies' residues are not imaginary: the fit is then
wrong for them); the window (± 3 half-widths, as :mod:`~tiremodal_cli.modal.pair_refine`),
the box (1.5 half-widths), the grid's step and the duplicate's quarter half-width (session
47's guard) are chosen, not tuned. Measured (docs/lsce.md, "Session 51") on the 27 tests whose
orders mix in eight rulers: spurious 63 → 58, cases over 5 % 9 → 7, found +1, nothing
mislabelled or lost; on 33 mixed tests no rule was measured on: spurious 72 → 68, the rest
unchanged.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.optimize
import scipy.special

from tiremodal_cli.frf.windows import correct_poles
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import lsfd, pole_basis
from tiremodal_cli.modal.mass_splits import MIN_PAIRS, SPLIT_MAX_RATIO, anti_phase_pairs
from tiremodal_cli.modal.misreads import without_modes
from tiremodal_cli.modal.spatial import decompose
from tiremodal_cli.modal.varpro import forward_jacobian, moved_poles

__all__ = ["WINDOW_HALF_WIDTHS", "BOX_HALF_WIDTHS", "GRID_STEP", "DUPLICATE_HALF_WIDTHS", "ALPHA",
           "suspect_clusters",
           "refined_blends"]

#: the refit's window: the cluster's rows ± this many half-power half-widths
WINDOW_HALF_WIDTHS = 3.0

#: how far a free pole may move from the table's, in its half-power half-widths (frequency)
#: and in ln of its decay rate
BOX_HALF_WIDTHS = 1.5

#: the frequency grid's step, in the pole's half-power half-widths
GRID_STEP = 0.1

#: a free pole this close to a held one (in the lesser half-width) models that copy again
DUPLICATE_HALF_WIDTHS = 0.25

#: a free pole whose removal raises the window's misfit less than the nested F-test's
#: quantile at this probability earns no place (the stage's other noise tests use 0.001)
ALPHA = 1e-3

#: the lines a window needs beyond the fit's parameters (as pair_refine)
MIN_SPARE_LINES = 8


def suspect_clusters(freq_hz, half_width_hz, group, classes) -> list[np.ndarray]:
    """The clusters of rows the module docstring describes (index arrays, by frequency: the
    chain's rows but its crowd rows).

    Parameters
    ----------
    freq_hz, half_width_hz : (n_modes,) Hz ; group : (n_modes,) int, each row's order group
    classes : list of Classification or None (``n``, ``branch``, ``pair``)
    """
    f, hw, group = np.asarray(freq_hz, float), np.asarray(half_width_hz, float), np.asarray(group)
    pairs = anti_phase_pairs(classes)
    median = (float(np.median([abs(f[a] - f[b]) / (0.5 * (f[a] + f[b])) for a, b in pairs]))
              if len(pairs) >= MIN_PAIRS else None)
    out = []
    for g in np.unique(group):
        rows = sorted((i for i in np.flatnonzero(group == g) if classes[i] is not None and classes[i].pair is None),
                      key=lambda i: f[i])
        for chain in _chains(rows, f, hw):
            free = [i for i in chain if not getattr(classes[i], "crowd", False)]
            if len({classes[i].n for i in chain}) != 1 or not free:
                continue
            if len(chain) >= 3 or (median is not None and abs(f[chain[1]] - f[chain[0]])
                                   / (0.5 * (f[chain[0]] + f[chain[1]])) > SPLIT_MAX_RATIO * median):
                out.append(np.array(free))
    return out


def _chains(rows, f, hw):
    """Runs of ≥ 2 consecutive rows (by frequency) whose half-power bands overlap."""
    runs, cur = [], rows[:1]
    for i in rows[1:]:
        if f[i] - f[cur[-1]] < hw[i] + hw[cur[-1]]:
            cur.append(i)
            continue
        runs.append(cur)
        cur = [i]
    runs.append(cur)
    return [r for r in runs if len(r) >= 2]


@dataclasses.dataclass(frozen=True)
class _Window:
    """An order group's rows over a window (weighted, real and imaginary parts stacked) and
    the poles it holds as real-mode copies."""
    freq_hz: np.ndarray
    data: np.ndarray  # (2 K, n_rows)
    weight: np.ndarray  # (2 K, 1)
    held: np.ndarray  # the other orders' poles: real-mode copies
    fixed: np.ndarray  # the group's other poles: where the table has them, complex residues

    def residual(self, free) -> np.ndarray:
        """The weighted misfit with ``free`` and ``fixed`` poles (complex residues) and the held
        ones (imaginary)."""
        s = np.concatenate([self.held, self.fixed, free])
        A = pole_basis(self.freq_hz, s, 2, True, True)[:, self.held.size:]
        Ar = np.concatenate([A.real, A.imag], axis=0) * self.weight  # held: only their Im R columns remain
        scale = np.linalg.norm(Ar, axis=0)
        scale[scale == 0] = 1
        x = np.linalg.lstsq(Ar / scale, self.data, rcond=None)[0]
        return (self.data - (Ar / scale) @ x).ravel()

    def cost(self, free) -> float:
        r = self.residual(free)
        return float(r @ r)


def refined_blends(res, classes, freq_hz, H_acc, point_angle, noise=None, exp_tau_s=None):
    """``res`` with each :func:`suspect_clusters` cluster's group refitted as the module
    docstring says, and the list of the refits (dicts: group, from, to, dropped, costs).

    Parameters
    ----------
    res : ModalResult ; classes : list of Classification (one per mode)
    freq_hz : (K,) Hz, the analysis band's lines ; H_acc : (n_live, n_points, K) complex,
        the live channels' FRFs there in accelerance ; point_angle : (n_points,) rad
    noise : (K,) relative noise variance per line or None ; exp_tau_s : the FRFs' exponential window, s
    """
    f, hw = res.poles.imag / (2 * np.pi), -res.poles.real / (2 * np.pi)
    clusters = suspect_clusters(f, hw, res.group, classes)
    if not clusters:
        return res, []
    groups = decompose(H_acc, point_angle)
    weight = np.ones(freq_hz.size) if noise is None else 1 / np.sqrt(np.maximum(noise, np.finfo(float).tiny))
    crowd = np.array([c is not None and bool(getattr(c, "crowd", False)) for c in classes], dtype=bool)
    poles, moves, dropped, changed = res.poles.copy(), [], [], []
    for idx in clusters:
        fit = _cluster_fit(poles, res.group, crowd, idx, freq_hz, groups.get(res.group[idx[0]], (None,))[0], weight)
        if fit is None:
            continue
        own, new, kept, costs = fit
        moves.append({"group": int(res.group[idx[0]]), "from_hz": [float(x) for x in f[own]],
                      "to_hz": [float(x) for x in new.imag / (2 * np.pi)],
                      "dropped_hz": [float(f[i]) for i in own if i not in kept], "cost": costs})
        poles[kept] = new
        changed += [int(i) for i in kept]
        dropped += [int(i) for i in own if i not in kept]
    if not moves:
        return res, []
    shapes = _residues(poles, changed, dropped, freq_hz, H_acc, weight, res.shapes)
    fn, zeta = poles_to_modal(correct_poles(poles, exp_tau_s))
    res = dataclasses.replace(res, poles=poles, freq_hz=fn, damping_ratio=zeta, shapes=shapes)
    for i in sorted(dropped, reverse=True):
        res = without_modes(res, np.delete(np.arange(res.freq_hz.size), i), {
            "frequency_hz": float(res.freq_hz[i]), "damping_ratio": float(res.damping_ratio[i]),
            "group": int(res.group[i]),
            "reason": f"a redundant pole: read n = {classes[i].n} among rows of one order in its group beyond a "
                      "lumped mass's splitting; its group's rows refitted with the other orders' modes as "
                      "real-mode copies fit better without it (it ran to its box's edge or onto a copy)"})
    return res, moves


def _cluster_fit(poles, group, crowd, idx, freq_hz, rows, weight):
    """The refit of the cluster ``idx``'s group over its window: (the cluster's indices, their new
    poles, the indices they stand for, [cost with the table's poles, cost after]) or None
    (no rows, too few lines, or no acceptable fit)."""
    if rows is None:
        return None
    f, hw = poles.imag / (2 * np.pi), -poles.real / (2 * np.pi)
    lo = float(np.min(f[idx] - WINDOW_HALF_WIDTHS * hw[idx]))
    hi = float(np.max(f[idx] + WINDOW_HALF_WIDTHS * hw[idx]))
    lines, near = (freq_hz >= lo) & (freq_hz <= hi), (f > lo) & (f < hi)
    own = np.asarray(idx)
    fixed = np.setdiff1d(np.flatnonzero(near & (group == group[idx[0]]) & ~crowd), own)
    held = np.flatnonzero(near & ((group != group[idx[0]]) | crowd))
    if lines.sum() < 2 * (own.size + fixed.size) + held.size + 2 + MIN_SPARE_LINES:
        return None
    w = weight[lines]
    Y = rows[:, lines].T * w[:, None]
    win = _Window(freq_hz[lines], np.concatenate([Y.real, Y.imag], axis=0), np.concatenate([w, w])[:, None],
                  poles[held], poles[fixed])
    cost0 = win.cost(poles[own])
    new, kept, cost = _reduced(win, poles[own], own, cost0, own.size)
    return None if new is None else (own, new, kept, [cost0, cost])


def _searched(win, start):
    """The poles ``start`` moved to the window's least cost within the box: a grid over each
    one's frequency in turn (three sweeps), then least squares on frequency and decay. Returns
    (poles, cost, (m,) bool: on the box's edge)."""
    m = start.size
    at = np.arange(m)
    steps = np.arange(-BOX_HALF_WIDTHS, BOX_HALF_WIDTHS + 1e-9, GRID_STEP)
    x = np.zeros(2 * m)
    for _ in range(3):
        for k in range(m):
            costs = [win.cost(moved_poles(np.concatenate([np.where(at == k, d, x[:m]), x[m:]]), start, at))
                     for d in steps]
            x[k] = steps[int(np.argmin(costs))]
    fun = lambda th: win.residual(moved_poles(th, start, at))
    b = BOX_HALF_WIDTHS * np.ones(2 * m)
    sol = scipy.optimize.least_squares(fun, np.clip(x, -0.99 * b, 0.99 * b), jac=lambda t: forward_jacobian(fun, t),
                                       bounds=(-b, b), x_scale=0.1, max_nfev=60 * m)
    edge = np.abs(sol.x) >= 0.98 * b
    return moved_poles(sol.x, start, at), 2 * float(sol.cost), edge[:m] | edge[m:]


def _reduced(win, start, ids, cost0, m0):
    """The least-cost fit without redundant poles (module docstring): (poles, the indices they
    stand for, cost), or (None, None, None)."""
    if start.size == 0:
        return None, None, None
    new, cost, edge = _searched(win, start)
    held = win.held
    onto = np.array([held.size > 0 and bool(np.any(np.abs(held.imag - s.imag)
                                                   < DUPLICATE_HALF_WIDTHS * np.minimum(-held.real, -s.real)))
                     for s in new], dtype=bool)
    redundant = np.flatnonzero(edge | onto | _unearned(win, new, cost))
    if redundant.size == 0:
        return (new, ids, cost) if start.size == m0 or cost < cost0 else (None, None, None)
    best = (None, None, None)
    for k in redundant:
        r = _reduced(win, np.delete(start, k), np.delete(ids, k), cost0, m0)
        if r[0] is not None and (best[0] is None or r[2] < best[2]):
            best = r
    return best


def _unearned(win, poles, cost) -> np.ndarray:
    """(m,) bool: the poles whose removal (the others searched again) the window's fit does not
    resist — the nested models' F-test at :data:`ALPHA` (the residual's variance taken from the
    fit with every pole, misfit included, which makes the test keep a pole more readily)."""
    m, n_rows = poles.size, win.data.shape[1]
    if m < 2:
        return np.zeros(m, dtype=bool)
    n_data = win.data.size
    n_par = 2 * m + n_rows * (2 * m + win.held.size + 2 * win.fixed.size + 4)
    per_pole = 2 + 2 * n_rows
    if n_data <= n_par:
        return np.zeros(m, dtype=bool)
    limit = scipy.special.fdtri(per_pole, n_data - n_par, 1 - ALPHA)  # the F quantile 1 − α
    var = cost / (n_data - n_par)
    return np.array([(_searched(win, np.delete(poles, k))[1] - cost) / per_pole / var < limit for k in range(m)])


def _residues(poles, idx, dropped, freq_hz, H_acc, weight, old):
    """The shapes with the modes ``idx`` given residues at their (moved) poles, fitted in the
    physical FRFs over their window with every other pole there held but the ``dropped``:
    (n_modes, n_channels, n_points), NaN on the dead channels as ``old``."""
    out = old.copy()
    live = ~np.all(np.isnan(old[0]), axis=1) if old.size else np.zeros(0, bool)
    f, hw = poles.imag / (2 * np.pi), -poles.real / (2 * np.pi)
    n_live, n_p = H_acc.shape[:2]
    for i in idx:
        lines = (freq_hz >= f[i] - WINDOW_HALF_WIDTHS * hw[i]) & (freq_hz <= f[i] + WINDOW_HALF_WIDTHS * hw[i])
        near = (f > f[i] - WINDOW_HALF_WIDTHS * hw[i] - hw) & (f < f[i] + WINDOW_HALF_WIDTHS * hw[i] + hw)
        near[[i] + list(dropped)] = False
        use = np.concatenate([[i], np.flatnonzero(near)])
        fit = lsfd(freq_hz[lines], H_acc[:, :, lines].reshape(-1, lines.sum()), poles[use], weight=weight[lines])
        out[i][live] = fit.residues[:, 0].reshape(n_live, n_p)
    return out
