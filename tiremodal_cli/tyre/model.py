"""The flexible-beam-on-modified-elastic-foundation tyre model (``docs/model.md``).

Tread: an Euler beam under inflation tension; sidewall: a distributed mass on two radial
springs; rim: rigid, coupled to n = 1 only. With u = U cos nθ the tread stiffness of
order n is ``K_n = EI n⁴/R⁴ + P0 b n²/R + k_r1`` and every order is a small eigenproblem
(2 × 2, or 3 × 3 for n = 1 with a finite rim mass). Candidate effects
(:mod:`tiremodal_cli.tyre.effects`) change those blocks or couple them.

Generalised coordinates: for each order n = 0 … n_max and harmonic ("cos", "sin"; n = 0
has "cos" only) the block's coordinates (U, S, [W], [A]) in m. The generalised mass and
stiffness are the per-length blocks times ∫cos² nθ R dθ = π R (2π R for n = 0), so
shapes normalised to unit generalised mass give receptances in m/N directly.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from tiremodal_cli.conventions import FRF_FORMS
from tiremodal_cli.tyre.effects import Block, resolve_effects
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.names import PARAMETERS

__all__ = ["TyreParameters", "PAPER_PARAMETERS", "ModalModel", "block", "closed_form_hz",
           "branch_frequencies", "point_mass_pairs", "solve_modes", "observation", "frf", "paper_damping", "FRF_FORMS"]



@dataclass(frozen=True)
class TyreParameters:
    """Structural parameters in SI units (per unit arc length where marked).

    Attributes
    ----------
    R : float, m            tread radius
    b : float, m            tread width (the tension is T = P0 b R)
    P0 : float, Pa          inflation pressure
    rhoA : float, kg/m      tread mass per length
    m_s : float, kg/m       sidewall mass per length
    EI : float, N·m²        tread bending stiffness
    k_r1 : float, N/m²      tread–sidewall radial stiffness per length
    k_r2 : float, N/m²      sidewall–rim radial stiffness per length
    m_w : float or None, kg rim (plus fixture) mass; None for a clamped rim
    """

    R: float = 0.65
    b: float = 0.35
    P0: float = 8.0e5
    rhoA: float = 19.64
    m_s: float = 10.0
    EI: float = 25.697
    k_r1: float = 6.686e6
    k_r2: float = 4.431e6
    m_w: float | None = None

    UNITS = {k: u for k, (_, u) in PARAMETERS.items()}  # names and units: tiremodal_cli.names

    def __post_init__(self):
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.name == "m_w" and v is None:
                continue
            if not (isinstance(v, (int, float)) and np.isfinite(v) and v > 0):
                raise ParameterError(f"parameter {f.name}={v!r} must be a positive finite "
                                     f"number ({self.UNITS[f.name]})")

    @property
    def T(self) -> float:
        """Tread hoop pre-tension P0 b R, N."""
        return self.P0 * self.b * self.R

    def replace(self, **changes) -> "TyreParameters":
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_mapping(cls, values: Mapping, base: "TyreParameters | None" = None) -> "TyreParameters":
        """Parameters from a mapping (e.g. a TOML table); unknown keys raise ParameterError."""
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - names)
        if unknown:
            raise ParameterError(f"unknown model parameter {unknown[0]!r}; allowed: "
                                 f"{', '.join(sorted(names))}")
        out = {}
        for k, v in values.items():
            if k == "m_w" and (v is None or (isinstance(v, str) and v.lower() in ("clamped", "none", "inf"))):
                out[k] = None
                continue
            try:
                out[k] = float(v)
            except (TypeError, ValueError):
                raise ParameterError(f"parameter {k}={v!r} is not a number") from None
        return dataclasses.replace(base or cls(), **out)


#: Table 1 and Table 3 of the paper, in consistent SI units (``docs/model.md``).
PAPER_PARAMETERS = TyreParameters()


def block(n: int, p: TyreParameters, effects=(), freq_hz: float | None = None) -> Block:
    """Per-length mass and stiffness of circumferential order ``n``.

    Parameters
    ----------
    n : int, ≥ 0
    p : TyreParameters
    effects : sequence of (Effect, values)
        As returned by :func:`tiremodal_cli.tyre.effects.resolve_effects`.
    freq_hz : float, optional
        Frequency at which frequency-dependent effects are evaluated.
    """
    Kn = p.EI * n**4 / p.R**4 + p.T * n**2 / p.R**2 + p.k_r1
    if n == 1 and p.m_w is not None:
        M = np.diag([p.rhoA, p.m_s, p.m_w / (np.pi * p.R)])
        K = np.array([[Kn, -p.k_r1, 0.0],
                      [-p.k_r1, p.k_r1 + p.k_r2, -p.k_r2],
                      [0.0, -p.k_r2, p.k_r2]])
        blk = Block(M, K, ("U", "S", "W"))
    else:
        M = np.diag([p.rhoA, p.m_s])
        K = np.array([[Kn, -p.k_r1], [-p.k_r1, p.k_r1 + p.k_r2]])
        blk = Block(M, K, ("U", "S"))
    for eff, values in effects:
        if eff.modify_block is not None:
            blk = eff.modify_block(n, blk, values, p, freq_hz)
    return blk


def closed_form_hz(n, p: TyreParameters) -> np.ndarray:
    """The seed model's closed form (MODEL.md) for the 2-DOF orders.

    Parameters
    ----------
    n : int or (k,) array of int
    p : TyreParameters

    Returns
    -------
    freq_hz : (..., 2) ndarray
        ``[..., 0]`` the same-direction, ``[..., 1]`` the opposite-direction frequency.
    """
    n = np.asarray(n, dtype=float)
    Kn = p.EI * n**4 / p.R**4 + p.P0 * p.b * n**2 / p.R + p.k_r1
    B = Kn * p.m_s + p.rhoA * (p.k_r1 + p.k_r2)
    C = Kn * (p.k_r1 + p.k_r2) - p.k_r1**2
    disc = np.sqrt(B * B - 4 * p.rhoA * p.m_s * C)
    w2 = np.stack([(B - disc), (B + disc)], axis=-1) / (2 * p.rhoA * p.m_s)
    return np.sqrt(w2) / (2 * np.pi)


def _stacked_blocks(ns, p: TyreParameters, effects, freq_hz=None) -> Block:
    """The 2 × 2 blocks of the orders ``ns`` (none of them 1) as (k, 2, 2) stacks."""
    n = np.asarray(ns, dtype=float)
    M = np.zeros((n.size, 2, 2))
    K = np.empty((n.size, 2, 2))
    M[:, 0, 0], M[:, 1, 1] = p.rhoA, p.m_s
    K[:, 0, 0] = p.EI * n**4 / p.R**4 + p.T * n**2 / p.R**2 + p.k_r1
    K[:, 0, 1] = K[:, 1, 0] = -p.k_r1
    K[:, 1, 1] = p.k_r1 + p.k_r2
    blk = Block(M, K, ("U", "S"))
    for eff, values in effects:
        if eff.modify_block is not None:
            blk = eff.modify_block(np.asarray(ns, dtype=int), blk, values, p, freq_hz)
    if np.shape(blk.M)[-1] != 2:
        raise ParameterError("an effect changed the size of a block other than n = 1")
    return blk


def _pair_eigenvalues(M, K) -> np.ndarray:
    """Both ω² of stacked symmetric 2 × 2 pencils (K − ω² M) in closed form, ascending.

    Written out because numpy/scipy have no batched generalised eigensolver; the
    quadratic det(K − λM) = 0 is exact and ~100 × faster than a loop of eigh calls.
    """
    a = M[:, 0, 0] * M[:, 1, 1] - M[:, 0, 1] ** 2
    b = -(M[:, 0, 0] * K[:, 1, 1] + M[:, 1, 1] * K[:, 0, 0] - 2 * M[:, 0, 1] * K[:, 0, 1])
    c = K[:, 0, 0] * K[:, 1, 1] - K[:, 0, 1] ** 2
    disc = np.sqrt(np.clip(b * b - 4 * a * c, 0.0, None))
    # the smaller root as c / (a λ_large) avoids cancellation when c is small
    big = (-b + disc) / (2 * a)
    small = np.divide(c, a * big, out=np.zeros_like(big), where=big > 0)
    return np.clip(np.stack([small, big], axis=-1), 0.0, None)


def branch_frequencies(ns, p: TyreParameters, effects=()) -> np.ndarray:
    """Same- and opposite-direction frequencies of the orders ``ns`` (block effects only).

    The fast path of identification: orders other than 1 are solved as one stack of
    2 × 2 pencils (the lower root is the same-direction mode: with a diagonal mass and
    a negative tread–sidewall coupling the lower eigenvector is in phase); n = 1 (3 × 3
    with a rim, one more with the air cavity) by :func:`_solve_block`, its structural
    modes labelled by :func:`_branch`. Frequency-dependent effects are iterated to a
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
        blk = _stacked_blocks(rest, p, eff)
        w2 = _pair_eigenvalues(blk.M, blk.K)
        if freq_dep:
            for r in range(2):
                def g(f, r=r):
                    b_f = _stacked_blocks(rest, p, eff, freq_hz=f)
                    return np.sqrt(_pair_eigenvalues(b_f.M, b_f.K)[:, r]) / (2 * np.pi)
                w2[:, r] = (2 * np.pi * fixed_point_hz(g, np.sqrt(w2[:, r]) / (2 * np.pi))) ** 2
        idx = np.searchsorted(rest, ns)
        hit = (idx < rest.size) & (rest[np.minimum(idx, rest.size - 1)] == ns)
        out[hit] = np.sqrt(w2[idx[hit]]) / (2 * np.pi)
    if np.any(ns == 1):
        blk, w2, vecs = _solve_block(1, p, eff, freq_dep)
        md = np.diag(blk.M)
        labels = [_branch(vecs[:, r], blk.dofs, md) for r in range(len(w2))]
        f1 = np.sqrt(w2) / (2 * np.pi)
        for col, name in enumerate(("same", "opposite")):
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
        blk, w2, vecs = _solve_block(n, p, eff, freq_dep)
        md = np.diag(blk.M)
        iu = blk.dofs.index("U")
        for r in range(len(w2)):
            lam.append(w2[r])
            c2.append(vecs[iu, r] ** 2 / _length(n, p))
            labels.append((n, _branch(vecs[:, r], blk.dofs, md)))
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


