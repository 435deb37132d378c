"""The model's natural frequencies by order and branch, the fast way: each order's block alone
(closed form for 2 × 2, one eigenproblem for n = 1 with a rim), and a lumped mass's
split pairs by the secular equation. :func:`tiremodal_cli.tyre.solve.solve_modes` is the
full solver (coupling effects, shapes).
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.conventions import BRANCHES
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.effects import resolve_effects
from tiremodal_cli.tyre.model import TyreParameters, closed_form_hz, branch_label, fixed_point_hz, generalised_length, pair_eigenvalues, solve_block, stacked_blocks
from tiremodal_cli.tyre.solve import solve_modes

__all__ = ['branch_frequencies', 'point_mass_pairs', 'model_frequencies', 'rim_mode_hz', 'nearer_rim_mode']


def branch_frequencies(ns, p: TyreParameters, effects=()) -> np.ndarray:
    """Same- and opposite-direction frequencies of the orders ``ns`` (block effects only).

    The fast path of identification: orders other than 1 are solved as one stack of
    2 × 2 pencils (the lower root is the same-direction mode: with a diagonal mass and
    a negative tread–sidewall coupling the lower eigenvector is in phase); n = 1 (3 × 3
    with a rim, one more with the air cavity) by :func:`solve_block`, its structural
    modes labelled by :func:`branch_label`. Frequency-dependent effects are iterated to a
    fixed point per mode. Coupling effects are not handled here (use :func:`solve_modes`).

    Parameters
    ----------
    ns : (k,) array of int, ≥ 0
    p : TyreParameters
    effects : resolved effects (see :func:`tiremodal_cli.tyre.effects.resolve_effects`)

    Returns
    -------
    freq_hz : (k, 2) ndarray, Hz
        ``[:, 0]`` same direction, ``[:, 1]`` opposite direction (NaN where a branch has
        no mode).
    """
    ns = np.asarray(ns, dtype=int)
    out = np.full((ns.size, 2), np.nan)
    eff = tuple(effects)
    if any(e.couple is not None for e, _ in eff):
        raise ParameterError("branch_frequencies takes block effects only; use solve_modes for coupling effects")
    freq_dep = any(e.frequency_dependent for e, _ in eff)
    uniq = np.unique(ns)
    rest = uniq[uniq != 1]
    if rest.size:
        blk = stacked_blocks(rest, p, eff)
        w2 = pair_eigenvalues(blk.M, blk.K)
        if freq_dep:
            for r in range(2):
                def g(f, r=r):
                    b_f = stacked_blocks(rest, p, eff, freq_hz=f)
                    return np.sqrt(pair_eigenvalues(b_f.M, b_f.K)[:, r]) / (2 * np.pi)
                w2[:, r] = (2 * np.pi * fixed_point_hz(g, np.sqrt(w2[:, r]) / (2 * np.pi))) ** 2
        idx = np.searchsorted(rest, ns)
        hit = (idx < rest.size) & (rest[np.minimum(idx, rest.size - 1)] == ns)
        out[hit] = np.sqrt(w2[idx[hit]]) / (2 * np.pi)
    if np.any(ns == 1):
        blk, w2, vecs = solve_block(1, p, eff, freq_dep)
        md = np.diag(blk.M)
        labels = [branch_label(vecs[:, r], blk.dofs, md) for r in range(len(w2))]
        f1 = np.sqrt(w2) / (2 * np.pi)
        for col, name in enumerate(BRANCHES):
            sel = [r for r, lab in enumerate(labels) if lab == name]
            if sel:
                out[ns == 1, col] = f1[min(sel, key=lambda r: f1[r])]
    return out


def point_mass_pairs(p: TyreParameters, m_a: float, n_max: int, effects=()) -> dict:
    """Split pairs of every (n, branch) with a point mass m_a (kg) on the tread.

    A point mass adds m_a ψψᵀ (rank one) to the mass matrix. In the modes of the
    axisymmetric model (ω_r², Φ of unit generalised mass) the new ω² are the roots of the
    secular equation ``λ m_a Σ_r c_r² / (ω_r² − λ) = 1`` with c_r = φ_rᵀψ (Golub 1973):
    one below each mode, found here by vectorised bisection. Of each cos/sin pair the
    member with a node at the mass keeps its frequency; the other (c_r² = U_r²/(πR))
    moves down to the root below it. Exact for the same orders as :func:`solve_modes`
    and ~100 × faster than assembling and solving the coupled problem; the position of
    the mass does not enter.

    Returns
    -------
    {(n, branch): (lower_hz, upper_hz)} ; n = 0 has one member (lower = upper)
    """
    eff = tuple(e for e in effects if e[0].couple is None)
    freq_dep = any(e.frequency_dependent for e, _ in eff)
    lam, c2, labels = [], [], []
    for n in range(n_max + 1):
        blk, w2, vecs = solve_block(n, p, eff, freq_dep)
        md = np.diag(blk.M)
        iu = blk.dofs.index("U")
        for r in range(len(w2)):
            lam.append(w2[r])
            c2.append(vecs[iu, r] ** 2 / generalised_length(n, p))
            labels.append((n, branch_label(vecs[:, r], blk.dofs, md)))
    lam, c2 = np.asarray(lam), np.asarray(c2)
    order = np.argsort(lam, kind="stable")
    lam, c2, labels = lam[order], c2[order], [labels[i] for i in order]
    active = c2 > 1e-14 * c2.max()
    la, ca = lam[active], c2[active]
    lo = np.concatenate([[0.0], la[:-1]])
    hi = la.copy()
    a, b = lo.copy(), hi.copy()
    with np.errstate(divide="ignore", invalid="ignore"):  # a bisection midpoint may hit a pole exactly
        for _ in range(80):  # h(λ) = λ m_a Σ c²/(λ_r − λ) − 1 rises from −∞ to +∞ in each interval
            mid = 0.5 * (a + b)
            h = mid * m_a * np.sum(ca[None, :] / (la[None, :] - mid[:, None]), axis=1) - 1.0
            a, b = np.where(h < 0, mid, a), np.where(h < 0, b, mid)
        roots = 0.5 * (a + b)
        # each root's eigenvector is q_r ∝ c_r / (ω_r² − λ): label it by the mode it is most of
        share = ca[None, :] / (la[None, :] - roots[:, None]) ** 2
        dom = np.flatnonzero(active)[np.argmax(np.nan_to_num(share, nan=np.inf), axis=1)]
    lower = {}
    for k, r in enumerate(dom):
        if r not in lower or abs(roots[k] - lam[r]) < abs(lower[r] - lam[r]):
            lower[r] = roots[k]
    out = {}
    for r, (n, br) in enumerate(labels):
        upper = np.sqrt(lam[r]) / (2 * np.pi)
        low = np.sqrt(lower[r]) / (2 * np.pi) if r in lower else upper
        out.setdefault((n, br), (low, low if n == 0 else upper))
    return out


def rim_mode_hz(p: TyreParameters, effects=()) -> float:
    """The n = 1 rim mode's frequency (Hz) of a free rim (block effects only); NaN for a
    clamped rim (``m_w`` None) or where no n = 1 mode is labelled "rim"."""
    if p.m_w is None:
        return float("nan")
    eff = tuple(effects)
    blk, w2, vecs = solve_block(1, p, eff, any(e.frequency_dependent for e, _ in eff))
    md = np.diag(blk.M)
    f = [np.sqrt(w2[r]) / (2 * np.pi) for r in range(len(w2)) if branch_label(vecs[:, r], blk.dofs, md) == "rim"]
    return float(min(f)) if f else float("nan")


def nearer_rim_mode(out, ns, br, meas_hz, f_rim, n1=None):
    """A measured n = 1 mode matched to the nearest (in frequency ratio) of the model's
    n = 1 modes of a free rim, whatever its branch label.

    The modal stage names a branch by the sign of the tread's and the sidewall's motion;
    in the rim mode of a free rim they move in phase, so a measured rim mode reads as
    n = 1 "same". The model labels that mode "rim" (its rim holds the largest share of the
    kinetic energy). With a free rim the n = 1 block has three structural modes (rim, same,
    opposite) whose shapes the rim's motion mixes, so a label read from the sign of two
    motions does not tell them apart: a measured n = 1 mode is the model mode nearest it
    (the rule of an unlabelled split-pair member). ``out`` (k,) or (S, k); ``f_rim`` scalar
    or (S,); ``n1``: the model's n = 1 same and opposite frequencies, (2,) or (S, 2) (None:
    a "same" row between same and rim only). Without measured frequencies or a rim: ``out``.
    """
    if meas_hz is None:
        return out
    ns, br = np.asarray(ns), np.asarray(br)
    rows = (ns == 1) & ((br == "same") if n1 is None else np.isin(br, ("same", "opposite")))
    f_rim = np.asarray(f_rim, dtype=float)
    if not rows.any() or not np.any(np.isfinite(f_rim)):
        return out
    out = np.array(out, dtype=float)
    f_m = np.asarray(meas_hz, dtype=float)[rows]
    cands = [out[..., rows], np.broadcast_to(f_rim[..., None], out[..., rows].shape)]
    if n1 is not None:
        n1 = np.asarray(n1, dtype=float)
        cands += [np.broadcast_to(n1[..., j:j + 1], out[..., rows].shape) for j in range(2)]
    C = np.stack(cands, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(np.isfinite(C) & (C > 0), np.abs(np.log(C / f_m[..., None])), np.inf)
    pick = np.argmin(d, axis=-1)  # ties: the row's own branch (index 0) first
    out[..., rows] = np.take_along_axis(C, pick[..., None], -1)[..., 0]
    return out


def model_frequencies(p: TyreParameters, ns, branches, effects=None, members=None, meas_hz=None) -> np.ndarray:
    """Model frequencies (Hz) of the given (n, branch) pairs.

    Parameters
    ----------
    p : TyreParameters
    ns : (k,) array of int
    branches : (k,) sequence of {"same", "opposite", "cavity"}
    effects : mapping ``{name: {param: value}}`` or resolved effects, optional
    members : (k,) sequence of {None, "lower", "upper"}, optional
        Which member of a cos/sin pair a measured mode is. Only a coupling effect (a
        lumped mass) splits the pairs; then "lower"/"upper" take that member and None
        the member nearer ``meas_hz`` (a pair of which one member was found), or the
        pair's mean without it. Without a coupling both members are one frequency.
    meas_hz : (k,) array, optional — the measured frequencies (for None members)

    Returns
    -------
    freq_hz : (k,) ndarray — NaN where the model has no such mode.

    A measured n = 1 "same" mode is the model's same-direction or rim mode, whichever is
    nearer ``meas_hz`` (:func:`nearer_rim_mode`; not with a coupling effect).

    The seed model uses the closed form (and the 3 × 3 problem for n = 1 with a rim);
    block effects the stacked solver :func:`tiremodal_cli.tyre.model.branch_frequencies`;
    coupling effects the assembled problem of :func:`tiremodal_cli.tyre.model.solve_modes`.
    """
    ns = np.asarray(ns, dtype=int)
    br = np.asarray(branches)
    eff = resolve_effects(effects) if (effects is None or isinstance(effects, dict)) else tuple(effects)
    out = np.full(ns.size, np.nan)
    cavity = br == "cavity"
    if not eff:
        cf = closed_form_hz(ns, p)
        col = (br == "opposite").astype(int)
        out = np.where(cavity, np.nan, cf[np.arange(ns.size), col])
        if p.m_w is not None and np.any(ns == 1):
            m = solve_modes(p, n_max=1)
            for i in np.flatnonzero((ns == 1) & ~cavity):
                sel = (m.n == 1) & (np.array(m.branch) == br[i]) & (np.array(m.harmonic) == "cos")
                out[i] = m.freq_hz[sel][0] if sel.any() else np.nan
        return nearer_rim_mode(out, ns, br, meas_hz, rim_mode_hz(p, eff), _n1(p, eff, ns))
    if not any(e.couple is not None for e, _ in eff):
        bf = branch_frequencies(ns, p, eff)
        out = np.where(br == "opposite", bf[:, 1], bf[:, 0])
        if cavity.any():
            m = solve_modes(p, n_max=1, effects=eff)
            fc = m.freq_hz[np.array(m.branch) == "cavity"]
            out[cavity] = fc.min() if fc.size else np.nan
        return nearer_rim_mode(out, ns, br, meas_hz, rim_mode_hz(p, eff), _n1(p, eff, ns))
    return _coupled_frequencies(p, ns, br, eff, members, meas_hz)


def _n1(p: TyreParameters, eff, ns):
    """The model's n = 1 same and opposite frequencies (Hz, (2,)) of a free rim, or None."""
    if p.m_w is None or not np.any(np.asarray(ns) == 1):
        return None
    return branch_frequencies(np.array([1]), p, eff)[0]


