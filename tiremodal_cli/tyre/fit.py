"""Structural parameters of the tyre model from a modal table.

Measured modes with a circumferential order n and a branch (same/opposite) are matched
to the model's (n, branch) frequencies; the free parameters are found by a global
evolutionary search (``scipy.optimize.differential_evolution``, seeded) over the log of
each parameter within its bounds, then polished by ``scipy.optimize.least_squares``.
The objective is the RMS of the relative frequency errors (the paper's Eq. 18), or of
errors weighted by each frequency's uncertainty. Standard errors and correlations come
from the Jacobian at the optimum; predictions of unmeasured orders carry their
uncertainty by linear propagation.

References
----------
Storn & Price (1997), Differential evolution, J. Global Optim. 11.
Bates & Watts (1988), *Nonlinear Regression Analysis and its Applications* (standard errors).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.optimize

from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.tyre.closed_form import first_estimate
from tiremodal_cli.tyre.evaluate import Evaluator, apply_parameters, jacobian, split_free
from tiremodal_cli.tyre.fit_types import FitOptions, FitResult
from tiremodal_cli.tyre.frequencies import model_frequencies
from tiremodal_cli.tyre.measured import MeasuredMode
from tiremodal_cli.tyre.model import NOMINAL_RIM_KG, TyreParameters

__all__ = ['fit']


def fit(modes: list[MeasuredMode], base: TyreParameters = TyreParameters(), opt: FitOptions = FitOptions(),
        *, progress=None) -> FitResult:
    """Identify the free parameters from measured (n, branch, frequency) modes.

    Raises ParameterError/DataFormatError for no usable modes, fewer modes than free
    parameters, unknown parameters or bad bounds.
    """
    names, logb, base = _checked(modes, base, opt)
    w = _weights(modes, opt)
    if opt.search == "local" and not opt.start:
        # no warm start: the closed-form estimate is one (or, where it does not apply, the
        # full search runs)
        cf = first_estimate(modes, base, tuple(names) if not (opt.effects or opt.effect_free) else (), weights=w)
        opt = dataclasses.replace(opt, start=cf, start_from="closed form") if cf else dataclasses.replace(opt, search="global")
    obj = Objective(Evaluator(base, opt, names, np.array([m.n for m in modes]), np.array([m.branch for m in modes]),
                              [m.member for m in modes], np.array([m.frequency_hz for m in modes])),
                    w, progress=progress, generations=opt.generations)
    x = _search(obj, names, logb, opt)
    obj.history.append((len(obj.history) + 1, obj.objective(x)))
    return _result(obj, x, modes, base, names, logb, opt)


def _checked(modes, base: TyreParameters, opt: FitOptions):
    """The free names and their log bounds, and the base parameters (a rim mass to fit
    given its nominal 1,000 kg); errors for what cannot be fitted."""
    if not modes:
        raise DataFormatError("no usable modes: a fit needs modes with n and branch (same/opposite)")
    names, logb = split_free(opt)
    if len(modes) < len(names):
        raise DataFormatError(f"{len(modes)} usable modes for {len(names)} free parameters; need at least as many")
    if opt.search not in ("global", "local", "polish"):
        raise ParameterError(f"search={opt.search!r}; allowed: global, local, polish")
    if opt.weights not in ("relative", "uncertainty"):
        raise ParameterError(f"weights={opt.weights!r}; allowed: relative, uncertainty")
    if "m_w" in opt.free and base.m_w is None:
        base = dataclasses.replace(base, m_w=NOMINAL_RIM_KG)
    return names, logb, base


def _weights(modes, opt: FitOptions) -> np.ndarray:
    """(m,) weights of the relative errors, RMS 1: f / σ_f (``weights="uncertainty"``) or 1."""
    if opt.weights != "uncertainty":
        w = np.ones(len(modes))
    else:
        # σ_f: the given uncertainty, else a fifth of the half-power half-bandwidth ζ f
        f_meas = np.array([m.frequency_hz for m in modes])
        sig = np.array([m.uncertainty_hz if m.uncertainty_hz else max((m.damping_ratio or 0.02) * m.frequency_hz / 5,
                                                                     1e-4 * m.frequency_hz) for m in modes])
        w = f_meas / sig
    return w / np.sqrt(np.mean(w**2))


class Objective:
    """The fit's weighted relative errors and their RMS, for one log-parameter vector or a
    population of them (one array call); ``history`` holds (generation, best RMS) of the
    search, and ``progress(generation, generations)`` is told of each."""

    def __init__(self, ev: Evaluator, w, *, progress=None, generations: int = 0):
        self.ev, self.w, self.progress, self.generations = ev, w, progress, generations
        self.history = []

    def residuals_batch(self, logX):
        """(k, S) log parameters → (S, m) weighted relative errors (one array call)."""
        f_meas = self.ev.f_meas
        r = (self.ev.frequencies(logX) - f_meas) / f_meas
        return np.where(np.isfinite(r), r, 10.0) * self.w

    def residuals(self, logx):
        return self.residuals_batch(np.asarray(logx, dtype=float)[:, None])[0]

    def objective_batch(self, logX):
        return np.sqrt(np.mean(self.residuals_batch(logX) ** 2, axis=1))

    def objective(self, logx):
        return float(self.objective_batch(np.asarray(logx, dtype=float)[:, None])[0])

    def callback(self, intermediate_result):
        self.history.append((len(self.history) + 1, float(intermediate_result.fun)))
        if self.progress:
            self.progress(len(self.history), self.generations)


def _start_vector(start: dict, names, logb, fallback) -> np.ndarray:
    """A start (``{name: value}``) as a log vector inside the bounds; a name without a
    positive value takes ``fallback``'s entry."""
    x = np.array([np.log(start[n]) if start.get(n, 0) > 0 else fallback[i] for i, n in enumerate(names)])
    return np.clip(x, logb[:, 0] + 1e-9, logb[:, 1] - 1e-9)