def paper_damping(n: int, branch: str) -> float:
    """Modal damping ratio of the paper's order (Table A1), by n and branch.

    Same-direction n = 1…8 and opposite-direction n = 1…10 take the measured values;
    higher orders the last one; n = 0 and the rim mode 2 %; the air-cavity mode 0.5 %
    (an acoustic mode of a closed cavity is lightly damped: 0.5–1 % in tyre
    measurements, which is why it shows as a sharp peak).
    """
    if branch == "cavity":
        return 0.005
    same = (0.0192, 0.0163, 0.0179, 0.0202, 0.0242, 0.0291, 0.0359, 0.0376)
    opp = (0.0213, 0.0215, 0.0189, 0.0196, 0.0228, 0.0245, 0.0254, 0.0272, 0.0282, 0.0307)
    if n >= 1 and branch == "same":
        return same[min(n, len(same)) - 1]
    if n >= 1 and branch == "opposite":
        return opp[min(n, len(opp)) - 1]
    return 0.02


@dataclass(frozen=True)
class ModalModel:
    """Modes of the tyre model.

    Attributes
    ----------
    freq_hz : (n_modes,) ndarray, Hz       sorted ascending
    n : (n_modes,) ndarray of int          circumferential order (dominant one if coupled)
    harmonic : tuple of str                "cos", "sin" or "mixed"
    branch : tuple of str                  "same", "opposite", "rim" or "cavity"
    shapes : (n_modes, n_dof) ndarray      unit generalised mass, m/√kg
    dofs : tuple of (kind, n, harmonic)    the generalised coordinates
    """

    freq_hz: np.ndarray
    n: np.ndarray
    harmonic: tuple[str, ...]
    branch: tuple[str, ...]
    shapes: np.ndarray
    dofs: tuple[tuple[str, int, str], ...]

    def select(self, mask) -> "ModalModel":
        idx = np.flatnonzero(mask)
        return ModalModel(self.freq_hz[idx], self.n[idx], tuple(self.harmonic[i] for i in idx),
                          tuple(self.branch[i] for i in idx), self.shapes[idx], self.dofs)


