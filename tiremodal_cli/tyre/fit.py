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
from dataclasses import dataclass, field

import numpy as np
import scipy.optimize

from tiremodal_cli.tyre.effects import get_effect
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.tyre.model import TyreParameters, closed_form_hz
from tiremodal_cli.tyre.solve import solve_modes
__all__ = ["MeasuredMode", "FitOptions", "FitResult", "DEFAULT_BOUNDS", "model_frequencies", "fit",
           "modes_from_rows", "predict_table", "fit_report", "PAPER_GA"]

#: Search bounds of each parameter (SI; see docs/model.md for units).
DEFAULT_BOUNDS = {"k_r1": (1e5, 1e8), "k_r2": (1e5, 1e8), "EI": (0.1, 1e4), "rhoA": (1.0, 200.0),
                  "m_s": (0.5, 200.0), "m_w": (1.0, 1e5), "b": (0.02, 2.0)}
#: The paper's genetic-algorithm settings, mapped onto differential evolution.
PAPER_GA = {"population": 20, "generations": 300, "crossover": 0.7, "mutation": 0.1}


@dataclass(frozen=True)
class MeasuredMode:
    """One measured mode matched to the model: order, branch, frequency (Hz)."""

    n: int
    branch: str
    frequency_hz: float
    damping_ratio: float | None = None
    uncertainty_hz: float | None = None
    source: str = ""
    member: str | None = None  # "lower"/"upper" member of a split pair kept apart (diagnose)
    aliased: bool = False  # n above the spatial Nyquist order: read from the dispersion, not the points


@dataclass(frozen=True)
class FitOptions:
    """What to fit and how.

    free : parameters to identify (the rest stay at ``base``)
    bounds : {name: (lo, hi)} overrides of :data:`DEFAULT_BOUNDS` (both > 0)
    weights : "relative" (the paper's RMS of relative errors) or "uncertainty"
    population, generations, crossover, mutation : differential evolution settings
        (``population`` is the number of members; ``mutation`` a constant or a dithering
        range). :data:`PAPER_GA` holds the paper's GA settings (population 20, 300
        generations, crossover 0.7, mutation 0.1); its generation gap (0.9) has no
        counterpart in DE, which replaces each member by a better trial one for one.
    seed : random seed of the search
    effects : {name: {param: value}} candidate effects switched on (fixed values), and
    effect_free : [(effect, param)] effect parameters fitted too (``diagnose``)
    error_floor : relative frequency uncertainty below which the residual variance is not
        taken for the standard errors (0.1 %: an impact test's frequencies)
    tol : relative convergence tolerance of the population's objective spread (DE's
        ``tol``); the default runs every generation, ``diagnose`` stops earlier
    start : {name: value} a known good point put into the initial population (DE's
        ``x0``; names as in ``free``/``"effect.param"``, missing ones at mid-range)
    search : "global" (differential evolution, then least squares) or "local" (with a
        ``start``: least squares from it, safeguarded by ``safeguard`` generations of the
        evolutionary search; the refits of ``diagnose``) or "polish" (with a ``start``: least
        squares from it alone — a refit after one mode more or less, from the optimum of
        a safeguarded search of nearly the same modes)
    """

    free: tuple[str, ...] = ("k_r1", "k_r2", "EI")
    bounds: dict = field(default_factory=dict)
    weights: str = "relative"
    population: int = 45
    generations: int = 300
    crossover: float = 0.7
    mutation: float | tuple = (0.5, 1.0)
    seed: int = 0
    effects: dict = field(default_factory=dict)
    effect_free: tuple = ()
    error_floor: float = 1e-3
    tol: float = 1e-10
    start: dict = field(default_factory=dict)
    search: str = "global"
    safeguard: int = 15
    #: more starts of a "local" search, tried when its end has a parameter pinned to a search
    #: limit (least squares from each; the best end wins): ``diagnose`` adds the nominal
    #: parameters, so that a candidate whose optimum lies far from the current model's (a
    #: Timoshenko tread's EI) is still found
    extra_starts: tuple = ()


