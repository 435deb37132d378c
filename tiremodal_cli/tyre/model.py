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

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.names import PARAMETERS
from tiremodal_cli.tyre.effects import Block

__all__ = ['NOMINAL_RIM_KG', 'FRF_FORMS', 'TyreParameters', 'PAPER_PARAMETERS', 'block', 'closed_form_hz', 'stacked_blocks', 'pair_eigenvalues', 'paper_damping', 'branch_label', 'eig_pairs', 'solve_block', 'dof_list', 'generalised_length', 'fixed_point_hz']


#: Rim (plus hub and fixture) mass assumed when a rim channel shows the rim moving and the
#: nominal parameters give none, kg. The paper gives none; ``diagnose`` tests m_w as a
#: parameter that may be off, so this is a starting value, not a result.
NOMINAL_RIM_KG = 1000.0

FRF_FORMS = ("receptance", "mobility", "accelerance")


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


def stacked_blocks(ns, p: TyreParameters, effects, freq_hz=None) -> Block:
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


def pair_eigenvalues(M, K) -> np.ndarray:
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


def branch_label(vec, dofs, M_diag) -> str:
    energy = M_diag * vec**2
    frac = {k: energy[[j for j, d in enumerate(dofs) if d == k]].sum() / energy.sum()
            for k in set(dofs)}
    if frac.get("A", 0.0) > 0.5:
        return "cavity"
    if "W" in frac and frac["W"] >= max(frac.values()):
        return "rim"
    u, s = vec[dofs.index("U")], vec[dofs.index("S")]
    return "same" if u * s >= 0 else "opposite"


def eig_pairs(M, K):
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


def solve_block(n, p, effects, freq_dependent):
    """Eigenpairs of one order's block; frequency-dependent effects by fixed-point iteration."""
    blk = block(n, p, effects)
    w2, vecs = eig_pairs(blk.M, blk.K)
    if freq_dependent:
        for r in range(len(w2)):
            def g(f, r=r):
                b_f = block(n, p, effects, freq_hz=float(f))
                return np.sqrt(eig_pairs(b_f.M, b_f.K)[0][r]) / (2 * np.pi)
            f = fixed_point_hz(g, np.sqrt(w2[r]) / (2 * np.pi))
            b_f = block(n, p, effects, freq_hz=float(f))
            w2_f, v_f = eig_pairs(b_f.M, b_f.K)
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


def dof_list(p, effects, n_max):
    dofs, spans, blocks = [], {}, {}
    for n in range(n_max + 1):
        blk = block(n, p, effects)
        blocks[n] = blk
        for h in (("cos",) if n == 0 else ("cos", "sin")):
            start = len(dofs)
            dofs.extend((k, n, h) for k in blk.dofs)
            spans[(n, h)] = slice(start, len(dofs))
    return tuple(dofs), spans, blocks


def generalised_length(n, p):
    return (2.0 if n == 0 else 1.0) * np.pi * p.R