def _branch(vec, dofs, M_diag) -> str:
    energy = M_diag * vec**2
    frac = {k: energy[[j for j, d in enumerate(dofs) if d == k]].sum() / energy.sum()
            for k in set(dofs)}
    if frac.get("A", 0.0) > 0.5:
        return "cavity"
    if "W" in frac and frac["W"] >= max(frac.values()):
        return "rim"
    u, s = vec[dofs.index("U")], vec[dofs.index("S")]
    return "same" if u * s >= 0 else "opposite"


def _eig(M, K):
    """Generalised eigenpairs, vectors M-normalised. A diagonal M (every block here) is
    scaled out and numpy's eigh used: the same result at a fifth of scipy's call cost,
    which matters for the thousands of small solves of an identification."""
    d = np.diag(M)
    if d.size <= 8 and np.all(d > 0) and not np.any(M - np.diag(d)):
        s = 1.0 / np.sqrt(d)
        w2, v = np.linalg.eigh(K * s[:, None] * s[None, :])
        return np.clip(w2, 0.0, None), v * s[:, None]
    w2, vecs = scipy.linalg.eigh(K, M)
    return np.clip(w2, 0.0, None), vecs


def _solve_block(n, p, effects, freq_dependent):
    """Eigenpairs of one order's block; frequency-dependent effects by fixed-point iteration."""
    blk = block(n, p, effects)
    w2, vecs = _eig(blk.M, blk.K)
    if freq_dependent:
        for r in range(len(w2)):
            def g(f, r=r):
                b_f = block(n, p, effects, freq_hz=float(f))
                return np.sqrt(_eig(b_f.M, b_f.K)[0][r]) / (2 * np.pi)
            f = fixed_point_hz(g, np.sqrt(w2[r]) / (2 * np.pi))
            b_f = block(n, p, effects, freq_hz=float(f))
            w2_f, v_f = _eig(b_f.M, b_f.K)
            w2[r], vecs[:, r] = w2_f[r], v_f[:, r]
    return blk, w2, vecs


