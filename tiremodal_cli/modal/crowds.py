"""The crowd test of the tyre classification: modes whose circumferential order cannot be told.

On N points the orders j N ± n_s alias onto one spatial order n_s. When another such order
lies, by its branch's dispersion f(n), within the mode's half-power bandwidth 2ζf, the two
cannot be told apart and the mode is a crowd (:func:`crowds`).

The branch's dispersion beyond its highest measured order: the in-phase ("same") branch
saturates under the sidewall-on-foundation resonance, and its measured top orders are the
crowd itself, biased towards it (their poles blend neighbours within a bandwidth). It is
continued with the model's own dispersion (:func:`saturating_dispersion`): eliminating the
sidewall from the two-degree-of-freedom order-n system of ``/work/shared/MODEL.md``,

    (k_r1 + k_r2 − m_s ω²)(K_n − ρA ω²) = k_r1²,   K_n = k_r1 + T n²/R² + EI n⁴/R⁴,

so with x = f² = (ω/2π)² and the bending term small where the branch saturates,

    (A − x)(α + β n² − δ x) = 1,

A = f∞² the sidewall resonance the branch tends to (its smaller root; the larger is the
anti-phase branch), α, β, δ ≥ 0. Given A the relation is linear in (α, β, δ); A is
searched above the branch's highest measured f².
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize_scalar

from tiremodal_cli.conventions import OPPOSITE, SAME

__all__ = ["branch_dispersion", "candidate_limit", "crowds", "saturating_dispersion"]

#: fewest clear orders n ≥ 2 of a branch the saturating form (4 parameters) is fitted to
MIN_ORDERS_FIT = 6

#: the lowest order from which the anti-phase branch's steps are judged
#: (:func:`_off_the_rising_steps`): below it a free rim (n = 1), the belt's extension (n = 0)
#: and a tangential stiffness (n ≤ 3) move orders off the branch's rise
STEADY_FROM = 3


def _fit_given(A: float, n, x):
    """(α, β, δ) of (A − x)(α + β n² − δ x) = 1 by least squares in x (a residual r of
    1/(A − x) is r (A − x)² in x), and the rms residual of the in-phase root in Hz."""
    w = A - x
    X = np.c_[np.ones_like(n), n * n, -x]
    c = np.linalg.lstsq(X * (w * w)[:, None], w, rcond=None)[0]
    fit = np.array([_root(A, c, q) for q in n])
    return c, float(np.sqrt(np.mean((np.sqrt(np.maximum(fit, 0.0)) - np.sqrt(x)) ** 2)))


def _root(A: float, c, n) -> float:
    """The smaller root x < A of (A − x)(α + β n² − δ x) = 1 (the in-phase branch), Hz²."""
    a, b, d = c
    k = a + b * n * n
    if k <= 0:
        return np.nan
    if d <= 0:
        return A - 1.0 / k
    # d x² − (k + d A) x + (k A − 1) = 0; the root below A
    p = k + d * A
    return float((p - np.sqrt(max(p * p - 4 * d * (k * A - 1), 0.0))) / (2 * d))


def saturating_dispersion(orders, freq_hz):
    """The in-phase branch's f(n) (module docstring), fitted to its clear modes.

    Parameters
    ----------
    orders : (m,) int array     the modes' orders (n ≥ 2 are used: n = 1 holds the rim,
        n = 0 the breathing term, both outside the two-degree-of-freedom system)
    freq_hz : (m,) array, Hz

    Returns
    -------
    callable n -> f (Hz), or None when fewer than :data:`MIN_ORDERS_FIT` orders, the fit
    unphysical (β ≤ 0, δ < 0, a root not rising with n) or the resonance not bracketed
    (the branch shows no saturation)
    """
    n = np.asarray(orders, float)
    f = np.asarray(freq_hz, float)
    keep = n >= 2
    n, x = n[keep], f[keep] ** 2
    if np.unique(n).size < MIN_ORDERS_FIT:
        return None
    top = float(x.max())
    # A = top (1 + e^u): from 1e-6 to 1 (f∞ from just above the highest mode to 1.41 times it)

    def cost(u):
        return _fit_given(top * (1 + np.exp(u)), n, x)[1]

    us = np.linspace(np.log(1e-6), 0.0, 57)  # coarse, then refined between the best's neighbours
    costs = np.array([cost(u) for u in us])
    if not np.any(np.isfinite(costs)):
        return None
    i = int(np.nanargmin(costs))
    if i in (0, us.size - 1):
        return None  # the best resonance at a bound: no saturation to continue
    u = float(minimize_scalar(cost, bounds=(us[i - 1], us[i + 1]), method="bounded", options={"xatol": 1e-4}).x)
    A = top * (1 + np.exp(u))
    c, _ = _fit_given(A, n, x)
    if c[1] <= 0 or c[2] < 0:
        return None
    grid = np.arange(2, 4 * int(n.max()) + 2)
    fg = np.array([_root(A, c, q) for q in grid])
    if not np.all(np.isfinite(fg)) or np.any(np.diff(fg) < 0):
        return None
    return lambda q: float(np.sqrt(max(_root(A, c, float(q)), 0.0)))


def branch_dispersion(orders, freq_hz, branch):
    """A branch's f(n) (Hz) from its clear modes (orders, frequencies): interpolated between
    them (made to rise: the running maximum), and beyond the highest continued — on the
    in-phase branch by the saturating law (:func:`saturating_dispersion`) when it describes
    the branch (its residual at the highest clear mode not below minus its rms residual over
    the orders n ≥ 2: that mode no outlier above the law), else by the larger of the law and
    the last step's slope; on the other branch by the last step's slope. Each errs low where
    its premise fails: the last step when the top orders are the crowd's members biased
    towards it (the ring's n = 16 → 17 at 0.1 Hz per order against the truth's 0.45), the law
    when the sidewall's stiffness rises with n (a sidewall membrane: the branch keeps rising,
    3 Hz per order, and the law falls below its top modes); an order put too low is a false
    crowd (a right label lost), put too high a crowd missed (the label kept, as the order's
    own reading). None with fewer than two orders.

    Parameters
    ----------
    orders : sequence of int         the clear modes' orders (one frequency per order)
    freq_hz : sequence of float, Hz
    branch : str                     "same" (the in-phase branch) or another

    Returns
    -------
    callable n -> f (Hz), or None
    """
    pts = sorted(dict(zip(orders, freq_hz)).items())
    if len(pts) < 2:
        return None
    nn = np.array([p[0] for p in pts], dtype=float)
    ff = np.maximum.accumulate(np.array([p[1] for p in pts]))  # f(n) rises along a branch
    slope = max(0.0, (ff[-1] - ff[-2]) / max(nn[-1] - nn[-2], 1.0))
    sat = saturating_dispersion(nn, [p[1] for p in pts]) if branch == SAME else None
    alone = False
    if sat is not None:
        k2 = nn >= 2  # the orders the law was fitted to
        res = np.array([sat(q) for q in nn[k2]]) - np.array([p[1] for p in pts])[k2]
        alone = bool(res[-1] >= -np.sqrt(np.mean(res**2)))

    def f_of(n):
        if n <= nn[-1]:
            return float(np.interp(n, nn, ff))
        line = float(ff[-1] + slope * (n - nn[-1]))
        if sat is None:
            return line
        return sat(n) if alone else max(line, sat(n))
    return f_of


def _anchored(points: dict, n_points: int) -> dict:
    """A branch's clear orders ({n: f}) up to the first gap of more than N/2 orders: N/2
    consecutive orders hold every spatial order of the grid once, so an order read beyond such a
    gap was inferred by the alias walk across a whole alias span with no mode of the branch
    between — not a measured neighbour to interpolate the dispersion to (the ring's 24 points at
    0.1 % noise: a weak copy at 380.36 Hz read n = 51 same, 27 orders above the crowd's n = 24 at
    166.80 Hz, put the alias n = 29 at 206 Hz and took the crowd's flags)."""
    orders = sorted(points)
    for i in range(1, len(orders)):
        if orders[i] - orders[i - 1] > n_points / 2:
            return {n: points[n] for n in orders[:i]}
    return points


def candidate_limit(n_points: int, top: int) -> int:
    """The highest order a crowd's candidates run to: one alias span N above the branch's
    highest clear order ``top``, and at least 1.5 N. Every spatial order's next alias above
    the orders the branch shows is then a candidate; a fixed 1.5 N had left the 24-point
    paper test at 2,560 Hz, whose opposite branch is read up to n = 60 (2.5 N), with its
    n = 47 at 834 Hz alone, though n = 49 of its alias class lies 18 Hz above, inside the
    52 Hz half-power bandwidth (the two reported as one confident n = 47)."""
    return max(int(1.5 * n_points), int(top) + n_points)


def _below_the_other_root(points: dict, br: str, clear_pts: dict) -> dict:
    """A branch's clear orders ({n: f}) less those on the wrong side of the other branch: the
    in-phase ("same") mode of an order is the smaller root of its two-degree-of-freedom system
    (MODEL.md; :func:`saturating_dispersion`), so no in-phase mode lies above the anti-phase
    mode of its order, nor an anti-phase one below the in-phase. The other branch's f(n) is
    its clear orders interpolated, judged only within their range. Such a row's order is the
    alias walk's inference, not the branch's (the ring's 24-point 5,120 Hz combination at
    seed + 2000: a band-top row at 1,323.3 Hz read as the in-phase n = 25, 166.75 Hz being
    that branch's n = 24 and the anti-phase n = 25 near 700 Hz, became the in-phase branch's
    last step and lifted its continuation off the crowd)."""
    other = clear_pts.get(OPPOSITE if br == SAME else SAME) or {}
    if br not in (SAME, OPPOSITE) or len(other) < 2:
        return points
    no, fo = np.array(sorted(other)), np.array([other[n] for n in sorted(other)])
    out = {}
    for n, fr in points.items():
        if no[0] <= n <= no[-1]:
            f_other = float(np.interp(n, no, fo))
            if (br == SAME and fr > f_other) or (br == OPPOSITE and fr < f_other):
                continue
        out[n] = fr
    return out


def _off_the_rising_steps(points: dict, br: str, half_width: dict) -> dict:
    """The anti-phase ("opposite") branch's clear orders ({n: f}) less those its rise cannot
    hold.

    The anti-phase root of the order-n system (MODEL.md; :func:`saturating_dispersion`)
    rises ever faster with n — K_n grows as T n²/R² and EI n⁴/R⁴ — so its step
    f(n + 1) − f(n) grows with n. Of the physics the generators hold, only a Timoshenko
    tread's shear bends it towards a straight line, lowering a step by at most 3.2 % per
    order (the truth of both tyres, ``TYRES``, and both generators above n = 3; below
    :data:`STEADY_FROM` a free rim, the belt's extension and a tangential stiffness move
    n = 0 … 2 off the rise, and steps fall by up to a half). So an order m read above the
    branch's last two kept orders n1 < n2 (n1 ≥ :data:`STEADY_FROM`) whose rise over the
    gap, f_m − f_n2, falls short of half the last step's, (m − n2) (f_n2 − f_n1) / (n2 − n1),
    by more than m's half-power half-width ``half_width[m]`` (ζ f, Hz: orders within a
    bandwidth of each other are not resolved, and their poles scatter by a fraction of it —
    the paper's 24-point Timoshenko test at 2,560 Hz, n = 56 … 59 on steps of 6–7 Hz at ζ = 3 %)
    is no point of the branch — halving a step takes 21 orders of the steepest decline
    measured — but a copy or leak of a lower order read at its spatial order, and is left out
    of the dispersion. Measured on the passenger-car tyre (docs/validation.md, "Another
    tyre"): a copy of n = 7 at 378.95 Hz read n = 16, 1.1 Hz above n = 7 (the 1,024 Hz test),
    continued the branch at 0.12 Hz per order and put n = 7 in a false crowd with its aliases
    n = 27 and 41; a row at 506.7 Hz read n = 20 under n = 14's 728.6 Hz (40 points), and one
    at 449.0 Hz read n = 15 (receptance), flattened the branch from n = 14 on through the
    running maximum, the same false crowd at n = 14. Kept orders are judged in turn from the
    lowest: a wrong order read too high would shadow the right ones above it (not met on
    the matrix of either tyre). The in-phase branch saturates: no such rule."""
    if br != OPPOSITE:
        return points
    kept: list[tuple[int, float]] = []
    for n, f in sorted(points.items()):
        if len(kept) >= 2 and kept[-2][0] >= STEADY_FROM:
            (n1, f1), (n2, f2) = kept[-2], kept[-1]
            if f - f2 + half_width[n] < 0.5 * (n - n2) * (f2 - f1) / (n2 - n1):
                continue
        kept.append((n, f))
    return dict(kept)


def _alias_class(m: int, n_points: int, n_hi: int) -> set:
    """The orders 0 … n_hi that alias onto spatial order m on a grid of N points (j N ± m)."""
    return {c for j in range(0, n_hi // max(n_points, 1) + 2) for c in (j * n_points - m, j * n_points + m)
            if 0 <= c <= n_hi}


def _seen_at(f_c: float, f_r: float, f, z, same) -> float:
    """Where an order whose dispersion puts it at ``f_c`` (Hz) lies, seen from a mode at
    ``f_r``: at the pole of one of the modes ``same`` (they read this mode's spatial order)
    that has f_c in its own half-power band and lies nearer to f_c than f_r — the order's
    own pole, the nearest such — else at f_c."""
    at = [f[q] for q in same if abs(f[q] - f_c) < min(abs(f_r - f_c), 2 * z[q] * f[q])]
    return min(at, key=lambda x: abs(x - f_c)) if at else f_c


def crowds(freq_hz, damping_ratio, ns, n_spatial, branch, clear, n_points, pair=None):
    """Modes whose order cannot be told: other orders that alias onto the same spatial
    order (n' ≡ ±n_s mod N) lie, by their branch's dispersion, within one half-power
    bandwidth 2ζf of the mode (ζ: below).

    The branch's dispersion f(n) is the frequencies of the modes ``clear`` (both confidences
    ≥ 0.5; :func:`classify` leaves out a mode read as an alias that falls out of its branch's
    order: the walk inferred that order for a mode on the branch, and it is not on it — a
    cavity mode at 254 Hz read n = 38, a leak at 625 Hz read n = 37, which the running
    maximum would lift to the branch's top, flattening it) against their orders,
    interpolated, and beyond the highest measured order continued (:func:`branch_dispersion`:
    the same-direction branch flattens under the sidewall resonance, where many orders pile up).
    Candidates run up to :func:`candidate_limit`. An alias order that another mode of the branch
    holds is no candidate (its pole was found apart from this one, so the two were resolved). Nor is
    one whose own pole the estimator found more than this mode's bandwidth away: a mode reading the
    same spatial order (so any of its aliases) with the order's dispersion frequency f(c) in its own
    half-power band, nearer to f(c) than this mode, is order c's pole (not when it is the other
    member of this mode's split pair, ``pair``: one order twice), and c's mode lies there, not at
    the extrapolated f(c) (the ring's n = 11 same at 159.4 Hz: its alias n = 23 extrapolated to
    165.8 Hz, inside the 6.4 Hz band, found at 166.8 Hz, outside it). The bandwidth is 2ζf with ζ
    the lesser of the mode's own damping and the median over its branch's clear modes (session 39):
    a pole that partly blends the flank of a neighbour it does not resolve is broader than the mode
    (the ring's n = 11 at 5 % noise: ζ 0.0224, not 0.020; its alias n = 23, 7.06 Hz off by the
    truth, fell inside 2ζf = 7.1 Hz, not 6.4 Hz). Returns, per mode, the sorted candidate orders
    (the mode's own included) when it is in a crowd, else ().
    """
    k = len(freq_hz)
    out = [()] * k
    if damping_ratio is None or k == 0:
        return out
    f = np.asarray(freq_hz, dtype=float)
    z = np.asarray(damping_ratio, dtype=float)
    clear_pts = {br: {ns[r]: f[r] for r in range(k) if branch[r] == br and clear[r]} for br in set(branch) - {None}}
    for br in clear_pts:
        mine = [r for r in range(k) if branch[r] == br and clear[r]]
        hw = {ns[r]: z[r] * f[r] for r in mine}  # half-power half-widths, Hz
        on = _anchored(_off_the_rising_steps(_below_the_other_root(clear_pts[br], br, clear_pts), br, hw), n_points)
        f_of = branch_dispersion(list(on), list(on.values()), br)
        if f_of is None:
            continue
        n_hi, z_one = candidate_limit(n_points, max(on)), float(np.median(z[mine]))

        for r in range(k):
            if branch[r] != br:
                continue
            alias = _alias_class(n_spatial[r], n_points, n_hi)
            bw = 2 * min(z[r], z_one) * f[r]
            others = [q for q in range(k) if q != r and branch[q] == br]
            same = [q for q in others if n_spatial[q] in alias
                    and (pair is None or pair[q] is None or pair[q] != pair[r])]

            # an alias order that another mode of the branch holds was resolved: the
            # estimator found its pole apart from this one
            held = {ns[q] for q in others if ns[q] != ns[r]}

            near = sorted(c for c in alias if abs(f_of(c) - f[r]) <= bw
                          and (c == ns[r] or (c not in held and abs(_seen_at(f_of(c), f[r], f, z, same) - f[r]) <= bw)))
            if len(near) > 1:
                out[r] = tuple(int(c) for c in near)
    return out