@dataclass(frozen=True)
class FitResult:
    """An identification.

    parameters : TyreParameters at the optimum; effects : {name: {param: value}}
    free : names of the fitted quantities (``"k_r1"`` or ``"effect.param"``)
    values, std_errors : (n_free,) arrays ; correlation : (n_free, n_free)
    undetermined : {name: reason} parameters the data cannot determine
    modes : list of dict (n, branch, measured_hz, model_hz, error_pct)
    rms_error_pct, max_error_pct : float
    history : list of (generation, best objective)
    jacobian : (n_modes, n_free) of relative errors w.r.t. log parameters
    """

    parameters: TyreParameters
    effects: dict
    free: tuple
    values: np.ndarray
    std_errors: np.ndarray
    correlation: np.ndarray
    undetermined: dict
    modes: list
    rms_error_pct: float
    max_error_pct: float
    history: list
    jacobian: np.ndarray
    covariance_log: np.ndarray
    options: FitOptions


def modes_from_rows(rows, *, min_confidence: float = 0.5, min_mpc: float = 0.5,
                    source: str = "", split_pairs: str = "mean") -> tuple[list[MeasuredMode], list[dict]]:
    """Measured modes usable for a fit, from table rows (``lsce`` JSON/CSV or a Table A1 CSV).

    Matching rules (docs/identify.md): a row needs ``frequency_hz`` > 0, an integer ``n`` ≥ 0
    and ``branch`` in {same, opposite}; rows with ``n_confidence`` below ``min_confidence``
    are left out, and so are rows with ``mpc`` below ``min_mpc`` (not a normal mode) and rows
    flagged out of their branch's dispersion order (``in_order`` false, from lsce); the two
    members of a split pair (one n and branch twice, within 5 %) enter as their mean
    frequency (``split_pairs="mean"``) or as two modes marked ``member`` "lower" and
    "upper" (``split_pairs="members"``, for ``diagnose``); of one n and branch twice
    farther apart, the more significant row stays.
    Returns the modes and the rows left out with their reasons (each with its ``row``
    number, ``frequency_hz``, and ``n``/``branch`` where the row has them).
    """
    kept, skipped = {}, []
    for i, r in enumerate(rows):
        def get(k):
            v = r.get(k)
            return None if v is None or (isinstance(v, str) and v.strip() == "") else v
        try:
            f = float(get("frequency_hz"))
        except (TypeError, ValueError):
            skipped.append({"row": i + 1, "reason": "no frequency_hz"})
            continue
        n, b = get("n"), get("branch")
        if n is None or b is None:
            skipped.append({"row": i + 1, "frequency_hz": f, "reason": "no n or branch"})
            continue
        try:
            n = int(float(n))
        except ValueError:
            skipped.append({"row": i + 1, "frequency_hz": f, "reason": f"n={n!r} is not an integer"})
            continue
        b = str(b).strip().lower()
        problem = _row_problem(get, n, b, f, min_confidence, min_mpc)
        if problem:
            skipped.append({"row": i + 1, "frequency_hz": f, "n": n, "branch": b, "reason": problem})
            continue
        z = get("damping_ratio")
        u = get("frequency_uncertainty_hz")
        sig = get("significance")
        al = str(get("n_aliased") or "").strip().lower() in ("true", "1")
        kept.setdefault((n, b), []).append((f, None if z is None else float(z), None if u is None else float(u),
                                            1.0 if sig is None else float(sig), i + 1, al))
    modes = []
    for (n, b), vals in sorted(kept.items(), key=lambda kv: np.mean([v[0] for v in kv[1]])):
        if len(vals) > 1:
            # members of a split pair lie close together; a far "duplicate" is a misread
            # order (an alias, a spurious pole): keep the strongest, skip the rest
            vals.sort(key=lambda v: -v[3])
            far = [v for v in vals[1:] if abs(v[0] / vals[0][0] - 1) > 0.05]
            for v in far:
                skipped.append({"row": v[4], "frequency_hz": v[0], "n": n, "branch": b,
                                "reason": f"n={n} {b} already at {vals[0][0]:.2f} Hz (not a split pair: > 5 % apart)"})
            vals = [v for v in vals if v not in far]
        if split_pairs == "members" and len(vals) == 2:
            for v, member in zip(sorted(vals, key=lambda v: v[0]), ("lower", "upper")):
                modes.append(MeasuredMode(n, b, v[0], v[1], v[2], source=f"{source} ({member} member of a split pair)",
                                          member=member, aliased=v[5]))
            continue
        f = float(np.mean([v[0] for v in vals]))
        zs = [v[1] for v in vals if v[1] is not None]
        us = [v[2] for v in vals if v[2] is not None]
        modes.append(MeasuredMode(n, b, f, float(np.mean(zs)) if zs else None, float(np.mean(us)) if us else None,
                                  source=source if len(vals) == 1 else f"{source} (mean of a split pair)",
                                  aliased=any(v[5] for v in vals)))
    return modes, skipped