def fixed_point_hz(g, f0, *, rtol: float = 1e-12, max_iter: int = 60):
    """Solve f = g(f) (a mode's frequency at its own frequency) by secant steps.

    Plain iteration converges at the rate of the effect's slope (β/2 for a power-law
    rubber, ~10 steps); the secant on h(f) = g(f) − f takes ~4. Works elementwise on
    arrays; falls back to the plain step where the secant is undefined.
    """
    f_prev = np.asarray(f0, dtype=float)
    h_prev = g(f_prev) - f_prev
    f = f_prev + h_prev
    for _ in range(max_iter):
        h = g(f) - f
        if np.all(np.abs(h) <= rtol * np.maximum(np.abs(f), 1.0)):
            return f
        dh = h - h_prev
        ok = np.abs(dh) > 1e-300
        step = np.where(ok, -h * (f - f_prev) / np.where(ok, dh, 1.0), h)
        f_prev, h_prev = f, h
        f = np.maximum(f + step, 1e-9)
    return f


def _dof_list(p, effects, n_max):
    dofs, spans, blocks = [], {}, {}
    for n in range(n_max + 1):
        blk = block(n, p, effects)
        blocks[n] = blk
        for h in (("cos",) if n == 0 else ("cos", "sin")):
            start = len(dofs)
            dofs.extend((k, n, h) for k in blk.dofs)
            spans[(n, h)] = slice(start, len(dofs))
    return tuple(dofs), spans, blocks


