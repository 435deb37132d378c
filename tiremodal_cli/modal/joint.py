"""A grid with missing points: the branch's unfound orders proposed from its dispersion and
refined jointly with the modes found, in the physical FRFs, each mode's residues held to its
orders.

With points missing, each order group's rows hold every other order's leaks
(:mod:`tiremodal_cli.modal.gaps`), and the group sweeps lose the crowded orders of a branch
where several lie within one half-power bandwidth (the paper's opposite branch above 670 Hz
on 19 of 24 points, ζ ≈ 3 %: eight orders within a bandwidth). The Cramér–Rao bound
(``benchmarks/crlb.py``) resolves every one of them with each mode's residues held to its
orders (σ_f/f 0.003–0.03 %) and none with a free residue per FRF: the model of
:func:`~tiremodal_cli.modal.gaps.order_lsfd` resolves them, the group sweeps do not.

So (:func:`add_missing_orders`): the modes are classified (:func:`~tiremodal_cli.modal.classify.classify`)
and each branch's dispersion f(n) is read from its clear modes (both confidences ≥ 0.5),
interpolated, and beyond its highest order continued with the last step's slope (as the crowd
test has it) for as many orders as that step spans. Every order the branch does not hold is
proposed at f(n) with its neighbours' damping, in its aliased order group (unless a mode of that
group already lies within its half-power band: that mode is the order's); a proposal in a crowd
(another order of its group within its bandwidth) only holds its response in the fit, its pole
held while the found modes of its branch about it are refined (the neighbours its response
biased). Each
proposal is refined (:func:`_local`) with the found modes of its branch within
:data:`NEAR_HALF_WIDTHS` of its half-width by variable projection (``scipy.optimize.least_squares``,
the residues eliminated linearly: :func:`_fit`) over the lines within
:data:`~tiremodal_cli.modal.refine.WINDOW_HALF_WIDTHS` half-widths of it, every other pole reaching
those lines held with its residues — bounded sets, whatever the chain of overlapping bands — in
:data:`PASSES` Gauss–Seidel passes. A proposal stays only when it ends inside its box, apart from
the other poles and with its branch's frequencies rising with n (of a falling pair, the
proposal that moved most goes), and when removing it raises its window's residual by more
than a fit of its unknowns to the noise would (:func:`threshold`:
χ²(2p + 2)/2 at the stage's false-alarm level ``NOISE_ALPHA``/K, times the proposal's window
gain κ_r, :func:`~tiremodal_cli.modal.band.window_noise_gain`), weakest first; the rest are
refined again without the dropped ones (:data:`ROUNDS`). Measured rates and effect: docs/lsce.md
("Session 12").
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
import scipy.optimize
import scipy.special

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.classify import classify
from tiremodal_cli.modal.gaps import min_norm_solve, order_design
from tiremodal_cli.modal.band import window_noise_gain
from tiremodal_cli.modal.groupfit import NOISE_ALPHA
from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import pole_basis, significance, synthesize
from tiremodal_cli.modal.merge import MergedMode
from tiremodal_cli.modal.refine import MAX_DAMPING_FACTOR, WINDOW_HALF_WIDTHS
from tiremodal_cli.modal.varpro import forward_jacobian, moved_poles
from tiremodal_cli.modal.spatial import grid_design, grid_points

__all__ = ["Proposal", "propose", "threshold", "add_missing_orders"]

#: the least confidence (order and branch) of a mode that fixes its branch's dispersion (the
#: crowd test's "clear" modes, :func:`~tiremodal_cli.modal.classify._crowds`)
CLEAR = 0.5
#: Gauss–Seidel passes over the proposals (each refined with its neighbours' refined poles),
#: as :data:`~tiremodal_cli.modal.refine.PASSES`
PASSES = 2
#: a proposal is refined with the live poles within this share of its half-power half-width
#: (the biased neighbours its own pole competes with; the rest of its window is held): the
#: cost of a refinement grows with the square of its free poles
NEAR_HALF_WIDTHS = 0.5
#: rounds of refinement and judgement: after a round that drops proposals the rest are
#: refined again without them (once)
ROUNDS = 2
#: the solver's function evaluations per refinement (each pole starts within a fraction of
#: its half-width: the dispersion's interpolation is within 0.1–0.7 % of the truth where
#: the matrix's paper case misses its orders, 0.1–0.25 half-widths)
MAX_NFEV = 10


@dataclass(frozen=True)
class Proposal:
    """An unfound order of a branch, where its dispersion puts it.

    n : int ; branch : str ; group : int (the grid's aliased order) ; pole : complex, rad/s ;
    crowd : another order of its group lies within its half-power bandwidth by the dispersion
    (as :func:`~tiremodal_cli.modal.classify._crowds`): its order cannot be told, and its pole
    only stands in the joint fit for the response it holds (never reported)
    """

    n: int
    branch: str
    group: int
    pole: complex
    crowd: bool = False


def aliased_group(n: int, n_grid: int) -> int:
    """The order group of the grid that order ``n`` falls in (n and N − n are one group)."""
    g = n % n_grid
    return int(min(g, n_grid - g))


def propose(modes, classes, f_band, n_grid: int) -> list[Proposal]:
    """The orders each branch does not hold, at its dispersion's frequency (module doc).

    modes : list of MergedMode ; classes : list of Classification, in the order of ``modes``
    f_band : (2,) Hz, the band's edges ; n_grid : the grid's points (:func:`grid_points`)
    """
    f, z = poles_to_modal(np.array([m.pole for m in modes]))
    out = []
    for br in sorted({c.branch for c in classes if c.branch is not None}):
        on = [r for r, c in enumerate(classes) if c.branch == br]
        clear = sorted((classes[r].n, r) for r in on if classes[r].n_confidence >= CLEAR
                       and classes[r].branch_confidence >= CLEAR and f_band[0] < f[r] * (1 - z[r])
                       and f[r] * (1 + z[r]) < f_band[1])  # (a mode off the band's edges is dropped)
        pts = dict(clear)  # the highest-frequency reading of an order (as the crowd test)
        if len(pts) < 2:
            continue
        nn = np.array(sorted(pts), dtype=float)
        ff = np.maximum.accumulate(f[[pts[n] for n in sorted(pts)]])
        zz = z[[pts[n] for n in sorted(pts)]]
        slope = max(0.0, (ff[-1] - ff[-2]) / max(nn[-1] - nn[-2], 1.0))

        def f_of(n):
            return float(np.interp(n, nn, ff)) if n <= nn[-1] else float(ff[-1] + slope * (n - nn[-1]))

        held = {classes[r].n for r in on if f_band[0] < f[r] * (1 - z[r]) and f[r] * (1 + z[r]) < f_band[1]}
        n = int(nn[0])
        n_end = nn[-1] + (nn[-1] - nn[-2] if slope > 0 else 0)  # extrapolated by its last step at most
        while n < n_end:
            n += 1
            f0, z0, g = f_of(n), float(np.interp(n, nn, zz)), aliased_group(n, n_grid)
            if f0 * (1 + z0) > f_band[1]:
                break
            if n in held or f0 * (1 - z0) < f_band[0]:
                continue
            if any(m.group == g and abs(fr - f0) <= zr * fr for m, fr, zr in zip(modes, f, z)):
                continue  # a mode of its group within its band: that mode is the order's
            crowd = any(c != n and aliased_group(c, n_grid) == g and abs(f_of(c) - f0) <= 2 * z0 * f0
                        for c in range(int(max(1.5 * n_grid, n_end)) + 1))
            w = 2 * np.pi * f0
            out.append(Proposal(n, br, g, complex(-z0 * w, w * np.sqrt(1 - z0**2)), crowd))
    return out


def threshold(p: int, n_lines: int, alpha: float = NOISE_ALPHA) -> float:
    """ΔE that a mode of ``p`` complex residues and a free pole fitted to noise alone exceeds
    with probability ``alpha``/``n_lines``: the 1 − α/K quantile of χ²(2p + 2)/2.

    E is the residual's power over the noise's (σ² per complex line); least squares projects
    the noise on 2p real dimensions of variance σ²/2 each for the residues, and about two more
    for the pole's frequency and damping (searched, so the share is at least that)."""
    return float(scipy.special.chdtri(2 * p + 2, alpha / n_lines) / 2)


def _fit(freq, Yr, D, cols, s, q):
    """The weighted residual (flattened, real) of the FRFs on ``freq`` fitted with poles ``s``,
    each pole's residues on its grid columns ``cols[r]`` (every channel), the lower and upper
    residual terms free per FRF; and the residues (n_poles, n_cols, n_channels) in the
    weighted units.

    Yr : (n_c, n_p, 2K) real — the weighted FRFs' real then imaginary parts ; D : (n_p, n_cols)
    """
    n_c, n_p, _ = Yr.shape
    A = pole_basis(freq, s, q, True, True)
    Ar = np.concatenate([A.real, A.imag], axis=0)
    scale = np.linalg.norm(Ar, axis=0)
    scale[scale == 0] = 1
    Q, R = np.linalg.qr(Ar / scale)
    Y = Yr.reshape(n_c * n_p, -1)
    Z = (Y @ Q).reshape(n_c, n_p, -1).transpose(1, 2, 0).reshape(-1, n_c)
    G, units = order_design(D, cols, R, s.size)
    x = min_norm_solve(G, Z)  # a mode may hold more columns than there are points
    model = (G @ x).reshape(n_p, -1, n_c).transpose(2, 0, 1).reshape(n_c * n_p, -1) @ Q.T
    X = np.zeros((s.size, D.shape[1], n_c), dtype=complex)
    nu = len(units)
    for u, (r, k) in enumerate(units):
        X[r, k] = x[u] / scale[r] + 1j * x[nu + u] / scale[s.size + r]
    return (Y - model).ravel(), X


def _refine(freq, Yr, D, cols, s, s_orig, free, q):
    """Poles ``s`` with ``free`` (indices) refined in their box about ``s_orig`` (frequency
    within its half-power half-width, damping within :data:`MAX_DAMPING_FACTOR`): (poles, the
    free poles' offsets in half-widths, σ of their frequencies in rad/s)."""
    m = free.size
    order = np.concatenate([free, np.setdiff1d(np.arange(s.size), free)])
    s_use = s[order].copy()
    s_use[:m] = s_orig[free]
    loc = np.arange(m)
    hw = -s_orig[free].real
    bound = np.concatenate([np.ones(m), np.full(m, np.log(MAX_DAMPING_FACTOR))])
    x0 = np.clip(np.concatenate([(s[free].imag - s_orig[free].imag) / hw, np.log(s[free].real / s_orig[free].real)]),
                 -0.97 * bound, 0.97 * bound)

    def fun(theta):
        return _fit(freq, Yr, D, [cols[i] for i in order], moved_poles(theta, s_use, loc), q)[0]

    sol = scipy.optimize.least_squares(fun, x0, jac=lambda th: forward_jacobian(fun, th), bounds=(-bound, bound),
                                       x_scale=0.1, max_nfev=MAX_NFEV)
    out = s.copy()
    out[order] = moved_poles(sol.x, s_use, loc)
    J = sol.jac[:, :m]
    cov = np.linalg.pinv(J.T @ J) / 2  # each real residual's variance is 1/2 (weights 1/σ)
    edge = np.max(np.abs(sol.x.reshape(2, m)) / bound.reshape(2, m), axis=0)  # the nearer box edge, as a share
    return out, edge, np.sqrt(np.maximum(np.diag(cov), 0)) * hw


@dataclass
class _Problem:
    """The weighted FRFs and the modes found: what each set is judged against.

    freq : (K,) Hz ; Yw : (n_c, n_p, K) complex, each channel over its noise ; D : (n_p, n_cols)
    col_of : {order group: its columns} ; poles : (m,) complex ; cols : list of column lists ;
    reads : list of (n, branch) of the found modes ; q : form power ; n_lines : the band's K
    """

    freq: np.ndarray
    Yw: np.ndarray
    D: np.ndarray
    col_of: dict
    poles: np.ndarray
    cols: list
    reads: list
    q: int
    n_lines: int
    branch_of: dict = None  # {pole index: branch} of the proposals
    exp_window: tuple | None = None  # the FRFs' exponential window (τ s, line Hz): the noise test's gain

    def window(self, f_lo, f_hi):
        w = (self.freq >= f_lo) & (self.freq <= f_hi)
        return self.freq[w], np.concatenate([self.Yw[:, :, w].real, self.Yw[:, :, w].imag], axis=2)


def _falling(prob: _Problem, poles, idx, props) -> set:
    """The proposals (their indices in ``props``) in a pair of orders of one branch whose
    frequencies do not rise with n — the pair a proposal and a found mode of its branch, or two
    proposals (refined: the found modes' poles ``poles`` at ``idx``, then the proposals')."""
    f = poles_to_modal(poles)[0]
    found = dict(zip(idx, f[:len(idx)]))
    bad = set()
    for br in {p.branch for p in props}:
        pts = [(n, found.get(i, poles_to_modal(prob.poles[i])[0]), None) for i, (n, b) in enumerate(prob.reads)
               if b == br]
        pts += [(p.n, fp, k) for k, (p, fp) in enumerate(zip(props, f[len(idx):])) if p.branch == br]
        pts.sort(key=lambda t: (t[0], t[1]))
        for (n1, f1, k1), (n2, f2, k2) in zip(pts[:-1], pts[1:]):
            if (k1 is not None or k2 is not None) and n2 > n1 and f2 <= f1:
                bad |= {k for k in (k1, k2) if k is not None}
    return bad


def _around(prob: _Problem, s, alive, j):
    """Pole ``j``'s window (the lines within WINDOW_HALF_WIDTHS half-widths of it) and the
    live poles whose bands reach it: (lines, weighted FRFs (n_c, n_p, 2K), their indices)."""
    f, z = poles_to_modal(s)
    lo, hi = f[j] * (1 - WINDOW_HALF_WIDTHS * z[j]), f[j] * (1 + WINDOW_HALF_WIDTHS * z[j])
    near = alive & (f * (1 + WINDOW_HALF_WIDTHS * z) >= lo) & (f * (1 - WINDOW_HALF_WIDTHS * z) <= hi)
    return (*prob.window(lo, hi), np.flatnonzero(near))


def _local(prob: _Problem, s, s_orig, cols, alive, j, held=False):
    """Proposal ``j`` refined with the found modes of its branch within :data:`NEAR_HALF_WIDTHS`
    of its half-power half-width, every other pole reaching its window held with its residues:
    (poles, j's offset as a share of its box, j's σ in rad/s). ``held`` (a crowd): j's pole
    stays where the dispersion puts it and only those found modes move (offset and σ 0)."""
    freq, Yr, idx = _around(prob, s, alive, j)
    f, z = poles_to_modal(s[idx])
    fj = poles_to_modal(s[j])
    branch = [prob.reads[i][1] if i < len(prob.reads) else None for i in idx]  # found modes: their reading
    free = np.flatnonzero((np.abs(f - fj[0]) < NEAR_HALF_WIDTHS * fj[1] * fj[0])
                          & (((idx == j) & (not held)) | (np.array(branch) == prob.branch_of[j])))
    if free.size == 0:
        return s, 0.0, 0.0
    new, off, sd = _refine(freq, Yr, prob.D, [cols[i] for i in idx], s[idx], s_orig[idx], free, prob.q)
    s = s.copy()
    s[idx] = new
    if held:
        return s, 0.0, 0.0
    k = int(np.flatnonzero(idx[free] == j)[0])
    return s, off[k], sd[k]


def _gain(prob: _Problem, s, cols, alive, j, n_c) -> float:
    """Proposal ``j``'s gain in its window, E(without j) − E(with j), over :func:`threshold` × κ_r (module doc)."""
    freq, Yr, idx = _around(prob, s, alive, j)
    e = []
    for use in (idx, idx[idx != j]):
        r = _fit(freq, Yr, prob.D, [cols[i] for i in use], s[use], prob.q)[0]
        e.append(float(r @ r))
    gain = float(window_noise_gain(-s[j].real, *prob.exp_window)[0]) if prob.exp_window else 1.0
    return (e[1] - e[0]) / (threshold(len(cols[j]) * n_c, prob.n_lines) * gain)


def _joint(prob: _Problem, props) -> tuple:
    """Every proposal refined with its neighbours and judged (module doc): (the poles, found
    modes first, then the proposals; which proposals are kept; their σ in rad/s; the dropped
    ones' reasons {index: why})."""
    nf, n_c = prob.poles.size, prob.Yw.shape[0]
    s_orig = np.concatenate([prob.poles, [p.pole for p in props]])
    cols = prob.cols + [prob.col_of[p.group] for p in props]
    alive = np.ones(s_orig.size, dtype=bool)
    why, sigma = {}, np.zeros(s_orig.size)
    mine = nf + np.argsort(poles_to_modal(s_orig[nf:])[0])
    for _ in range(ROUNDS):
        s, off = s_orig.copy(), {}
        for _ in range(PASSES):
            for j in mine[alive[mine]]:  # a crowd's pole is held; the found modes about it move
                if props[j - nf].crowd:
                    s = _local(prob, s, s_orig, cols, alive, j, held=True)[0]
                else:
                    s, off[j], sigma[j] = _local(prob, s, s_orig, cols, alive, j)
        out = [j for j in off if alive[j] and abs(off[j]) >= 0.98]
        for j in out:
            why[j] = "ends on its box's edge (the fit's minimum lies on another mode)"
        f = poles_to_modal(s)[0]
        line = prob.freq[1] - prob.freq[0]
        for j in [j for j in off if alive[j] and j not in out and np.sum(alive & (np.abs(f - f[j]) <= line)) > 1]:
            out.append(j)
            why[j] = "ends within a line of another pole (one pole twice)"
        live = [j for j in mine if alive[j] and j not in out]
        bad = [] if out else _falling(prob, np.concatenate([s[:nf], s[live]]), np.arange(nf),
                                      [props[j - nf] for j in live])
        if bad:  # the proposal of a falling pair that moved most
            out = [max((live[k] for k in bad), key=lambda j: abs(s[j] - s_orig[j]))]
            why[out[0]] = "its branch's frequencies rise with n only without it"
        alive[out] = False
        ratio = {j: _gain(prob, s, cols, alive, j, n_c) for j in mine if alive[j]}
        while ratio and min(ratio.values()) <= 1:
            j = min(ratio, key=ratio.get)
            why[j] = f"improves the physical FRFs' fit by {ratio.pop(j):.2f} × what a fit to the noise exceeds"
            alive[j] = False
            out.append(j)
            f, z = poles_to_modal(s)
            ratio = {k: _gain(prob, s, cols, alive, k, n_c) if abs(f[k] - f[j]) < WINDOW_HALF_WIDTHS * (
                z[k] * f[k] + z[j] * f[j]) else ratio[k] for k in ratio}
        if not out:
            break
    return s, alive[nf:], sigma[nf:], {j - nf: w for j, w in why.items()}


def add_missing_orders(freq, Hb, point_angle, locs, modes, synth, form: str = "accelerance", window=None) -> tuple:
    """The modes found on a grid with missing points, with the branches' unfound orders that
    the physical FRFs hold added, and the found modes around them refined (module doc).

    Parameters
    ----------
    freq : (K,) Hz ; Hb : (n_c, n_p, K) complex, the band's FRFs (``form``) ; point_angle :
    (n_p,) rad ; locs : the channels' locations ; modes : list of MergedMode ; synth : (n_c ·
    n_p, K) complex, the modes' synthesis (its residual gives each channel's noise) ; window :
    (τ s, line Hz) of the FRFs' exponential window, or None (the noise test's gain)

    Returns
    -------
    modes : list of MergedMode ; synth : (n_c · n_p, K) complex, with the added modes ;
    rejected : list of dict, the proposals not kept and why
    """
    n_c, n_p, K = Hb.shape
    if "tread" not in locs or len(modes) < 2:
        return modes, synth, []
    f, z = poles_to_modal(np.array([m.pole for m in modes]))
    shapes = np.array([m.residues for m in modes]).reshape(len(modes), n_c, n_p)
    classes = classify(f, shapes, point_angle, locs, np.array([m.significance for m in modes]), z,
                       np.array([m.significance_in_group for m in modes]), np.array([m.group for m in modes]))
    props = propose(modes, classes, (freq[0], freq[-1]), grid_points(point_angle))
    if not props:
        return modes, synth, []
    D, names = grid_design(point_angle)
    col_of = {n: [k for k, (m, _) in enumerate(names) if m == n] for n, _ in names}
    res = Hb.reshape(-1, K) - synth
    var = (np.median(res.real**2 + res.imag**2, axis=1) / np.log(2)).reshape(n_c, n_p).mean(axis=1)
    w = 1 / np.sqrt(np.maximum(var, np.finfo(float).tiny))
    prob = _Problem(freq, Hb * w[:, None, None], D, col_of, np.array([m.pole for m in modes]),
                    [sorted(k for g in m.order_energy for k in col_of[g]) for m in modes],
                    [(c.n, c.branch) for c in classes], FORM_POWER[form], K, exp_window=window)
    prob.branch_of = {len(modes) + j: p.branch for j, p in enumerate(props)}
    poles, kept, sigma, why = _joint(prob, props)
    nf, modes, synth, rejected = len(modes), list(modes), synth.copy(), []
    f_all = poles_to_modal(poles[np.concatenate([np.ones(nf, dtype=bool), kept])])[0]
    for i in range(nf):  # the found modes moved with a kept proposal: not onto their box's edge, nor within a line
        if poles[i] != prob.poles[i] and abs(poles[i].imag - prob.poles[i].imag) < -0.9 * prob.poles[i].real \
                and abs(np.log(poles[i].real / prob.poles[i].real)) < 0.9 * np.log(MAX_DAMPING_FACTOR) \
                and np.sum(np.abs(f_all - f_all[i]) <= freq[1] - freq[0]) == 1:  # of another pole (a merge)
            modes[i] = replace(modes[i], pole=complex(poles[i]))
    alive = np.concatenate([np.ones(nf, dtype=bool), kept])
    cols = prob.cols + [col_of[p.group] for p in props]
    for j in np.flatnonzero(kept & ~np.array([p.crowd for p in props])):
        p, s = props[j], poles[nf + j]
        lines, Yr, idx = _around(prob, poles, alive, nf + j)
        x = _fit(lines, Yr, D, [cols[i] for i in idx], poles[idx], prob.q)[1][int(np.flatnonzero(idx == nf + j)[0])]
        R = (np.einsum("pk,kc->cp", D, x) / w[:, None]).ravel()
        sig = float(significance(freq, Hb.reshape(-1, K), R[:, None], [s], form=form)[0])
        modes.append(MergedMode(complex(s), p.group, R, sig, {p.group: 1.0}, sig, float(sigma[j] / (2 * np.pi))))
        synth += synthesize(freq, R[:, None], [s], form=form)
    for j, reason in why.items():
        f0, z0 = poles_to_modal(props[j].pole)
        rejected.append({"frequency_hz": float(f0), "damping_ratio": float(z0), "group": int(props[j].group),
                         "reason": f"order n = {props[j].n} ({props[j].branch}) proposed where its branch's "
                                   f"dispersion puts it, not kept: {reason}"})
    order = np.argsort([poles_to_modal(m.pole)[0] for m in modes], kind="stable")
    return [modes[i] for i in order], synth, rejected