def _coupled_frequencies(p, ns, br, eff, members, meas_hz) -> np.ndarray:
    """:func:`model_frequencies` with a coupling effect: each measured mode the member of its
    (n, branch) pair that ``members`` names (or the one nearer the measured frequency, or the
    pair's mean)."""
    out = np.full(ns.size, np.nan)
    mem = [None] * ns.size if members is None else list(members)
    coupling = [(e, v) for e, v in eff if e.couple is not None]
    if len(coupling) == 1 and coupling[0][0].extra.get("point_mass") and not (br == "cavity").any():
        pairs = point_mass_pairs(p, coupling[0][1][coupling[0][0].extra["point_mass"]], max(2, int(ns.max())), eff)
        lookup = lambda n, b: np.array(pairs.get((n, b), ()))  # noqa: E731
    else:
        m = solve_modes(p, n_max=max(2, int(ns.max())), effects=eff)
        mb = np.array(m.branch)
        lookup = lambda n, b: np.sort(m.freq_hz[(m.n == n) & (mb == b)])  # noqa: E731
    for i, (n, b) in enumerate(zip(ns, br)):
        f = lookup(n, b)
        if f.size == 0:
            continue
        pair = f[:2] if b != "cavity" else f[:1]
        if mem[i] == "lower":
            out[i] = pair[0]
        elif mem[i] == "upper":
            out[i] = pair[-1]
        elif meas_hz is not None:  # one member found: the nearer one
            out[i] = pair[np.argmin(np.abs(pair - meas_hz[i]))]
        else:
            out[i] = pair.mean()
    return out