def _length(n, p):
    return (2.0 if n == 0 else 1.0) * np.pi * p.R


def solve_modes(p: TyreParameters, *, n_max: int = 30, effects=None) -> ModalModel:
    """All modes of orders 0 … ``n_max`` (both harmonics of every n ≥ 1).

    Parameters
    ----------
    p : TyreParameters
    n_max : int, keyword-only
    effects : mapping ``{name: {param: value}}`` or resolved sequence, keyword-only

    Returns
    -------
    ModalModel
        Without a coupling effect every mode is a pure (n, harmonic); with one (a lumped
        mass) the modes of the assembled system are labelled by their dominant order.
    """
    if not (isinstance(n_max, (int, np.integer)) and n_max >= 1):
        raise ParameterError(f"n_max={n_max!r} must be an integer ≥ 1")
    eff = resolve_effects(effects) if (effects is None or isinstance(effects, Mapping)) else tuple(effects)
    freq_dep = any(e.frequency_dependent for e, _ in eff)
    coupling = [(e, v) for e, v in eff if e.couple is not None]
    dofs, spans, _ = _dof_list(p, eff, n_max)
    nd = len(dofs)
    if not coupling:
        freqs, ns, harms, branches, shapes = [], [], [], [], []
        for n in range(n_max + 1):
            blk, w2, vecs = _solve_block(n, p, eff, freq_dep)
            L = _length(n, p)
            md = np.diag(blk.M)
            for h in (("cos",) if n == 0 else ("cos", "sin")):
                for r in range(len(w2)):
                    phi = np.zeros(nd)
                    phi[spans[(n, h)]] = vecs[:, r] / np.sqrt(L)
                    freqs.append(np.sqrt(w2[r]) / (2 * np.pi))
                    ns.append(n)
                    harms.append(h)
                    branches.append(_branch(vecs[:, r], blk.dofs, md))
                    shapes.append(phi)
        order = np.argsort(np.asarray(freqs), kind="stable")
        return ModalModel(np.asarray(freqs)[order], np.asarray(ns)[order],
                          tuple(harms[i] for i in order), tuple(branches[i] for i in order),
                          np.asarray(shapes)[order], dofs)
    return _solve_coupled(p, eff, coupling, dofs, spans, n_max, freq_dep)


def _assemble(p, eff, coupling, dofs, spans, n_max, freq_hz=None):
    M = np.zeros((len(dofs),) * 2)
    K = np.zeros_like(M)
    for n in range(n_max + 1):
        blk = block(n, p, eff, freq_hz=freq_hz)
        L = _length(n, p)
        for h in (("cos",) if n == 0 else ("cos", "sin")):
            s = spans[(n, h)]
            M[s, s] = L * blk.M
            K[s, s] = L * blk.K
    for e, v in coupling:
        M, K = e.couple(M, K, dofs, v, p)
    return M, K


def _solve_coupled(p, eff, coupling, dofs, spans, n_max, freq_dep):
    M, K = _assemble(p, eff, coupling, dofs, spans, n_max)
    w2, vecs = _eig(M, K)
    if freq_dep:
        for r in range(len(w2)):
            f = np.sqrt(w2[r]) / (2 * np.pi)
            for _ in range(100):
                Mf, Kf = _assemble(p, eff, coupling, dofs, spans, n_max, freq_hz=f)
                w2_f, v_f = _eig(Mf, Kf)
                f_new = np.sqrt(w2_f[r]) / (2 * np.pi)
                done = abs(f_new - f) <= 1e-12 * max(f, 1.0)
                f = f_new
                if done:
                    break
            w2[r], vecs[:, r] = w2_f[r], v_f[:, r]
    ns, harms, branches = [], [], []
    kinds = np.array([d[0] for d in dofs])
    dof_n = np.array([d[1] for d in dofs])
    dof_h = np.array([d[2] for d in dofs])
    md = np.diag(M)
    for r in range(len(w2)):
        e = md * vecs[:, r] ** 2
        n_dom = int(np.argmax(np.bincount(dof_n, weights=e, minlength=n_max + 1)))
        sel = dof_n == n_dom
        e_cos, e_sin = e[sel & (dof_h == "cos")].sum(), e[sel & (dof_h == "sin")].sum()
        tot = e_cos + e_sin
        harm = "cos" if e_cos > 0.9 * tot else "sin" if e_sin > 0.9 * tot else "mixed"
        h_dom = "cos" if e_cos >= e_sin else "sin"
        sub = sel & (dof_h == h_dom)
        branches.append(_branch(vecs[sub, r], tuple(kinds[sub]), md[sub]))
        ns.append(n_dom)
        harms.append(harm)
    return ModalModel(np.sqrt(w2) / (2 * np.pi), np.asarray(ns), tuple(harms), tuple(branches),
                      vecs.T.copy(), dofs)


