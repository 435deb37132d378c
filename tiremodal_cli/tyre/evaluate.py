"""The fit's parameter vector (log parameters) and the model: the free names and their
bounds, a vector applied to the nominal parameters, the model's frequencies for a whole
population of vectors in one array call, and the Jacobian by central differences.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.effects import get_effect, resolve_effects
from tiremodal_cli.tyre.fit_types import DEFAULT_BOUNDS, FitOptions
from tiremodal_cli.tyre.frequencies import model_frequencies, nearer_rim_mode
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.stacked import ParamStack, stacked_branch_frequencies, stacked_point_mass_pairs

__all__ = ['split_free', 'apply_parameters', 'jacobian', 'Evaluator']


def split_free(opt: FitOptions):
    names = list(opt.free) + [f"{e}.{k}" for e, k in opt.effect_free]
    bounds = []

    for name in opt.free:
        if name not in DEFAULT_BOUNDS:
            raise ParameterError(f"cannot fit {name!r}; allowed: {', '.join(DEFAULT_BOUNDS)}")
        lo, hi = opt.bounds.get(name, DEFAULT_BOUNDS[name])
        bounds.append((float(lo), float(hi)))
    for e, k in opt.effect_free:
        par = {q.name: q for q in get_effect(e).parameters}[k]
        lo, hi = opt.bounds.get(f"{e}.{k}", (par.lower, par.upper))
        bounds.append((float(max(lo, 1e-12 * max(hi, 1.0))), float(hi)))
    for name, (lo, hi) in zip(names, bounds):
        if not (lo > 0 and hi > lo and math.isfinite(hi)):
            raise ParameterError(f"bounds of {name}: ({lo:g}, {hi:g}) must be positive and increasing")
    return names, np.log(np.array(bounds))


def apply_parameters(base: TyreParameters, opt: FitOptions, names, logx):
    vals = np.exp(logx)
    p_changes = {n: float(v) for n, v in zip(names, vals) if "." not in n}
    eff = {k: dict(v) for k, v in opt.effects.items()}
    for n, v in zip(names, vals):
        if "." in n:
            e, k = n.split(".", 1)
            par = {q.name: q for q in get_effect(e).parameters}[k]
            # a finite-difference step may cross a physical limit by a rounding: clip to it
            eff.setdefault(e, {})[k] = float(np.clip(v, par.lower, par.upper))
    return dataclasses.replace(base, **p_changes), eff


def jacobian(fun_batch, x, h=1e-6):
    """Central differences of ``fun_batch`` ((k, S) → (S, m)) at ``x``: all 2k points in one call."""
    k = x.size
    X = np.concatenate([x[:, None] + h * np.eye(k), x[:, None] - h * np.eye(k)], axis=1)
    F = fun_batch(X)
    return ((F[:k] - F[k:]) / (2 * h)).T


class Evaluator:
    """Model frequencies of the measured (n, branch) for a whole population of log
    parameter vectors in one array call (no per-call object rebuilding).

    Built once per fit: which columns are structural parameters, which are effect
    parameters (clipped to their physical limits, as :func:`apply_parameters` does), the fixed
    effects resolved once. Block effects and the seed model go through
    :func:`tiremodal_cli.tyre.model.stacked_branch_frequencies`, one lumped mass through
    :func:`tiremodal_cli.tyre.model.stacked_point_mass_pairs`; another coupling effect set by
    set through :func:`model_frequencies`. ``calls`` and
    ``evaluations`` count array calls and parameter sets (for the benchmarks).
    """

    def __init__(self, base, opt, names, ns, br, mem, f_meas):
        self.base, self.opt, self.names = base, opt, list(names)
        self.ns, self.br, self.mem, self.f_meas = ns, br, mem, f_meas
        self.struct = [(i, nm) for i, nm in enumerate(names) if "." not in nm]
        self.free_eff = {}
        for i, nm in enumerate(names):
            if "." in nm:
                e, k = nm.split(".", 1)
                par = {q.name: q for q in get_effect(e).parameters}[k]
                self.free_eff.setdefault(e, []).append((i, k, par.lower, par.upper))
        fixed = {k: dict(v) for k, v in opt.effects.items()}
        for e in self.free_eff:
            fixed.setdefault(e, {})
        self.effects = resolve_effects(fixed)  # defaults overlaid, sorted as model_frequencies has them
        coupling = [e for e, _ in self.effects if e.couple is not None]
        self.coupling = bool(coupling)
        self.point_mass = (len(coupling) == 1 and bool(coupling[0].extra.get("point_mass"))
                           and not np.any(br == "cavity"))
        self.mem_code = np.array([{"lower": 0, "upper": 1}.get(m, -1) for m in mem])
        self.col = np.where(br == "opposite", 1, np.where(br == "cavity", 2, 0))
        self.calls = 0
        self.evaluations = 0
        self._base_columns = {}

    def frequencies(self, logX) -> np.ndarray:
        logX = np.asarray(logX, dtype=float)
        S = logX.shape[1]
        self.calls += 1
        self.evaluations += S
        if self.coupling and not self.point_mass:  # a general coupling: the assembled problem, set by set
            out = np.empty((S, self.ns.size))
            for j in range(S):
                p, eff = apply_parameters(self.base, self.opt, self.names, logX[:, j])
                out[j] = model_frequencies(p, self.ns, self.br, eff or None, self.mem, self.f_meas)
            return out
        vals = np.exp(logX)
        cols = self._base_columns.get(S)
        if cols is None:  # the fixed parameters' columns, built once per stack size
            cols = self._base_columns[S] = {k: None if getattr(self.base, k) is None
                                            else np.full(S, float(getattr(self.base, k))) for k in ParamStack.FIELDS}
        P = ParamStack.of_arrays({**cols, **{nm: vals[i] for i, nm in self.struct}})
        eff = []
        for e, v in self.effects:
            v = dict(v)
            for i, k, lo, hi in self.free_eff.get(e.name, ()):
                v[k] = np.clip(vals[i], lo, hi)
            eff.append((e, v))
        if self.point_mass:  # one lumped mass: the secular equation, as model_frequencies has it
            (e_pm, v_pm), = [(e, v) for e, v in eff if e.couple is not None]
            pairs = stacked_point_mass_pairs(max(2, int(self.ns.max())), P, v_pm[e_pm.extra["point_mass"]], eff)
            pair = pairs[:, self.ns, self.col, :]  # (S, m, 2): lower, upper member
            nearer = np.where(np.abs(pair[..., 1] - self.f_meas) < np.abs(pair[..., 0] - self.f_meas), 1, 0)
            pick = np.where(self.mem_code >= 0, self.mem_code, nearer)
            return np.take_along_axis(pair, pick[..., None], 2)[..., 0]
        F = stacked_branch_frequencies(self.ns, P, eff)
        out = F[:, np.arange(self.ns.size), self.col]
        if self.base.m_w is None or not np.any(self.ns == 1):
            return out
        i1 = np.argmax(self.ns == 1)
        return nearer_rim_mode(out, self.ns, self.br, self.f_meas, F[:, i1, 3], F[:, i1, :2])