def _search(obj: Objective, names, logb, opt: FitOptions) -> np.ndarray:
    """The optimum (log parameters): least squares from the start (``polish``), a local
    search safeguarded by a short global one (``local``), or differential evolution and a
    least-squares polish (``global``, and any search without a start; with a start, the
    whole local search from it and least squares from the extra starts as well, so that it
    contains the local search)."""
    x0 = _start_vector(opt.start, names, logb, logb.mean(axis=1)) if opt.start else None
    jac = lambda x: jacobian(obj.residuals_batch, x)  # noqa: E731
    # the Jacobian by central differences, its 2k points in one array call; the polish stops
    # when a step moves the log parameters by < 1e-10 relative or the cost by < 1e-10: six
    # orders below the smallest standard error a 0.1 % frequency uncertainty allows (at
    # 1e-14 it crawled on for ~30 iterations of no consequence: 85 % of the polish's calls)
    lsq = dict(jac=jac, bounds=(logb[:, 0], logb[:, 1]), x_scale=1.0, xtol=1e-10, ftol=1e-10, gtol=1e-10)
    if opt.search == "polish" and x0 is not None:
        return scipy.optimize.least_squares(obj.residuals, x0, **lsq).x
    if opt.search == "local" and x0 is not None:
        x = _local_search(obj.objective_batch, obj.residuals, x0, logb, opt, lsq, obj.history)
        # a parameter pinned to a search limit is the mark of a search caught in a degenerate
        # basin (a Timoshenko tread's EI driven to 0): then try the other starts too — also
        # when the local search carried a vanishing parameter onto its bound (the ring's
        # tangential k_t left at 5e-5 from the current model, 6.0e5 from the nominal start:
        # 0.29 % against 0.11 % RMS); it costs Table A1's diagnosis 0.25 → 0.6 s of CPU, most
        # of its candidates being absent effects whose parameters vanish
        pinned = np.any((x - logb[:, 0] < 1e-3) | (logb[:, 1] - x < 1e-3))
        for extra in opt.extra_starts if pinned else ():
            x1 = scipy.optimize.least_squares(obj.residuals, _start_vector(extra, names, logb, x), **lsq).x
            if obj.objective(x1) < obj.objective(x):
                x = x1
        return x
    de = scipy.optimize.differential_evolution(
        obj.objective_batch, bounds=list(map(tuple, logb)), popsize=max(1, math.ceil(opt.population / len(names))),
        maxiter=opt.generations, recombination=opt.crossover,
        mutation=tuple(opt.mutation) if isinstance(opt.mutation, (tuple, list)) else opt.mutation, seed=opt.seed,
        tol=opt.tol, atol=0, polish=False, updating="deferred", vectorized=True, callback=obj.callback,
        init="latinhypercube", x0=x0)
    ls = scipy.optimize.least_squares(obj.residuals, de.x, **lsq)
    x = _to_vanishing_bounds(obj.objective_batch, ls.x if obj.objective(ls.x) <= de.fun else de.x, logb)[0]
    # the full search contains the local one: the whole local search from the start (least
    # squares and its safeguard) and least squares from the extra starts, the lowest end
    # wins — DE with the start in its population may still leave a narrow basin next to it
    # unexplored (a Timoshenko tread's), and a reference search must never end above the
    # local search from the same start
    if x0 is None:
        return x
    ends = [_local_search(obj.objective_batch, obj.residuals, x0, logb, opt, lsq, obj.history)]
    ends += [scipy.optimize.least_squares(obj.residuals, _start_vector(e, names, logb, x0), **lsq).x
             for e in opt.extra_starts]
    for x1 in ends:
        if obj.objective(x1) < obj.objective(x):
            x = x1
    return x