def observation(dofs, location: str, angle_rad: float) -> np.ndarray:
    """Weights that turn generalised coordinates into a radial displacement.

    Parameters
    ----------
    dofs : tuple of (kind, n, harmonic)
    location : {"tread", "sidewall", "rim"}
    angle_rad : float, rad

    Returns
    -------
    c : (n_dof,) ndarray
        ``u(θ) = c @ q``; the same vector is the generalised force of a unit radial point
        force at that place (reciprocity).
    """
    kind = {"tread": "U", "sidewall": "S", "rim": "W"}.get(location)
    if kind is None:
        raise ParameterError(f"location={location!r}; allowed: tread, sidewall, rim")
    c = np.zeros(len(dofs))
    for j, (k, n, h) in enumerate(dofs):
        if k == kind:
            c[j] = np.cos(n * angle_rad) if h == "cos" else np.sin(n * angle_rad)
    return c


def frf(model: ModalModel, freq_hz, damping_ratio, out_locations, out_angles, in_angles, *,
        form: str = "accelerance") -> np.ndarray:
    """FRFs between tread point forces and radial responses, by modal superposition.

    ``H_oi(ω) = Σ_r c_o·φ_r c_i·φ_r / (ω_r² − ω² + 2iζ_r ω_r ω)`` (receptance), times
    iω (mobility) or −ω² (accelerance).

    Parameters
    ----------
    model : ModalModel
    freq_hz : (n_freq,) array, Hz
    damping_ratio : float or (n_modes,) array
    out_locations : sequence of str, length n_out
    out_angles : (n_out,) array, rad
    in_angles : (n_in,) array, rad      angles of the tread point forces
    form : {"receptance", "mobility", "accelerance"}

    Returns
    -------
    H : (n_out, n_in, n_freq) complex ndarray
        m/N, m/(s·N) or m/(s²·N).
    """
    if form not in FRF_FORMS:
        raise ParameterError(f"form={form!r}; allowed: {', '.join(FRF_FORMS)}")
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    wr = 2 * np.pi * model.freq_hz
    zeta = np.broadcast_to(np.asarray(damping_ratio, dtype=float), wr.shape)
    C_out = np.array([observation(model.dofs, loc, a) for loc, a in zip(out_locations, out_angles)])
    C_in = np.array([observation(model.dofs, "tread", a) for a in np.atleast_1d(in_angles)])
    po = C_out @ model.shapes.T  # (n_out, n_modes)
    pi = C_in @ model.shapes.T  # (n_in, n_modes)
    den = wr[:, None] ** 2 - w[None, :] ** 2 + 2j * zeta[:, None] * wr[:, None] * w[None, :]
    H = np.einsum("or,ir,rf->oif", po, pi, 1.0 / den)
    if form == "mobility":
        H = H * (1j * w)
    elif form == "accelerance":
        H = H * (-(w**2))
    return H


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
    """:func:`_branch` of every mode of a stack: (N, d) array of 0 same, 1 opposite,
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
    cavity) pencils for one batched ``eigh``, its modes labelled as :func:`_branch` does;
    frequency-dependent effects iterated to a fixed point elementwise over the stack.

    Parameters
    ----------
    ns : (k,) array of int, ≥ 0
    p : ParamStack with (S,) fields — S parameter sets
    effects : sequence of (Effect, values), values scalars or (S,) arrays

    Returns
    -------
    freq_hz : (S, k, 3) ndarray, Hz — ``[..., 0]`` same, ``[..., 1]`` opposite,
        ``[..., 2]`` the lowest cavity mode (NaN where there is no such mode)
    """
    ns = np.asarray(ns, dtype=int)
    eff = tuple(effects)
    if any(e.couple is not None for e, _ in eff):
        raise ParameterError("stacked_branch_frequencies takes block effects only")
    S = p.k_r1.size
    out = np.full((S, ns.size, 3), np.nan)
    freq_dep = any(e.frequency_dependent for e, _ in eff)
    uniq = np.unique(ns)
    rest = uniq[uniq != 1]
    if rest.size:
        member = np.repeat(np.arange(S), rest.size)
        nn = np.tile(rest, S)
        pf = p.take(member)
        ef = tuple((e, _take_values(v, member)) for e, v in eff)
        blk = _stack_block(nn, pf, ef)
        w2 = _pair_eigenvalues(blk.M, blk.K)
        if freq_dep:  # both roots of every block in one fixed point: each entry (block, root r)
            nn2, root = np.repeat(nn, 2), np.tile([0, 1], nn.size)
            pf2 = pf.take(np.repeat(np.arange(nn.size), 2))
            ef2 = tuple((e, _take_values(v, np.repeat(np.arange(nn.size), 2))) for e, v in ef)
            at = np.arange(nn2.size)

            def g(f):
                b_f = _stack_block(nn2, pf2, ef2, freq_hz=f)
                return np.sqrt(_pair_eigenvalues(b_f.M, b_f.K)[at, root]) / (2 * np.pi)
            w2 = ((2 * np.pi * fixed_point_hz(g, np.sqrt(w2.ravel()) / (2 * np.pi))) ** 2).reshape(-1, 2)
        f = (np.sqrt(w2) / (2 * np.pi)).reshape(S, rest.size, 2)
        idx = np.searchsorted(rest, ns)
        hit = (idx < rest.size) & (rest[np.minimum(idx, rest.size - 1)] == ns)
        out[:, hit, :2] = f[:, idx[hit], :]
    if np.any(ns == 1):
        blk, w2, vecs = _stack_modes(np.ones(S, dtype=int), p, eff, freq_dep)
        lab = _stack_labels(vecs, blk.dofs, blk.M)
        f1 = np.sqrt(w2) / (2 * np.pi)
        for col in range(3):
            cand = np.where(lab == col, f1, np.inf).min(axis=1)
            out[:, ns == 1, col] = np.where(np.isfinite(cand), cand, np.nan)[:, None]
    return out


