"""The model's frequencies for a stack of parameter sets at once (a whole evolutionary
population in one array call): 2 × 2 blocks in closed form, batched eigenproblems for
n = 1, batched fixed points for frequency-dependent effects. The same numbers as
:mod:`tiremodal_cli.tyre.frequencies` for each row (tests/test_speed_equivalence.py).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.effects import Block
from tiremodal_cli.tyre.model import TyreParameters, fixed_point_hz, pair_eigenvalues
__all__ = ['ParamStack', 'stacked_branch_frequencies', 'stacked_point_mass_pairs']


class ParamStack:
    """:class:`TyreParameters` with every field a (N,) array: one value per stacked block.

    What the effects' ``modify_block`` hooks see when a whole population of candidate
    parameter sets is evaluated at once (:func:`stacked_branch_frequencies`); ``m_w`` is
    None for a clamped rim. Not validated: the caller (an optimiser inside its bounds) is.
    """

    FIELDS = ("R", "b", "P0", "rhoA", "m_s", "EI", "k_r1", "k_r2", "m_w")

    def __init__(self, **values):
        for k in self.FIELDS:
            v = values.get(k)
            setattr(self, k, None if v is None else np.asarray(v, dtype=float))

    @classmethod
    def broadcast(cls, p: TyreParameters, size: int, **arrays) -> "ParamStack":
        """``size`` copies of ``p`` with the fields in ``arrays`` ((size,) each) replaced."""
        vals = {k: (None if getattr(p, k) is None else np.full(size, float(getattr(p, k)))) for k in cls.FIELDS}
        vals.update({k: np.broadcast_to(np.asarray(v, dtype=float), (size,)) for k, v in arrays.items()})
        return cls(**vals)

    @classmethod
    def of_arrays(cls, arrays: Mapping) -> "ParamStack":
        """A stack of the given (N,) float arrays as they are (no conversion or copy: the
        evaluator's per-call constructor; every field of :attr:`FIELDS` must be given)."""
        obj = cls.__new__(cls)
        obj.__dict__.update(arrays)
        return obj

    @property
    def T(self):
        return self.P0 * self.b * self.R

    def take(self, idx) -> "ParamStack":
        return ParamStack(**{k: (None if getattr(self, k) is None else getattr(self, k)[idx]) for k in self.FIELDS})


def _take_values(values: Mapping, idx) -> dict:
    return {k: (np.asarray(v)[idx] if np.ndim(v) else v) for k, v in values.items()}


def _stack_block(n, p: ParamStack, effects, freq_hz=None) -> Block:
    """Blocks of the orders ``n`` ((N,) int) for the parameter sets ``p`` (one per row).

    Either no n is 1, or every n is 1 (then the block is 3 × 3 with a rim, and an
    effect may add a coordinate): the stacks of :func:`stacked_branch_frequencies`.
    """
    nf = n.astype(float)
    N = n.size
    Kn = p.EI * nf**4 / p.R**4 + p.T * nf**2 / p.R**2 + p.k_r1
    rim = p.m_w is not None and N > 0 and n[0] == 1
    d = 3 if rim else 2
    M = np.zeros((N, d, d))
    K = np.zeros((N, d, d))
    M[:, 0, 0], M[:, 1, 1] = p.rhoA, p.m_s
    K[:, 0, 0] = Kn
    K[:, 0, 1] = K[:, 1, 0] = -p.k_r1
    K[:, 1, 1] = p.k_r1 + p.k_r2
    if rim:
        M[:, 2, 2] = p.m_w / (np.pi * p.R)
        K[:, 1, 2] = K[:, 2, 1] = -p.k_r2
        K[:, 2, 2] = p.k_r2
    blk = Block(M, K, ("U", "S", "W") if rim else ("U", "S"))
    for eff, values in effects:
        if eff.modify_block is not None:
            blk = eff.modify_block(n, blk, values, p, freq_hz)
    return blk


def _stack_eigh(M, K):
    """Eigenpairs of stacked pencils with diagonal M (every block here): M scaled out and
    one batched ``numpy.linalg.eigh`` call. Returns ω² (N, d) ascending and M-normalised
    vectors (N, d, d), column r the r-th mode."""
    s = 1.0 / np.sqrt(np.diagonal(M, axis1=-2, axis2=-1))
    w2, v = np.linalg.eigh(K * s[:, :, None] * s[:, None, :])
    return np.clip(w2, 0.0, None), v * s[:, :, None]


def _stack_labels(vecs, dofs, M):
    """:func:`branch_label` of every mode of a stack: (N, d) array of 0 same, 1 opposite,
    2 cavity, 3 rim (the same rules: cavity if its coordinate holds > half the kinetic
    energy, rim if the rim holds the largest share, else the sign of U·S)."""
    md = np.diagonal(M, axis1=-2, axis2=-1)
    energy = md[:, :, None] * vecs**2  # (N, dof, mode)
    total = energy.sum(axis=1)
    frac = {k: energy[:, [j for j, d in enumerate(dofs) if d == k], :].sum(axis=1) / total for k in set(dofs)}
    u, s = vecs[:, dofs.index("U"), :], vecs[:, dofs.index("S"), :]
    lab = np.where(u * s >= 0, 0, 1)
    if "W" in frac:
        fmax = np.max(np.stack(list(frac.values())), axis=0)
        lab = np.where(frac["W"] >= fmax, 3, lab)
    if "A" in frac:
        lab = np.where(frac["A"] > 0.5, 2, lab)
    return lab


def stacked_branch_frequencies(ns, p: ParamStack, effects=()) -> np.ndarray:
    """Same-, opposite-direction and cavity frequencies of the orders ``ns`` for a whole
    stack of parameter sets in one array call (block effects only).

    The vectorised form of :func:`branch_frequencies` (the same rules, the same numbers to
    rounding): orders other than 1 of every parameter set are one stack of 2 × 2 pencils
    solved in closed form; n = 1 of every set one stack of 3 × 3 (rim) or 4 × 4 (and the
    cavity) pencils for one batched ``eigh``, its modes labelled as :func:`branch_label` does;
    frequency-dependent effects iterated to a fixed point elementwise over the stack.

    Parameters
    ----------
    ns : (k,) array of int, ≥ 0
    p : ParamStack with (S,) fields — S parameter sets
    effects : sequence of (Effect, values), values scalars or (S,) arrays

    Returns
    -------
    freq_hz : (S, k, 4) ndarray, Hz — ``[..., 0]`` same, ``[..., 1]`` opposite,
        ``[..., 2]`` the lowest cavity mode, ``[..., 3]`` the rim mode of a free rim (n = 1
        only; NaN where there is no such mode)
    """
    ns = np.asarray(ns, dtype=int)
    eff = tuple(effects)
    if any(e.couple is not None for e, _ in eff):
        raise ParameterError("stacked_branch_frequencies takes block effects only")
    S = p.k_r1.size
    out = np.full((S, ns.size, 4), np.nan)
    freq_dep = any(e.frequency_dependent for e, _ in eff)
    uniq = np.unique(ns)
    rest = uniq[uniq != 1]
    if rest.size:
        member = np.repeat(np.arange(S), rest.size)
        nn = np.tile(rest, S)
        pf = p.take(member)
        ef = tuple((e, _take_values(v, member)) for e, v in eff)
        blk = _stack_block(nn, pf, ef)
        w2 = pair_eigenvalues(blk.M, blk.K)
        if freq_dep:  # both roots of every block in one fixed point: each entry (block, root r)
            nn2, root = np.repeat(nn, 2), np.tile([0, 1], nn.size)
            pf2 = pf.take(np.repeat(np.arange(nn.size), 2))
            ef2 = tuple((e, _take_values(v, np.repeat(np.arange(nn.size), 2))) for e, v in ef)
            at = np.arange(nn2.size)

            def g(f):
                b_f = _stack_block(nn2, pf2, ef2, freq_hz=f)
                return np.sqrt(pair_eigenvalues(b_f.M, b_f.K)[at, root]) / (2 * np.pi)
            w2 = ((2 * np.pi * fixed_point_hz(g, np.sqrt(w2.ravel()) / (2 * np.pi))) ** 2).reshape(-1, 2)
        f = (np.sqrt(w2) / (2 * np.pi)).reshape(S, rest.size, 2)
        idx = np.searchsorted(rest, ns)
        hit = (idx < rest.size) & (rest[np.minimum(idx, rest.size - 1)] == ns)
        out[:, hit, :2] = f[:, idx[hit], :]
    if np.any(ns == 1):
        blk, w2, vecs = _stack_modes(np.ones(S, dtype=int), p, eff, freq_dep)
        lab = _stack_labels(vecs, blk.dofs, blk.M)
        f1 = np.sqrt(w2) / (2 * np.pi)
        for col in range(4):
            cand = np.where(lab == col, f1, np.inf).min(axis=1)
            out[:, ns == 1, col] = np.where(np.isfinite(cand), cand, np.nan)[:, None]
    return out


def _stack_modes(n, p: ParamStack, eff, freq_dep):
    """Eigenpairs of a stack of blocks (as :func:`solve_block`, one block per row):
    the block (at no frequency), ω² (N, d) and M-normalised vectors (N, d, d). With a
    frequency-dependent effect every mode r of every block is iterated to its own
    frequency, all in one fixed point over entries (block, r)."""
    N = n.size
    blk = _stack_block(n, p, eff)
    w2, vecs = _stack_eigh(blk.M, blk.K)
    if freq_dep:
        d = w2.shape[1]
        rep = np.repeat(np.arange(N), d)
        n_d, p_d, e_d = n[rep], p.take(rep), tuple((e, _take_values(v, rep)) for e, v in eff)
        root, at = np.tile(np.arange(d), N), np.arange(N * d)

        def g(f):
            b_f = _stack_block(n_d, p_d, e_d, freq_hz=f)
            return np.sqrt(_stack_eigh(b_f.M, b_f.K)[0][at, root]) / (2 * np.pi)
        f = fixed_point_hz(g, np.sqrt(w2.ravel()) / (2 * np.pi))
        b_f = _stack_block(n_d, p_d, e_d, freq_hz=f)
        w2_f, v_f = _stack_eigh(b_f.M, b_f.K)
        w2 = w2_f[at, root].reshape(N, d)
        vecs = v_f[at, :, root].reshape(N, d, d).transpose(0, 2, 1)
    return blk, w2, vecs


def stacked_point_mass_pairs(n_max: int, p: ParamStack, m_a, effects=()) -> np.ndarray:
    """:func:`point_mass_pairs` for a whole stack of parameter sets in one array call.

    The same secular equation and rules (each root labelled by the mode it is most of,
    the root nearest that mode kept as its lower member), solved by vectorised
    bisection over every member and root at once.

    Parameters
    ----------
    n_max : int
    p : ParamStack with (S,) fields
    m_a : float or (S,) array, kg
    effects : block effects (values scalars or (S,) arrays); coupling ones are ignored

    Returns
    -------
    pairs : (S, n_max + 1, 2, 2) ndarray, Hz — [s, n, branch (0 same, 1 opposite),
        (lower, upper)]; NaN where (n, branch) has no mode; n = 0 lower = upper
    """
    lam, c2, lab_n, lab_b = _stacked_spectrum(n_max, p, effects)
    S, R = lam.shape
    active = c2 > 1e-14 * c2.max(axis=1, keepdims=True)
    # the active modes first (ascending), the rest (no pole) pushed to +inf with no weight
    la = np.where(active, lam, np.inf)
    aord = np.argsort(la, axis=1, kind="stable")
    la, ca = np.take_along_axis(la, aord, 1), np.take_along_axis(np.where(active, c2, 0.0), aord, 1)
    ok = np.arange(R)[None, :] < active.sum(axis=1)[:, None]
    roots, dom_act = _secular_roots(la, ca, ok, np.broadcast_to(np.asarray(m_a, dtype=float), (S,))[:, None])
    dom = np.take_along_axis(aord, dom_act, 1)  # index in λ order
    dist = np.where((dom[:, :, None] == np.arange(R)[None, None, :]) & ok[:, :, None],
                    np.abs(roots[:, :, None] - lam[:, None, :]), np.inf)  # (S, root, mode)
    best = np.argmin(dist, axis=1)
    has = np.isfinite(np.min(dist, axis=1))
    lower = np.where(has, np.take_along_axis(roots, best, 1), lam)
    upper_hz, lower_hz = np.sqrt(lam) / (2 * np.pi), np.sqrt(lower) / (2 * np.pi)
    out = np.full((S, n_max + 1, 2, 2), np.nan)
    rows = np.arange(S)
    for r in range(R - 1, -1, -1):  # descending, so the lowest mode of each (n, branch) is written last
        n_r, b_r = lab_n[:, r], lab_b[:, r]
        sel = b_r < 2
        out[rows[sel], n_r[sel], b_r[sel], 0] = lower_hz[sel, r]
        out[rows[sel], n_r[sel], b_r[sel], 1] = np.where(n_r[sel] == 0, lower_hz[sel, r], upper_hz[sel, r])
    return out


def _stacked_spectrum(n_max: int, p: ParamStack, effects):
    """Every mode of orders 0 … n_max of each member without the mass, in ascending order:
    (S, R) eigenvalues ω², squared tread shape at the mass per generalised length, order n
    and branch label."""
    eff = tuple(e for e in effects if e[0].couple is None)
    freq_dep = any(e.frequency_dependent for e, _ in eff)
    S = p.k_r1.size
    lam, c2, lab_n, lab_b = [], [], [], []
    rest = np.array([n for n in range(n_max + 1) if n != 1])
    member = np.repeat(np.arange(S), rest.size)
    for nn, pp, ee in ((np.tile(rest, S), p.take(member), tuple((e, _take_values(v, member)) for e, v in eff)),
                       (np.ones(S, dtype=int), p, eff)):
        blk, w2, vecs = _stack_modes(nn, pp, ee, freq_dep)
        lab = _stack_labels(vecs, blk.dofs, blk.M)
        L = np.where(nn == 0, 2.0, 1.0) * np.pi * pp.R
        U = vecs[:, blk.dofs.index("U"), :]
        d = w2.shape[1]
        k = nn.size // S
        lam.append(w2.reshape(S, k * d))
        c2.append((U**2 / L[:, None]).reshape(S, k * d))
        lab_n.append(np.broadcast_to(nn.reshape(S, k)[:, :, None], (S, k, d)).reshape(S, k * d))
        lab_b.append(lab.reshape(S, k * d))
    lam, c2 = np.concatenate(lam, axis=1), np.concatenate(c2, axis=1)
    lab_n, lab_b = np.concatenate(lab_n, axis=1), np.concatenate(lab_b, axis=1)
    order = np.argsort(lam, axis=1, kind="stable")
    return (np.take_along_axis(lam, order, 1), np.take_along_axis(c2, order, 1),
            np.take_along_axis(lab_n, order, 1), np.take_along_axis(lab_b, order, 1))


def _secular_roots(la, ca, ok, ma):
    """Roots of λ m_a Σ c²/(λ_r − λ) = 1 below each active pole (valid where ``ok``), and
    for each root the index (among the active-sorted modes) of the mode it is most of."""
    S = la.shape[0]
    lo = np.concatenate([np.zeros((S, 1)), la[:, :-1]], axis=1)
    a, b = np.where(ok, lo, 0.0), np.where(ok, la, 1.0)
    lafin = np.where(np.isfinite(la), la, 0.0)
    # bisection as point_mass_pairs (Newton steps crawl here: the lower member's root sits
    # next to its pole), stopped once every bracket is down to rounding
    with np.errstate(divide="ignore", invalid="ignore"):  # a bisection midpoint may hit a pole exactly
        for _ in range(80):  # h(λ) = λ m_a Σ c²/(λ_r − λ) − 1 rises from −∞ to +∞ in each interval
            mid = 0.5 * (a + b)
            h = mid * ma * np.sum(ca[:, None, :] / (lafin[:, None, :] - mid[:, :, None]), axis=2) - 1.0
            a, b = np.where(h < 0, mid, a), np.where(h < 0, b, mid)
            if np.all(b - a <= 4 * np.finfo(float).eps * np.abs(b)):
                break
        roots = 0.5 * (a + b)  # (S, R): root k of member s (valid where ok)
        share = ca[:, None, :] / (lafin[:, None, :] - roots[:, :, None]) ** 2
        dom_act = np.argmax(np.nan_to_num(share, nan=np.inf), axis=2)
    return roots, dom_act