def _result(obj: Objective, x, modes, base: TyreParameters, names, logb, opt: FitOptions) -> FitResult:
    """The fit at ``x``: values with standard errors and correlations from the Jacobian,
    the parameters that the modes do not determine, and the mode table."""
    J = jacobian(obj.residuals_batch, x)
    r = obj.residuals(x)
    dof = max(len(modes) - len(names), 1)
    # residual variance, but never below the floor of a measured frequency's uncertainty:
    # a perfect fit of a few modes does not make a parameter known better than the data are
    s2 = max(float(r @ r) / dof, opt.error_floor**2)
    cov = s2 * np.linalg.pinv(J.T @ J, rcond=1e-12)
    se_log = np.sqrt(np.clip(np.diag(cov), 0, None))
    vals = np.exp(x)
    d = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
    p, eff = apply_parameters(base, opt, names, x)
    ev = obj.ev
    f_mod = model_frequencies(p, ev.ns, ev.br, eff or None, ev.mem, ev.f_meas)
    err = 100 * (f_mod - ev.f_meas) / ev.f_meas
    table = [{"n": int(m.n), "branch": m.branch, "measured_hz": m.frequency_hz, "model_hz": float(fm),
              "error_pct": float(e), **({"member": m.member} if m.member else {})}
             for m, fm, e in zip(modes, f_mod, err)]
    return FitResult(parameters=p, effects=eff, free=tuple(names), values=vals, std_errors=vals * se_log,  # d p = p d ln p
                     correlation=cov / np.outer(d, d), undetermined=_undetermined(J, x, se_log, names, logb),
                     modes=table, rms_error_pct=float(np.sqrt(np.mean(err**2))),
                     max_error_pct=float(np.max(np.abs(err))), history=obj.history, jacobian=J, covariance_log=cov,
                     options=opt)


def _undetermined(J, x, se_log, names, logb) -> dict:
    """{name: why} for the parameters the measured modes do not determine."""
    out = {}
    sens = np.sqrt(np.mean(J**2, axis=0))
    for i, name in enumerate(names):
        at_bound = x[i] - logb[i, 0] < 1e-3 or logb[i, 1] - x[i] < 1e-3
        if sens[i] < 1e-4:
            out[name] = (f"the measured modes hardly depend on it (RMS ∂ln f/∂ln p = {sens[i]:.1e})")
        elif se_log[i] > 0.5:
            out[name] = f"relative standard error {100 * se_log[i]:.0f} %"
        elif at_bound:
            out[name] = "at a bound of the search"
    return out


def _local_search(objective_batch, residuals, x0, logb, opt: FitOptions, lsq: dict, history: list) -> np.ndarray:
    """A least-squares search from a warm start, safeguarded by a short global search.

    From ``x0`` (the current fit, a candidate's own parameters at their defaults) least
    squares to the end; then ``safeguard`` generations of the same differential evolution
    as the full search (same population, seeded), its population spread over the bounds
    with the local optimum in it; where it finds a point below that optimum, least squares
    from there too, and the better end point wins. Used by ``diagnose`` for the refits on
    top of a fitted model (``search="local"``); tests/test_speed_equivalence.py checks it
    lands on the full search's optimum.
    """
    ls = scipy.optimize.least_squares(residuals, x0, **lsq)
    best, best_f = ls.x, float(objective_batch(ls.x[:, None])[0])
    history.append((len(history) + 1, best_f))
    k = x0.size
    de = scipy.optimize.differential_evolution(
        objective_batch, bounds=list(map(tuple, logb)), popsize=max(1, math.ceil(opt.population / k)),
        maxiter=opt.safeguard, recombination=opt.crossover,
        mutation=tuple(opt.mutation) if isinstance(opt.mutation, (tuple, list)) else opt.mutation, seed=opt.seed,
        tol=0, atol=0, polish=False, updating="deferred", vectorized=True, init="latinhypercube",
        x0=np.clip(best, logb[:, 0] + 1e-9, logb[:, 1] - 1e-9))
    if de.fun < best_f * (1 - 1e-6):  # another, lower basin: search it to its bottom
        ls = scipy.optimize.least_squares(residuals, de.x, **lsq)
        f_s = float(objective_batch(ls.x[:, None])[0])
        history.append((len(history) + 1, f_s))
        if f_s < best_f:
            best, best_f = ls.x, f_s
    return _to_vanishing_bounds(objective_batch, best, logb)[0]


def _to_vanishing_bounds(objective_batch, x, logb) -> tuple[np.ndarray, float]:
    """``x`` with every parameter whose lower bound fits at least as well moved onto it, and
    its objective.

    An effect's coupling that the modes do not need vanishes: its column of the Jacobian
    (in log parameters) shrinks with it, and least squares stops wherever the gradient
    falls below its tolerance (seen: an air cavity's γ at 1e-6, where the full search goes
    on to the bound at 1e-12). Where the objective at the bound is no higher (to 1e-9
    relative: rounding moves it by ~1e-14, a change the fit could tell is ≥ 1e-6), the end
    is the bound, as the full search's — all such parameters in one array call.
    """
    k = x.size
    f0 = float(objective_batch(x[:, None])[0])
    X = np.repeat(x[:, None], k, axis=1)
    X[np.arange(k), np.arange(k)] = logb[:, 0]
    f = objective_batch(X)
    down = (f <= f0 * (1 + 1e-9)) & (x > logb[:, 0])
    if not down.any():
        return x, f0
    x1 = np.where(down, logb[:, 0], x)
    f1 = float(objective_batch(x1[:, None])[0])
    return (x1, f1) if f1 <= f0 * (1 + 1e-9) else (x, f0)