def _stack_modes(n, p: ParamStack, eff, freq_dep):
    """Eigenpairs of a stack of blocks (as :func:`_solve_block`, one block per row):
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
    lam, c2 = np.take_along_axis(lam, order, 1), np.take_along_axis(c2, order, 1)
    lab_n, lab_b = np.take_along_axis(lab_n, order, 1), np.take_along_axis(lab_b, order, 1)
    R = lam.shape[1]
    active = c2 > 1e-14 * c2.max(axis=1, keepdims=True)
    # the active modes first (ascending), the rest (no pole) pushed to +inf with no weight
    la = np.where(active, lam, np.inf)
    aord = np.argsort(la, axis=1, kind="stable")
    la, ca = np.take_along_axis(la, aord, 1), np.take_along_axis(np.where(active, c2, 0.0), aord, 1)
    n_act = active.sum(axis=1)
    ok = np.arange(R)[None, :] < n_act[:, None]
    lo = np.concatenate([np.zeros((S, 1)), la[:, :-1]], axis=1)
    a, b = np.where(ok, lo, 0.0), np.where(ok, la, 1.0)
    ma = np.broadcast_to(np.asarray(m_a, dtype=float), (S,))[:, None]
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
        dom_act = np.argmax(np.nan_to_num(share, nan=np.inf), axis=2)  # index among the active-sorted modes
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