#: a row explaining less of the physical response than lsce's own cut-off
#: (``ModalOptions.min_significance``) was kept by lsce for its share in its order group
#: alone: a mode, but its order is not trusted for a fit
WEAK_SIGNIFICANCE = 0.05


def _row_problem(get, n, b, f, min_confidence, min_mpc) -> str | None:
    """Why a table row cannot enter the fit (None when it can)."""
    conf, order_ok, mpc = get("n_confidence"), get("in_order"), get("mpc")
    if b not in ("same", "opposite") or n < 0 or not f > 0:
        return f"branch {b!r} / n {n} not fitted"
    crowd = get("crowd")
    if crowd is not None and str(crowd).strip().lower() in ("true", "1"):  # lsce: the order cannot be told
        return f"in a crowd: its order is one of {get('n_candidates') or 'several'}"
    sig = get("significance")
    if sig is not None and float(sig) < WEAK_SIGNIFICANCE:
        # lsce keeps a mode significant in its own order group only; its order is read from
        # a shape that explains little of the measured response
        return f"significance {float(sig):.3f} < {WEAK_SIGNIFICANCE}: its order is read from a weak shape"
    if conf is not None and float(conf) < min_confidence:
        return f"n_confidence {float(conf):.2f} < {min_confidence}"
    if order_ok is not None and str(order_ok).strip().lower() in ("false", "0"):
        return f"n={n} {b} out of its branch's dispersion order"
    if mpc is not None and float(mpc) < min_mpc:
        return f"mpc {float(mpc):.2f} < {min_mpc}: not a normal mode"
    return None


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

    The seed model uses the closed form (and the 3 × 3 problem for n = 1 with a rim);
    block effects the stacked solver :func:`tiremodal_cli.tyre.model.branch_frequencies`;
    coupling effects the assembled problem of :func:`tiremodal_cli.tyre.model.solve_modes`.
    """
    from tiremodal_cli.tyre.effects import resolve_effects
    from tiremodal_cli.tyre.frequencies import branch_frequencies
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
        return out
    if not any(e.couple is not None for e, _ in eff):
        bf = branch_frequencies(ns, p, eff)
        out = np.where(br == "opposite", bf[:, 1], bf[:, 0])
        if cavity.any():
            m = solve_modes(p, n_max=1, effects=eff)
            fc = m.freq_hz[np.array(m.branch) == "cavity"]
            out[cavity] = fc.min() if fc.size else np.nan
        return out
    mem = [None] * ns.size if members is None else list(members)
    coupling = [(e, v) for e, v in eff if e.couple is not None]
    if len(coupling) == 1 and coupling[0][0].extra.get("point_mass") and not cavity.any():
        from tiremodal_cli.tyre.frequencies import point_mass_pairs
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


def _split_free(opt: FitOptions):
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


def _apply(base: TyreParameters, opt: FitOptions, names, logx):
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


def fit(modes: list[MeasuredMode], base: TyreParameters = TyreParameters(), opt: FitOptions = FitOptions(),
        *, progress=None) -> FitResult:
    """Identify the free parameters from measured (n, branch, frequency) modes.

    Raises ParameterError/DataFormatError for no usable modes, fewer modes than free
    parameters, unknown parameters or bad bounds.
    """
    if not modes:
        raise DataFormatError("no usable modes: a fit needs modes with n and branch (same/opposite)")
    names, logb = _split_free(opt)
    if len(modes) < len(names):
        raise DataFormatError(f"{len(modes)} usable modes for {len(names)} free parameters; need at least as many")
    if opt.search not in ("global", "local", "polish"):
        raise ParameterError(f"search={opt.search!r}; allowed: global, local, polish")
    if opt.weights not in ("relative", "uncertainty"):
        raise ParameterError(f"weights={opt.weights!r}; allowed: relative, uncertainty")
    if "m_w" in opt.free and base.m_w is None:
        base = dataclasses.replace(base, m_w=1000.0)
    ns = np.array([m.n for m in modes])
    br = np.array([m.branch for m in modes])
    mem = [m.member for m in modes]
    f_meas = np.array([m.frequency_hz for m in modes])
    if opt.weights == "uncertainty":
        # σ_f: the given uncertainty, else a fifth of the half-power half-bandwidth ζ f
        sig = np.array([m.uncertainty_hz if m.uncertainty_hz else max((m.damping_ratio or 0.02) * m.frequency_hz / 5,
                                                                     1e-4 * m.frequency_hz) for m in modes])
        w = f_meas / sig
    else:
        w = np.ones(len(modes))
    w = w / np.sqrt(np.mean(w**2))

    ev = _Evaluator(base, opt, names, ns, br, mem, f_meas)

    def residuals_batch(logX):
        """(k, S) log parameters → (S, m) weighted relative errors (one array call)."""
        f = ev.frequencies(logX)
        r = (f - f_meas) / f_meas
        return np.where(np.isfinite(r), r, 10.0) * w

    def residuals(logx):
        return residuals_batch(np.asarray(logx, dtype=float)[:, None])[0]

    def objective_batch(logX):
        return np.sqrt(np.mean(residuals_batch(logX) ** 2, axis=1))

    def objective(logx):
        return float(objective_batch(np.asarray(logx, dtype=float)[:, None])[0])

    history = []

    def callback(intermediate_result):
        history.append((len(history) + 1, float(intermediate_result.fun)))
        if progress:
            progress(len(history), opt.generations)

    k = len(names)
    x0 = None
    if opt.start:
        mid = logb.mean(axis=1)
        x0 = np.array([np.log(opt.start[n]) if opt.start.get(n, 0) > 0 else mid[i] for i, n in enumerate(names)])
        x0 = np.clip(x0, logb[:, 0] + 1e-9, logb[:, 1] - 1e-9)
    jac = lambda x: _jacobian(residuals_batch, x)  # noqa: E731
    # the Jacobian by central differences, its 2k points in one array call; the polish stops
    # when a step moves the log parameters by < 1e-10 relative or the cost by < 1e-10: six
    # orders below the smallest standard error a 0.1 % frequency uncertainty allows (at
    # 1e-14 it crawled on for ~30 iterations of no consequence: 85 % of the polish's calls)
    lsq = dict(jac=jac, bounds=(logb[:, 0], logb[:, 1]), x_scale=1.0, xtol=1e-10, ftol=1e-10, gtol=1e-10)
    if opt.search == "polish" and x0 is not None:
        x = scipy.optimize.least_squares(residuals, x0, **lsq).x
    elif opt.search == "local" and x0 is not None:
        x = _local_search(objective_batch, residuals, x0, logb, opt, lsq, history)
        # a parameter pinned to a search limit is the mark of a search caught in a degenerate
        # basin (a Timoshenko tread's EI driven to 0): then try the other starts too
        pinned = np.any((x - logb[:, 0] < 1e-3) | (logb[:, 1] - x < 1e-3))
        for extra in opt.extra_starts if pinned else ():
            x1 = np.array([np.log(extra[n]) if extra.get(n, 0) > 0 else x[i] for i, n in enumerate(names)])
            x1 = np.clip(x1, logb[:, 0] + 1e-9, logb[:, 1] - 1e-9)
            x1 = scipy.optimize.least_squares(residuals, x1, **lsq).x
            if objective(x1) < objective(x):
                x = x1
    else:
        de = scipy.optimize.differential_evolution(
            objective_batch, bounds=list(map(tuple, logb)), popsize=max(1, math.ceil(opt.population / k)),
            maxiter=opt.generations, recombination=opt.crossover,
            mutation=tuple(opt.mutation) if isinstance(opt.mutation, (tuple, list)) else opt.mutation, seed=opt.seed,
            tol=opt.tol, atol=0, polish=False, updating="deferred", vectorized=True, callback=callback,
            init="latinhypercube", x0=x0)
        ls = scipy.optimize.least_squares(residuals, de.x, **lsq)
        x = ls.x if objective(ls.x) <= de.fun else de.x
    history.append((len(history) + 1, objective(x)))
    J = _jacobian(residuals_batch, x)
    r = residuals(x)
    dof = max(len(modes) - k, 1)
    # residual variance, but never below the floor of a measured frequency's uncertainty:
    # a perfect fit of a few modes does not make a parameter known better than the data are
    s2 = max(float(r @ r) / dof, opt.error_floor**2)
    JtJ = J.T @ J
    cov = s2 * np.linalg.pinv(JtJ, rcond=1e-12)
    se_log = np.sqrt(np.clip(np.diag(cov), 0, None))
    vals = np.exp(x)
    se = vals * se_log  # d p = p d ln p
    d = np.sqrt(np.clip(np.diag(cov), 1e-300, None))
    corr = cov / np.outer(d, d)
    undetermined = {}
    sens = np.sqrt(np.mean(J**2, axis=0))
    for i, name in enumerate(names):
        at_bound = x[i] - logb[i, 0] < 1e-3 or logb[i, 1] - x[i] < 1e-3
        if sens[i] < 1e-4:
            undetermined[name] = (f"the measured modes hardly depend on it (RMS ∂ln f/∂ln p = {sens[i]:.1e})")
        elif se_log[i] > 0.5:
            undetermined[name] = f"relative standard error {100 * se_log[i]:.0f} %"
        elif at_bound:
            undetermined[name] = "at a bound of the search"
    p, eff = _apply(base, opt, names, x)
    f_mod = model_frequencies(p, ns, br, eff or None, mem, f_meas)
    err = 100 * (f_mod - f_meas) / f_meas
    table = [{"n": int(m.n), "branch": m.branch, "measured_hz": m.frequency_hz, "model_hz": float(fm),
              "error_pct": float(e), **({"member": m.member} if m.member else {})}
             for m, fm, e in zip(modes, f_mod, err)]
    return FitResult(parameters=p, effects=eff, free=tuple(names), values=vals, std_errors=se, correlation=corr,
                     undetermined=undetermined, modes=table, rms_error_pct=float(np.sqrt(np.mean(err**2))),
                     max_error_pct=float(np.max(np.abs(err))), history=history, jacobian=J, covariance_log=cov,
                     options=opt)


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
    return best


def _jacobian(fun_batch, x, h=1e-6):
    """Central differences of ``fun_batch`` ((k, S) → (S, m)) at ``x``: all 2k points in one call."""
    k = x.size
    X = np.concatenate([x[:, None] + h * np.eye(k), x[:, None] - h * np.eye(k)], axis=1)
    F = fun_batch(X)
    return ((F[:k] - F[k:]) / (2 * h)).T


class _Evaluator:
    """Model frequencies of the measured (n, branch) for a whole population of log
    parameter vectors in one array call (no per-call object rebuilding).

    Built once per fit: which columns are structural parameters, which are effect
    parameters (clipped to their physical limits, as :func:`_apply` does), the fixed
    effects resolved once. Block effects and the seed model go through
    :func:`tiremodal_cli.tyre.model.stacked_branch_frequencies`, one lumped mass through
    :func:`tiremodal_cli.tyre.model.stacked_point_mass_pairs`; another coupling effect set by
    set through :func:`model_frequencies`. ``calls`` and
    ``evaluations`` count array calls and parameter sets (for the benchmarks).
    """

    def __init__(self, base, opt, names, ns, br, mem, f_meas):
        from tiremodal_cli.tyre.effects import resolve_effects

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

    def frequencies(self, logX) -> np.ndarray:
        from tiremodal_cli.tyre.stacked import ParamStack, stacked_branch_frequencies, stacked_point_mass_pairs
        logX = np.asarray(logX, dtype=float)
        S = logX.shape[1]
        self.calls += 1
        self.evaluations += S
        if self.coupling and not self.point_mass:  # a general coupling: the assembled problem, set by set
            out = np.empty((S, self.ns.size))
            for j in range(S):
                p, eff = _apply(self.base, self.opt, self.names, logX[:, j])
                out[j] = model_frequencies(p, self.ns, self.br, eff or None, self.mem, self.f_meas)
            return out
        vals = np.exp(logX)
        P = ParamStack.broadcast(self.base, S, **{nm: vals[i] for i, nm in self.struct})
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
        return F[:, np.arange(self.ns.size), self.col]


def predict_table(res: FitResult, n_max: int, *, measured=()) -> list[dict]:
    """Model frequencies of every (n, branch) up to ``n_max`` with 1σ uncertainty.

    The uncertainty propagates the fit's covariance (in log parameters) through a
    numerical Jacobian of each frequency.
    """
    names = res.free
    logx = np.log(res.values)
    opt = res.options
    base = res.parameters
    ns = np.repeat(np.arange(0, n_max + 1), 2)
    br = np.array(["same", "opposite"] * (n_max + 1))

    def f_of(lx):
        p, eff = _apply(base, opt, names, lx)
        return model_frequencies(p, ns, br, eff or None)

    f0 = f_of(logx)
    J = np.empty((f0.size, logx.size))
    for i in range(logx.size):
        d = np.zeros_like(logx)
        d[i] = 1e-6
        J[:, i] = (f_of(logx + d) - f_of(logx - d)) / 2e-6
    var = np.einsum("ij,jk,ik->i", J, res.covariance_log, J)
    meas = {(m["n"], m["branch"]) for m in measured}
    # a frequency the model cannot differentiate at the fit (a NaN in its Jacobian: the
    # rim-coupled n = 1 root switching branch under the step) has no σ: an explicit null
    return [{"n": int(n), "branch": b, "model_hz": float(f),
             "std_hz": float(np.sqrt(max(v, 0))) if np.isfinite(v) else None,
             **({} if np.isfinite(v) else {"std_reason": "not computable: the model frequency is not "
                                                         "differentiable in the parameters here"}),
             "measured": (int(n), b) in meas} for n, b, f, v in zip(ns, br, f0, var)]


def fit_report(res, skipped, predictions) -> dict:
    """An identification as JSON-ready data (the keys of ``identify --json``)."""
    names = list(res.free)
    return {
        "parameters": {n: {"value": float(v), "std_error": float(s), "relative_std_error_pct": float(100 * s / v)}
                       for n, v, s in zip(names, res.values, res.std_errors)},
        "all_parameters": res.parameters.to_dict(), "effects": res.effects,
        "correlation": {"names": names, "matrix": np.round(res.correlation, 6).tolist()},
        "undetermined": res.undetermined,
        "rms_error_pct": res.rms_error_pct, "max_error_pct": res.max_error_pct,
        "modes": res.modes,
        "not_followed": [m for m in res.modes if abs(m["error_pct"]) > max(2.0, 2 * res.rms_error_pct)],
        "skipped_rows": skipped, "predictions": predictions,
        "history": [{"generation": g, "rms_error_pct": 100 * v} for g, v in res.history],
        "search": {"method": "differential_evolution + least_squares", "seed": res.options.seed,
                   "population": res.options.population, "generations": res.options.generations,
                   "crossover": res.options.crossover, "mutation": res.options.mutation,
                   "weights": res.options.weights},
    }
