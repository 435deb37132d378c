"""Close the loop: the residual of a fit, the physics that explains it, the model with it.

After the base fit (:func:`tiremodal_cli.tyre.fit.fit`) the residual of every measured
mode is compared with its uncertainty; if it exceeds the noise, every candidate of
:mod:`tiremodal_cli.tyre.effects` (and every nominal parameter that may be off) is fitted in
turn on top of the current model and scored. A candidate is adopted only when

1. the current residual exceeds the noise (χ² test at level ``alpha``),
2. it improves the fit beyond what its extra parameters buy by chance (nested F-test at
   level ``alpha``, and a lower AICc),
3. its parameter is significant (|value / standard error| ≥ ``min_t``) and physically
   plausible (inside its bounds, not pinned to a search limit), and
4. it has its own evidence where it needs some: split pairs for a lumped mass, an
   unexplained n = 1 mode in the cavity band for the air cavity.

The best adopted candidate (lowest AICc) is added, and a second one is tried on top when
the residual still exceeds the noise. "No effect needed" and "a residual remains that no
candidate explains" are normal outcomes, reported with the residual's pattern.

Noise: each mode's relative frequency uncertainty is its ``frequency_uncertainty_hz``
where the table has one, never below a stated floor (``noise_floor_pct``, default
0.1 %: the repeatability of an impact test's frequencies).

References
----------
Burnham & Anderson (2002), *Model Selection and Multimodel Inference* (AICc).
Seber & Wild (1989), *Nonlinear Regression*, §5.3 (extra-sum-of-squares F-test).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.special

from tiremodal_cli.tyre.effects import EFFECTS, get_effect
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.tyre.fit import DEFAULT_BOUNDS, FitOptions, FitResult, MeasuredMode, fit, modes_from_rows, predict_table
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.robust import RobustFit, robust_fit, with_sigma

__all__ = ["DiagnoseOptions", "Candidate", "Diagnosis", "residual_analysis", "diagnose", "PARAMETER_CANDIDATES",
           "cavity_band_hz", "report", "mode_table", "predictions"]

#: Nominal values that may be off: freed one at a time ("a parameter value is off").
PARAMETER_CANDIDATES = ("rhoA", "m_s", "m_w", "b")


@dataclass(frozen=True)
class DiagnoseOptions:
    """How to diagnose (fractions, not per cent, unless the name says so).

    free : parameters of the base fit (and of every candidate's refit)
    noise_floor_pct : floor of each mode's relative frequency uncertainty, %
    alpha : level of the residual χ² test and of the candidates' F-tests
    min_t : smallest |value / standard error| of an adopted effect's parameter
    max_effects : effects adopted on top of one another at most
    candidates : names of the candidates to try (default: every effect and parameter)
    seed, population, generations, tol : the evolutionary search of every fit
    search : "local" (default): the base fit by the evolutionary search, every refit on
        top of a fitted model by least squares from it, safeguarded by a short evolutionary search
        (:class:`tiremodal_cli.tyre.fit.FitOptions`); "global": the full search every time
    speed_of_sound : m/s, for the cavity band c / (2π r_c)
    cavity_radius : (lo, hi) fractions of the tread radius R the cavity's mean radius
        may take (default 0.4 … 1.0)
    rim : "clamped" or "free" when the test's rim channel showed it (``run``), else "from
        parameters"; a rim the data show clamped has no mass or fixture to fit (the
        candidates m_w and rim_fixture are not tried)
    """

    free: tuple[str, ...] = ("k_r1", "k_r2", "EI")
    noise_floor_pct: float = 0.1
    alpha: float = 0.01
    min_t: float = 3.0
    max_effects: int = 2
    candidates: tuple[str, ...] | None = None
    seed: int = 0
    population: int = 24
    generations: int = 120
    tol: float = 1e-6
    speed_of_sound: float = 343.0
    cavity_radius: tuple[float, float] = (0.4, 1.0)
    search: str = "local"
    rim: str = "from parameters"

    def check(self, base: TyreParameters) -> None:
        if self.rim not in ("clamped", "free", "from parameters"):
            raise ParameterError(f"rim={self.rim!r}; allowed: clamped, free, from parameters")
        if not 0 < self.noise_floor_pct < 100:
            raise ParameterError(f"noise_floor_pct={self.noise_floor_pct} must be in (0, 100) %")
        if not 0 < self.alpha < 0.5:
            raise ParameterError(f"alpha={self.alpha} must be in (0, 0.5)")
        if self.max_effects < 0:
            raise ParameterError(f"max_effects={self.max_effects} must be ≥ 0")
        lo, hi = self.cavity_radius
        if not 0 < lo < hi:
            raise ParameterError(f"cavity_radius={self.cavity_radius} must be 0 < lo < hi (fractions of R)")
        known = set(EFFECTS) | set(PARAMETER_CANDIDATES)
        for c in self.candidates or ():
            if c not in known:
                raise ParameterError(f"unknown candidate {c!r}; allowed: {', '.join(sorted(known))}")


@dataclass(frozen=True)
class Candidate:
    """One candidate tried on top of a model, with its score and verdict.

    name, kind : effect name or parameter; "structural", "coupling", "acoustic" or "parameter"
    round : 1 for the first effect, 2 for one on top of it
    parameters : {name: {"value", "std_error", "t"}} its fitted parameters
    rms_error_pct, aicc, delta_aicc : the refit's RMS error and AICc, and AICc − the current model's
    f_p_value : nested F-test p-value against the current model
    adopted : bool ; reason : why adopted or rejected
    fit : the refit (None when it had no evidence to fit)
    """

    name: str
    kind: str
    title: str
    round: int
    parameters: dict
    rms_error_pct: float | None
    aicc: float | None
    delta_aicc: float | None
    f_p_value: float | None
    adopted: bool
    reason: str
    signature: str
    fit: FitResult | None = field(default=None, repr=False)
    cavity_mode: dict | None = None
    #: the candidate's robust fit of every mode, the modes it was judged on (those either
    #: model keeps), the current model's set-aside modes it brings back, its search bounds
    robust: RobustFit | None = field(default=None, repr=False)
    data: tuple = field(default=(), repr=False)
    brought_back: tuple = ()
    bounds: dict = field(default_factory=dict, repr=False)

    @property
    def passes(self) -> bool:
        """Every test passed (adoptable)."""
        return self.reason == "passes"


@dataclass(frozen=True)
class Diagnosis:
    """What :func:`diagnose` found (see :func:`tiremodal_cli.cli.diagnose.report` for its JSON)."""

    base: FitResult
    augmented: FitResult
    adopted: tuple[str, ...]
    candidates: tuple[Candidate, ...]
    residual_before: dict
    residual_after: dict
    unexplained: tuple[dict, ...]
    cavity_modes: tuple[dict, ...]
    relabelled: tuple[dict, ...]
    skipped_rows: tuple[dict, ...]
    verdict: str
    options: DiagnoseOptions
    base_robust: RobustFit | None = None
    augmented_robust: RobustFit | None = None


def cavity_band_hz(R: float, opt: DiagnoseOptions) -> tuple[float, float]:
    """Frequencies c / (2π r_c) of a cavity whose mean radius is ``cavity_radius`` × R."""
    lo, hi = opt.cavity_radius
    return opt.speed_of_sound / (2 * np.pi * hi * R), opt.speed_of_sound / (2 * np.pi * lo * R)


def _with_sigma(modes, opt) -> list[MeasuredMode]:
    return with_sigma(modes, opt.noise_floor_pct)


def _sigma_rel(modes) -> np.ndarray:
    return np.array([m.uncertainty_hz / m.frequency_hz for m in modes])


def residual_analysis(rf: RobustFit, opt: DiagnoseOptions, *, n_extra: int = 0) -> dict:
    """The residual of a robust fit against the noise, and its pattern.

    Returns a dict: per kept mode ``z`` (error / σ), ``chi2``, ``dof``, ``p_value`` of the
    kept modes, ``set_aside`` (the modes the fit set aside, each with its reason) and
    ``exceeds_noise``: the χ² test at level ``alpha`` fails, or a mode was set aside (an
    outlier at the same level); and ``pattern``: per branch the trend
    of the error with n (slope %/order and its t), the number of sign changes along n,
    isolated outliers (|z| > 3 and > 4 robust deviations from the branch's median), split
    pairs (one (n, branch) measured twice), and a list of plain-language ``findings``.
    """
    res, modes = rf.fit, list(rf.kept)
    err = np.array([m["error_pct"] for m in res.modes])
    sig = 100 * _sigma_rel(modes)
    z = err / sig
    k = len(res.free)
    dof = max(len(modes) - k, 1)
    chi2 = float(np.sum(z**2))
    p = float(scipy.special.chdtrc(dof, chi2))  # χ² survival function (scipy.stats costs 0.4 s to import)
    ns = np.array([m.n for m in modes])
    br = np.array([m.branch for m in modes])
    pattern = {"branches": {}, "outliers": [], "split_pairs": [], "findings": []}
    for b in ("same", "opposite"):
        sel = np.flatnonzero(br == b)
        if sel.size == 0:
            continue
        order = sel[np.argsort(ns[sel], kind="stable")]
        e = err[order]
        signs = np.sign(e[np.abs(e) > 1e-12])
        entry = {"modes": int(sel.size), "mean_error_pct": float(e.mean()),
                 "sign_changes": int(np.sum(signs[1:] != signs[:-1])) if signs.size > 1 else 0}
        if np.unique(ns[order]).size >= 3:
            x = ns[order].astype(float)
            A = np.column_stack([np.ones_like(x), x])
            coef, *_ = np.linalg.lstsq(A, e, rcond=None)
            r = e - A @ coef
            s2 = max(float(r @ r) / max(x.size - 2, 1), float(np.mean(sig[order] ** 2)) / 4)
            se = math.sqrt(s2 / float(np.sum((x - x.mean()) ** 2)))
            entry.update(slope_pct_per_order=float(coef[1]), slope_t=float(coef[1] / se))
        pattern["branches"][b] = entry
        med = np.median(e)
        mad = 1.4826 * np.median(np.abs(e - med)) if e.size >= 4 else np.inf
        for i in order:
            if abs(z[i]) > 3 and abs(err[i] - med) > 4 * max(mad, 1e-9):
                pattern["outliers"].append({"n": int(ns[i]), "branch": b, "error_pct": float(err[i]),
                                            "z": float(z[i])})
    pairs = {}
    for m in modes:
        if m.member:
            pairs.setdefault((m.n, m.branch), []).append(m.frequency_hz)
    pattern["split_pairs"] = [{"n": n, "branch": b, "frequencies_hz": sorted(f),
                               "splitting_pct": float(100 * (max(f) - min(f)) / np.mean(f))}
                              for (n, b), f in sorted(pairs.items())]
    pattern["findings"] = _findings(pattern, chi2, dof, p, opt, n_extra, rf.set_aside)
    return {"modes": [{**m, "sigma_pct": float(s), "z": float(zz)} for m, s, zz in zip(res.modes, sig, z)],
            "chi2": chi2, "dof": dof, "p_value": p, "exceeds_noise": bool(p < opt.alpha or rf.set_aside),
            "set_aside": [a.to_dict() for a in rf.set_aside], "z_crit": rf.z_crit,
            "rms_error_pct": res.rms_error_pct, "max_error_pct": res.max_error_pct,
            "noise_floor_pct": opt.noise_floor_pct, "pattern": pattern}


def _findings(pattern, chi2, dof, p, opt, n_extra, set_aside=()) -> list[str]:
    out = []
    if p < opt.alpha:
        out.append(f"the residual exceeds the noise: χ² = {chi2:.1f} on {dof} degrees of freedom (p = {p:.2g})")
    else:
        out.append(f"the residual is at the level of the noise: χ² = {chi2:.1f} on {dof} degrees of freedom "
                   f"(p = {p:.2g})")
    if set_aside:
        out.append(f"{len(set_aside)} mode(s) the model cannot represent, set aside: "
                   + ", ".join(f"n = {a.mode.n} {a.mode.branch} at {a.mode.frequency_hz:.1f} Hz"
                               + (f" ({a.error_pct:+.1f} %)" if np.isfinite(a.error_pct) else " (no such model mode)")
                               for a in set_aside))
    for b, e in pattern["branches"].items():
        t = e.get("slope_t")
        if t is not None and abs(t) >= 3:
            word = "over" if e["slope_pct_per_order"] > 0 else "under"
            out.append(f"{b} branch {word}-predicted increasingly with n ({e['slope_pct_per_order']:+.3f} %/order, "
                       f"t = {t:.1f})")
        if e["sign_changes"] >= 2 and e["modes"] >= 4:
            out.append(f"{b} branch error changes sign {e['sign_changes']} times along n")
    for o in pattern["outliers"]:
        out.append(f"isolated outlier: n = {o['n']} {o['branch']} ({o['error_pct']:+.2f} %, z = {o['z']:.1f})")
    if pattern["split_pairs"]:
        out.append(f"{len(pattern['split_pairs'])} split pair(s): "
                   + ", ".join(f"n = {s['n']} {s['branch']} ({s['splitting_pct']:.2f} %)" for s in pattern["split_pairs"]))
    if n_extra:
        out.append(f"{n_extra} measured mode(s) fit no structural (n, branch)")
    return out


def _aicc(rss: float, n: int, k: int) -> float:
    rss = max(rss, 1e-300)
    corr = 2 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else np.inf
    return n * math.log(rss / n) + 2 * k + corr


def _rss(res: FitResult, modes) -> float:
    """Σ (error / σ)² over ``modes`` (the first len(modes) rows of the fit's table)."""
    e = np.array([m["error_pct"] for m in res.modes[:len(modes)]]) / 100 / _sigma_rel(modes)
    return float(e @ e)


def _f_test(rss0, k0, rss1, k1, n) -> float:
    dk, dof1 = k1 - k0, n - k1
    if dk <= 0 or dof1 <= 0:
        return 1.0
    if rss1 <= 0:
        return 0.0
    F = max((rss0 - rss1) / dk, 0.0) / (rss1 / dof1)
    return float(scipy.special.fdtrc(dk, dof1, F))  # F survival function


def _start(current: FitResult) -> dict:
    """The current optimum as a start of the next search (DE's x0)."""
    out = {k: float(getattr(current.parameters, k)) for k in ("k_r1", "k_r2", "EI", "rhoA", "m_s", "b")}
    if current.parameters.m_w is not None:
        out["m_w"] = float(current.parameters.m_w)
    for e, vals in current.effects.items():
        out.update({f"{e}.{k}": float(v) for k, v in vals.items()})
    return out


def _fit_opts(opt: DiagnoseOptions, **kw) -> FitOptions:
    # refits from the current model (a start) search locally with a short global safeguard
    # unless the options ask for the full search every time
    search = opt.search if kw.get("start") else "global"
    return FitOptions(free=kw.pop("free", opt.free), seed=opt.seed, population=opt.population, weights="uncertainty",
                      generations=opt.generations, tol=opt.tol, error_floor=opt.noise_floor_pct / 100,
                      search=search, **kw)


def _effect_spec(name, fixed_effects):
    eff = get_effect(name)
    fitted = eff.fitted_parameters()
    fixed = {p.name: eff.diagnose_fixed.get(p.name, p.default) for p in eff.parameters if p not in fitted}
    effects = {k: dict(v) for k, v in fixed_effects.items()}
    effects[name] = fixed
    return eff, fitted, effects


def _param_table(res: FitResult, names) -> dict:
    out = {}
    for nm in names:
        i = res.free.index(nm)
        v, se = float(res.values[i]), float(res.std_errors[i])
        out[nm] = {"value": v, "std_error": se, "t": float(v / se) if se > 0 else float("inf")}
    return out


def _judge(cand_fit, current, names, modes, opt, bounds, n_tried, evidence_ok=True, evidence_why="",
           extra_point=None):
    """Score a refit against the current model; return (fields, reason or None when it passes).

    ``extra_point`` = (z_current, z_candidate): one more measured point (a cavity mode)
    with its normalised error under either model.
    """
    n_modes = len(modes)
    k0, k1 = len(current.free), len(cand_fit.free)
    rss0, rss1 = _rss(current, modes), _rss(cand_fit, modes)
    if extra_point is not None:
        rss0, rss1, n_modes = rss0 + extra_point[0] ** 2, rss1 + extra_point[1] ** 2, n_modes + 1
    a0, a1 = _aicc(rss0, n_modes, k0), _aicc(rss1, n_modes, k1)
    p = _f_test(rss0, k0, rss1, k1, n_modes)
    params = _param_table(cand_fit, names)
    fields = dict(parameters=params, rms_error_pct=cand_fit.rms_error_pct, aicc=a1, delta_aicc=a1 - a0,
                  f_p_value=p, fit=cand_fit)
    if not evidence_ok:
        return fields, evidence_why
    level = opt.alpha / max(n_tried, 1)  # Bonferroni: the best of n_tried candidates is not chance
    if not p < level:
        return fields, f"no better than an extra parameter buys by chance (F-test p = {p:.2g} ≥ {level:.2g})"
    if not a1 < a0 - 2:
        return fields, f"AICc not lower by more than 2 ({a1 - a0:+.1f})"
    # a parameter resting on its physical limit (a fraction at 1, a belt stiff beyond what the
    # modes can see) is determined by that limit; the others must be significant — at least
    # one of them, the F-test above being the joint test of them all
    on_limit = [nm for nm in names if (*bounds[nm], False)[2] and params[nm]["value"] >= bounds[nm][1] * 0.999]
    free_t = [abs(params[nm]["t"]) for nm in names if nm not in on_limit]
    if not on_limit and max(free_t) < opt.min_t:
        return fields, f"its parameter is not significant (|t| = {max(free_t):.1f} < {opt.min_t})"
    for nm in names:
        lo, hi, hard = (*bounds[nm], False)[:3]
        v = params[nm]["value"]
        # a lower bound of 0 is reached as a vanishing value (the search is in log parameters)
        if v <= max(lo * 1.001, 1e-6 * hi) or (v >= hi * 0.999 and not hard):
            return fields, f"{nm} = {v:.4g} sits at a limit of its search range [{lo:.3g}, {hi:.3g}]"
    return fields, None


def _unexplained_rows(skipped, rows) -> list[dict]:
    """Rows that fit no structural (n, branch): far duplicates, out of order, no n/branch,
    an uncertain order. Rows that are not normal modes (low MPC) are not counted."""
    out = []
    for s in skipped:
        reason = s.get("reason", "")
        if "frequency_hz" not in s or "mpc" in reason:
            continue
        row = rows[s["row"] - 1] if 0 < s.get("row", 0) <= len(rows) else {}
        out.append({"frequency_hz": float(s["frequency_hz"]), "n": s.get("n"), "branch": s.get("branch"),
                    "row": s.get("row"), "reason": reason,
                    "significance": _num(row.get("significance")), "n_spatial": _num(row.get("n_spatial"))})
    return out


def _num(v):
    try:
        return None if v is None or v == "" else float(v)
    except (TypeError, ValueError):
        return None


def usable_modes(rows, opt: DiagnoseOptions, *, min_confidence: float = 0.5, source: str = "", on_empty=None):
    """The modes a diagnosis fits (split pairs as two members, each with its σ_f), the rows
    left out, and those of them that fit no structural (n, branch) (the evidence of an air
    cavity or an alias). No usable mode: DataFormatError (its message from ``on_empty()``
    when given)."""
    modes, skipped = modes_from_rows(rows, min_confidence=min_confidence, split_pairs="members", source=source)
    if not modes:
        raise DataFormatError(on_empty() if on_empty else
                              "no usable modes: a diagnosis needs modes with n and branch (same/opposite)")
    return _with_sigma(modes, opt), skipped, _unexplained_rows(skipped, rows)


def base_fit(modes, base_params: TyreParameters, opt: DiagnoseOptions) -> RobustFit:
    """The base model's robust fit (:func:`tiremodal_cli.tyre.robust.robust_fit`): the one base fit
    of a run, made by ``identify`` and handed to :func:`diagnose`."""
    opt.check(base_params)
    return robust_fit(modes, base_params, _fit_opts(opt), alpha=opt.alpha)


def diagnose(rows, base_params: TyreParameters = TyreParameters(), opt: DiagnoseOptions = DiagnoseOptions(),
             *, n_points: int | None = None, min_confidence: float = 0.5, progress=None,
             base: RobustFit | None = None) -> Diagnosis:
    """Diagnose what a fitted model lacks, from a modal table.

    Parameters
    ----------
    rows : list of dict
        Modal-table rows (``lsce`` file/CSV, or a table such as the paper's Table A1):
        ``frequency_hz``, ``n``, ``branch``, optionally ``pair``, ``n_confidence``,
        ``mpc``, ``significance``, ``frequency_uncertainty_hz``.
    base_params : TyreParameters — the nominal values (the free ones are fitted)
    opt : DiagnoseOptions
    n_points : number of impact points of the test (for the spatial-alias check); None
        for a table without geometry
    min_confidence : rows with a lower ``n_confidence`` fit no (n, branch)
    progress : callable(done, total), optional
    base : the base model's robust fit of these rows (:func:`base_fit`, as ``run``'s
        identify stage made it); None: fitted here

    Returns
    -------
    Diagnosis
    """
    opt.check(base_params)
    modes, skipped, extra = usable_modes(rows, opt, min_confidence=min_confidence)
    if base is None:
        base = base_fit(modes, base_params, opt)
    names = [c for c in (opt.candidates or tuple(EFFECTS) + PARAMETER_CANDIDATES)
             if not (c in PARAMETER_CANDIDATES and c in opt.free)]
    total = 1 + len(names) * max(opt.max_effects, 1)
    ticks = _Ticker(progress, total)
    ticks()
    relabelled = []
    nominal = {k: float(getattr(base_params, k)) for k in ("k_r1", "k_r2", "EI", "rhoA", "m_s", "b")}
    current = _recheck(base, n_points, opt, relabelled)
    adopted, tried, cavity_modes = [], [], []
    residual_before = residual_analysis(base, opt, n_extra=len(extra))
    residual_now = residual_analysis(current, opt, n_extra=len(extra)) if current is not base else residual_before
    for rnd in range(1, opt.max_effects + 1):
        pending = [n for n in names if n not in adopted]
        round_cands = []
        for name in pending:
            round_cands.append(_try(name, rnd, current, extra, opt, n_tried=len(pending), nominal=nominal))
            ticks()
        best, judged = _choose(round_cands, current, opt, len(pending), needed=residual_now["exceeds_noise"])
        tried.extend(judged)
        if best is None:
            break
        adopted.append(best.name)
        current = best.robust
        if best.cavity_mode is not None:
            # the cavity mode was the evidence; from here on the structure is fitted alone,
            # the cavity fixed at its fitted values
            cavity_modes.append(best.cavity_mode)
            struct = [m for m in current.modes if m.branch != "cavity"]
            keep = tuple(f for f in current.fit.free if not f.startswith(f"{best.name}."))
            current = _refit_robust(dataclasses.replace(current.fit, free=keep), struct, opt)
        current = _recheck(current, n_points, opt, relabelled)
        residual_now = residual_analysis(current, opt, n_extra=len(extra) - len(cavity_modes))
        if not residual_now["exceeds_noise"]:
            break
    ticks.finish()
    explained = {round(c["frequency_hz"], 6) for c in cavity_modes}
    unexplained = tuple(u for u in extra if round(u["frequency_hz"], 6) not in explained)
    verdict = _verdict(adopted, tried, residual_before, residual_now, unexplained)
    return Diagnosis(base=base.fit, augmented=current.fit, adopted=tuple(adopted), candidates=tuple(tried),
                     residual_before=residual_before, residual_after=residual_now, unexplained=unexplained,
                     cavity_modes=tuple(cavity_modes), relabelled=tuple(relabelled), skipped_rows=tuple(skipped),
                     verdict=verdict, options=opt, base_robust=base, augmented_robust=current)


class _Ticker:
    """Progress of the candidate search: ``progress(done, total)`` once per fit."""

    def __init__(self, progress, total):
        self.progress, self.total, self.done = progress, total, 0

    def __call__(self):
        self.done += 1
        if self.progress:
            self.progress(min(self.done, self.total), self.total)

    def finish(self):
        if self.progress:
            self.progress(self.total, self.total)


def _choose(cands, current: RobustFit, opt, n_tried, *, needed: bool):
    """The round's verdicts: the passing candidate with the most evidence over the current
    model (lowest ΔAICc, each on the modes it was judged on) adopted, the others with the
    reason they were not.

    Each candidate is judged on the modes either it or the current model keeps; a candidate
    that brings back a set-aside mode is judged on one mode more. Its ΔAICc is the evidence
    it has against the current model on its own data, and that is what is compared."""
    if not needed:
        return None, [dataclasses.replace(c, reason="not needed: the residual is at the level of the noise"
                                          + ("" if c.passes else f"; besides, {c.reason}")) for c in cands]
    passing = [c for c in cands if c.passes]
    best = min(passing, key=lambda c: c.delta_aicc) if passing else None
    runner = min((c for c in cands if c is not best and c.delta_aicc is not None), key=lambda c: c.delta_aicc,
                 default=None)
    out = []
    for c in cands:
        if c is best:
            out.append(dataclasses.replace(best, adopted=True, reason=_adopt_reason(best, runner)))
        elif c.passes:
            out.append(dataclasses.replace(c, reason=f"passes, but {best.name} explains more "
                                                     f"(ΔAICc {c.delta_aicc - best.delta_aicc:+.1f} above it)"))
        else:
            out.append(c)
    return best, out


def _ordered_union(first, *others):
    seen, out = set(), []
    for group in (first, *others):
        for m in group:
            if m not in seen:
                seen.add(m)
                out.append(m)
    return tuple(out)


def _recheck(rf: RobustFit, n_points, opt, relabelled: list) -> RobustFit:
    """Set-aside modes that are a spatial alias of another order, relabelled and fitted again."""
    new_modes, changed = _misreads(rf, n_points, opt)
    if not changed:
        return rf
    relabelled.extend(changed)
    return _refit_robust(rf.fit, new_modes, opt)


def _misreads(rf: RobustFit, n_points, opt) -> tuple[list, list]:
    """Set-aside modes that are a spatial alias of another order, read under the current model.

    A grid of N points sees order n also as N − n, N + n, …: a set-aside mode is relabelled
    to the alias (either branch) the current model puts within 3 σ of it, if that
    (n, branch) is not measured already. Returns every mode (relabelled) and what was
    relabelled. Without N (a CSV table) nothing is relabelled.
    """
    modes = list(rf.modes)
    if not n_points or not rf.set_aside:
        return modes, []
    from tiremodal_cli.tyre.fit import model_frequencies

    current = rf.fit
    taken = {(m.n, m.branch) for m in modes}
    out, changed = list(modes), []
    n_max = max(x.n for x in modes) + n_points
    for a in rf.set_aside:
        m = a.mode
        i = modes.index(m)
        sig = m.uncertainty_hz / m.frequency_hz
        aliases = sorted({k for j in range(0, n_max // n_points + 2) for k in (j * n_points - m.n, j * n_points + m.n)
                          if 0 <= k <= n_max and k != m.n})
        best = None
        for k in aliases:
            for b in ("same", "opposite"):
                if (k, b) in taken:
                    continue
                f = model_frequencies(current.parameters, [k], [b], current.effects or None)[0]
                e = abs(f / m.frequency_hz - 1)
                if np.isfinite(f) and e <= 3 * sig and (best is None or e < best[2]):
                    best = (k, b, e, f)
        if best is not None:
            k, b, _, f = best
            out[i] = dataclasses.replace(m, n=k, branch=b, member=None,
                                         source=f"{m.source} (read as n = {m.n} {m.branch}: a spatial alias)")
            taken.add((k, b))
            changed.append({"frequency_hz": m.frequency_hz, "read_as": {"n": m.n, "branch": m.branch},
                            "relabelled": {"n": k, "branch": b}, "model_hz": float(f),
                            "reason": f"spatial alias on {n_points} points: the model puts n = {k} {b} at "
                                      f"{f:.2f} Hz"})
    # a split pair that lost a member is one mode again
    count = {}
    for m in out:
        if m.member:
            count[(m.n, m.branch)] = count.get((m.n, m.branch), 0) + 1
    out = [dataclasses.replace(m, member=None) if m.member and count[(m.n, m.branch)] < 2 else m for m in out]
    return out, changed


def _adopt_reason(c: Candidate, runner: Candidate | None) -> str:
    what = "a parameter value is off" if c.kind == "parameter" else "missing physics"
    s = (f"adopted ({what}): RMS {c.rms_error_pct:.3f} %, ΔAICc {c.delta_aicc:+.1f}, F-test p = {c.f_p_value:.2g}, "
         + ", ".join(f"{k} = {v['value']:.4g} ± {v['std_error']:.2g}" for k, v in c.parameters.items()))
    if c.brought_back:
        s += "; brings back " + ", ".join(f"n = {b['n']} {b['branch']} at {b['frequency_hz']:.1f} Hz"
                                          for b in c.brought_back)
    if runner is not None:
        s += f"; runner-up {runner.name} (ΔAICc {runner.delta_aicc:+.1f})"
    return s


def _try(name, rnd, current: RobustFit, extra, opt, n_tried, nominal=None) -> Candidate:
    """Refit every mode (the set-aside ones too) with one more candidate on top of the
    current model, robustly; judge it on the modes either model keeps."""
    cur = current.fit
    fixed_effects = dict(cur.effects)
    free = tuple(cur.free)
    struct_free = tuple(f for f in free if "." not in f)
    prev_eff_free = tuple(tuple(f.split(".", 1)) for f in free if "." in f)
    start = cur.parameters
    if name in ("m_w", "rim_fixture") and opt.rim == "clamped":
        return Candidate(name=name, parameters={}, rms_error_pct=None, aicc=None, delta_aicc=None, f_p_value=None,
                         adopted=False, kind="parameter" if name == "m_w" else "structural",
                         title=f"nominal {name} is off" if name == "m_w" else get_effect(name).title, round=rnd,
                         signature="", reason="no evidence: the rim channel recorded no signal (a clamped rim)")
    if name in PARAMETER_CANDIDATES:
        lo, hi = DEFAULT_BOUNDS[name]
        fo = dataclasses.replace(_fit_opts(opt, free=struct_free + (name,), effects=fixed_effects,
                                           effect_free=prev_eff_free, start=_start(cur)), bounds={})
        p0 = start if name != "m_w" or start.m_w is not None else start.replace(m_w=1000.0)
        return _judged(name, dict(kind="parameter", title=f"nominal {name} is off", round=rnd,
                                  signature="a parameter value is off, not missing physics"),
                       current, p0, fo, [name], {name: (lo, hi)}, opt, n_tried)
    eff, fitted, effects = _effect_spec(name, fixed_effects)
    efree = prev_eff_free + tuple((name, p.name) for p in fitted)
    bounds = {f"{name}.{p.name}": (p.lower, p.upper, p.upper_is_physical) for p in fitted}
    pnames = [f"{name}.{p.name}" for p in fitted]
    common = dict(kind=eff.kind, title=eff.title, round=rnd, signature=eff.signature)
    if eff.kind == "coupling" and not any(m.member for m in current.modes):
        return Candidate(name=name, parameters={}, rms_error_pct=None, aicc=None, delta_aicc=None,
                         f_p_value=None, adopted=False, reason="no evidence: no split pair in the modal table",
                         **common)
    if eff.kind == "acoustic":
        return _try_cavity(name, _CavitySpec(effects, efree, bounds, pnames, struct_free), current, extra, opt,
                           n_tried, common)
    if eff.extra.get("needs_free_rim") and start.m_w is None:
        return Candidate(name=name, parameters={}, rms_error_pct=None, aicc=None, delta_aicc=None,
                         f_p_value=None, adopted=False,
                         reason="no evidence: the rim is clamped (its channel recorded no signal, or the "
                                "parameters say so)", **common)
    also = tuple(a for a in eff.extra.get("also_free", ()) if a not in struct_free)
    if also:  # the effect's own parameter and the seed model's that it acts with (the rim mass)
        struct_free = struct_free + also
        pnames = pnames + list(also)
        bounds = {**bounds, **{a: DEFAULT_BOUNDS[a] for a in also}}
    own = {f"{name}.{p.name}": p.default for p in fitted}
    fo = _fit_opts(opt, free=struct_free, effects=effects, effect_free=efree, start={**_start(cur), **own},
                   extra_starts=({**_start(cur), **(nominal or {}), **own},) if nominal else ())
    return _judged(name, common, current, start, fo, pnames, bounds, opt, n_tried)


def _judged(name, common, current: RobustFit, p0, fo, pnames, bounds, opt, n_tried) -> Candidate:
    """A candidate judged against the current model on the modes the current model keeps
    plus the set-aside modes the candidate brings back.

    Every mode enters the candidate's fit; those the current model keeps stay in it (the
    candidate must carry what the current model carries), and a set-aside mode comes back
    only when the candidate holds it inside the current model's outlier limit with all of
    them in the fit — a candidate cannot buy a mode back by bending the others."""
    kept = set(current.kept)
    rc = robust_fit(_testimony(current), p0, fo, alpha=opt.alpha, scale=current.scale, protect=lambda m: m in kept)
    data = rc.kept
    cur = current.fit if set(data) == kept else _aligned(_refit_on(current.fit, data, opt), data)
    fields, why = _judge(rc.fit, cur, pnames, list(data), opt, bounds, n_tried)
    back = tuple(a.to_dict() for a in current.set_aside if a.mode in set(rc.kept))
    return Candidate(name=name, reason=why or "passes", adopted=False, robust=rc, data=tuple(data),
                     brought_back=back, bounds=bounds, **fields, **common)


def _testimony(current: RobustFit) -> list:
    """The modes a candidate is fitted to: those the current model keeps and the set-aside
    ones whose order was measured — a set-aside mode above the spatial Nyquist order has its
    n from the model's own dispersion, not from the points, and cannot testify against the
    model (it may still be relabelled as an alias, :func:`_misreads`)."""
    return list(current.kept) + [a.mode for a in current.set_aside if not a.mode.aliased]


def _aligned(res: FitResult, data) -> FitResult:
    """``res`` with its mode table in the order of ``data`` (fits of the same modes in
    another order)."""
    key = lambda n, b, f, mem: (n, b, round(f, 9), mem)  # noqa: E731
    table = {key(m["n"], m["branch"], m["measured_hz"], m.get("member")): m for m in res.modes}
    rows = [table[key(m.n, m.branch, m.frequency_hz, m.member)] for m in data]
    return dataclasses.replace(res, modes=rows)


def _refit_on(res: FitResult, modes, opt) -> FitResult:
    """The model of ``res`` (same free parameters and effects) fitted to ``modes``, from ``res``."""
    o = res.options
    fo = _fit_opts(opt, free=tuple(f for f in res.free if "." not in f), effects=res.effects,
                   effect_free=tuple(tuple(f.split(".", 1)) for f in res.free if "." in f), start=_start(res))
    fo = dataclasses.replace(fo, bounds=o.bounds, search="polish")
    return fit(list(modes), res.parameters, fo)


def _refit_robust(res: FitResult, modes, opt) -> RobustFit:
    """The model of ``res`` fitted robustly to ``modes`` (relabelled modes, the structure
    without its cavity mode)."""
    fo = _fit_opts(opt, free=tuple(f for f in res.free if "." not in f), effects=res.effects,
                   effect_free=tuple(tuple(f.split(".", 1)) for f in res.free if "." in f), start=_start(res))
    return robust_fit(list(modes), res.parameters, dataclasses.replace(fo, bounds=res.options.bounds),
                      alpha=opt.alpha)


@dataclass(frozen=True)
class _CavitySpec:
    effects: dict
    efree: tuple
    bounds: dict
    pnames: list
    struct_free: tuple


def _modes_for_cavity(modes, cav, opt):
    """The structural modes once ``cav`` is the cavity mode: drop it where it was kept as
    n = 1 and let the row it had displaced (an n = 1 duplicate) take its place."""
    f_c = cav["frequency_hz"]
    kept = [m for m in modes if not (m.n == 1 and m.branch != "cavity" and abs(m.frequency_hz - f_c) <= 1e-9 * f_c)]
    if len(kept) == len(modes):
        return kept, None
    b = next(m.branch for m in modes if m.n == 1 and abs(m.frequency_hz - f_c) <= 1e-9 * f_c)
    alt = cav.get("displaced")
    if alt is not None:
        kept.append(MeasuredMode(1, b, alt, source="n = 1 row displaced by the cavity mode",
                                 uncertainty_hz=alt * opt.noise_floor_pct / 100))
    return kept, b


def _cavity_evidence(current: RobustFit, extra, opt) -> list[dict]:
    """Modes that may be the cavity's: an n = 1 pattern in the cavity band that fits no
    structural (n, branch) — or the n = 1 row kept, when the unexplained one is the structure's."""
    lo, hi = cavity_band_hz(current.fit.parameters.R, opt)
    cands = []
    for u in extra:
        n_ok = u.get("n") == 1 or (u.get("n_spatial") is not None and int(u["n_spatial"]) == 1)
        if n_ok and lo <= u["frequency_hz"] <= hi:
            cands.append({"frequency_hz": u["frequency_hz"], "displaced": None, "row": u.get("row")})
            for m in current.modes:
                if m.n == 1 and m.branch == u.get("branch") and lo <= m.frequency_hz <= hi:
                    cands.append({"frequency_hz": m.frequency_hz, "displaced": u["frequency_hz"], "row": None})
    return cands


def _try_cavity(name, spec: _CavitySpec, current: RobustFit, extra, opt, n_tried, common) -> Candidate:
    """The air cavity: a mode with an n = 1 tread pattern in the cavity band that fits no
    structural (n, branch) (or that displaced the structural n = 1 from its label)."""
    lo, hi = cavity_band_hz(current.fit.parameters.R, opt)
    cands = _cavity_evidence(current, extra, opt)
    if not cands:
        return Candidate(name=name, parameters={}, rms_error_pct=None, aicc=None, delta_aicc=None, f_p_value=None,
                         adopted=False,
                         reason=f"no evidence: no unexplained n = 1 mode in the cavity band {lo:.0f}–{hi:.0f} Hz",
                         **common)
    cur = current.fit
    best = None
    for cav in cands:
        struct, _ = _modes_for_cavity(_testimony(current), cav, opt)
        cav_mode = MeasuredMode(1, "cavity", cav["frequency_hz"], source="cavity mode",
                                uncertainty_hz=cav["frequency_hz"] * opt.noise_floor_pct / 100)
        eff_start = {**spec.effects, name: {**spec.effects[name],
                                            "f_cavity_hz": float(np.clip(cav["frequency_hz"], 50.0, 400.0))}}
        fo = _fit_opts(opt, free=spec.struct_free, effects=eff_start, effect_free=spec.efree,
                       start={**_start(cur), **{f"{name}.{k}": v for k, v in eff_start[name].items()}})
        kept = set(current.kept)
        rc = robust_fit(struct + [cav_mode], cur.parameters, fo, alpha=opt.alpha,
                        protect=lambda m: m.branch == "cavity" or m in kept, scale=current.scale)
        kept_struct = [m for m in rc.kept if m.branch != "cavity"]
        score = _rss(_restrict(_aligned(rc.fit, rc.kept), len(kept_struct)), kept_struct) - len(kept_struct)
        if best is None or score < best[0]:
            best = (score, cav, rc, struct, cav_mode)
    _, cav, rc, struct, cav_mode = best
    kept_struct = [m for m in rc.kept if m.branch != "cavity"]
    # judged on the structural modes either model keeps, plus the cavity mode as one more point
    data = _ordered_union([m for m in current.kept if m in set(struct)], kept_struct)
    cand_all = _refit_on(rc.fit, list(data) + [cav_mode], opt)
    cand_all = _aligned(cand_all, list(data) + [cav_mode])
    cav_err = cand_all.modes[-1]
    ok = abs(cav_err["error_pct"]) <= 3 * opt.noise_floor_pct
    cur_on = _aligned(_refit_on(cur, data, opt), data)
    from tiremodal_cli.tyre.fit import model_frequencies

    f_c = cav["frequency_hz"]
    near = model_frequencies(cur_on.parameters, [1, 1], ["same", "opposite"], cur_on.effects or None)
    e0 = float(np.nanmin(np.abs(near / f_c - 1))) / (opt.noise_floor_pct / 100)
    e1 = cav_err["error_pct"] / opt.noise_floor_pct
    fields, why = _judge(_restrict(cand_all, len(data)), cur_on, spec.pnames, list(data), opt, spec.bounds, n_tried,
                         evidence_ok=ok,
                         evidence_why=f"the model's cavity mode misses the measured one by {cav_err['error_pct']:+.2f} %",
                         extra_point=(e0, e1))
    fields["fit"] = cand_all
    cavity_mode = {"frequency_hz": cav["frequency_hz"], "n": 1, "model_hz": cav_err["model_hz"],
                   "displaced": cav["displaced"], "band_hz": [lo, hi]}
    back = tuple(a.to_dict() for a in current.set_aside if a.mode in set(kept_struct))
    return Candidate(name=name, reason=why or "passes", adopted=False, cavity_mode=cavity_mode, robust=rc,
                     data=tuple(data), brought_back=back, bounds=spec.bounds, **fields, **common)


def _restrict(res: FitResult, k: int) -> FitResult:
    """The fit's structural modes only (the first ``k``): RMS and table recomputed."""
    modes = res.modes[:k]
    e = np.array([m["error_pct"] for m in modes])
    return dataclasses.replace(res, modes=modes, rms_error_pct=float(np.sqrt(np.mean(e**2))),
                               max_error_pct=float(np.max(np.abs(e))))


def _verdict(adopted, tried, before, after, unexplained) -> str:
    if not before["exceeds_noise"] and not adopted:
        v = ("no effect needed: the base model's residual is at the level of the noise "
             f"(RMS {before['rms_error_pct']:.3f} %, χ² p = {before['p_value']:.2g})")
    elif adopted:
        what = ", ".join(adopted)
        v = (f"adopted {what}: RMS error {before['rms_error_pct']:.3f} % → {after['rms_error_pct']:.3f} %, "
             f"max {before['max_error_pct']:.3f} % → {after['max_error_pct']:.3f} %")
        if after["exceeds_noise"]:
            v += ("; a residual remains that no candidate explains ("
                  + "; ".join(after["pattern"]["findings"][1:] or ["no clear pattern"]) + ")")
    else:
        v = ("a residual remains that no candidate explains: "
             + "; ".join(before["pattern"]["findings"]))
    tail = f"{len(unexplained)} measured mode(s) fit no structural (n, branch)"
    if unexplained and tail not in v:  # the pattern's findings may say it already
        v += f"; {tail}"
    return v


def predictions(diag: Diagnosis, n_max: int) -> dict:
    """Both models' frequencies of every (n, branch) up to ``n_max``, with 1σ."""
    base = predict_table(diag.base, n_max, measured=diag.base.modes)
    aug = predict_table(diag.augmented, n_max, measured=diag.augmented.modes)
    return {"base": base, "augmented": aug}


def mode_table(diag: Diagnosis) -> list[dict]:
    """Per measured mode: measured, base model, augmented model and both errors (%)."""
    aug = {(m["n"], m["branch"], round(m["measured_hz"], 9)): m for m in diag.augmented.modes}
    out = []
    for m in diag.base.modes:
        a = aug.get((m["n"], m["branch"], round(m["measured_hz"], 9)))
        out.append({"n": m["n"], "branch": m["branch"], **({"member": m["member"]} if "member" in m else {}),
                    "measured_hz": m["measured_hz"], "base_hz": m["model_hz"], "base_error_pct": m["error_pct"],
                    "augmented_hz": a["model_hz"] if a else None, "augmented_error_pct": a["error_pct"] if a else None})
    for c in diag.cavity_modes:
        out.append({"n": 1, "branch": "cavity", "measured_hz": c["frequency_hz"], "base_hz": None,
                    "base_error_pct": None, "augmented_hz": c["model_hz"],
                    "augmented_error_pct": 100 * (c["model_hz"] / c["frequency_hz"] - 1)})
    return out


def _fit_block(res) -> dict:
    return {"parameters": {n: {"value": float(v), "std_error": float(s)} for n, v, s in
                           zip(res.free, res.values, res.std_errors)},
            "all_parameters": res.parameters.to_dict(), "effects": res.effects,
            "undetermined": res.undetermined,
            "rms_error_pct": res.rms_error_pct, "max_error_pct": res.max_error_pct}


def _finite(obj):
    """Non-finite floats (an infinite t of a zero error bar, an undefined AICc) as None."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    if isinstance(obj, (float, np.floating)) and not np.isfinite(obj):
        return None
    return obj


def report(diag, n_max: int = 12) -> dict:
    """The diagnosis as JSON-ready data (keys documented in docs/diagnose.md)."""
    return _finite(_report(diag, n_max))


def _report(diag, n_max):
    cands = [{"name": c.name, "kind": c.kind, "title": c.title, "round": c.round,
              "score": c.delta_aicc, "aicc": c.aicc, "f_p_value": c.f_p_value,
              "rms_error_pct": c.rms_error_pct, "parameters": c.parameters, "adopted": c.adopted,
              "reason": c.reason, "signature": c.signature, "brings_back": list(c.brought_back)}
             for c in diag.candidates]
    return {
        "verdict": diag.verdict,
        "base": _fit_block(diag.base),
        "augmented": _fit_block(diag.augmented),
        "adopted_effects": list(diag.adopted),
        "parameter_off": [c.name for c in diag.candidates if c.adopted and c.kind == "parameter"],
        "candidates": cands,
        "modes": mode_table(diag),
        "unexplained_modes": [{"frequency_hz": u["frequency_hz"], "n": u.get("n"), "reason": u["reason"]}
                              for u in diag.unexplained],
        "cavity_modes": list(diag.cavity_modes),
        "relabelled_modes": list(diag.relabelled),
        "set_aside_before": list(diag.residual_before.get("set_aside", [])),
        "set_aside_after": list(diag.residual_after.get("set_aside", [])),
        "outlier_rule": {"z_crit_before": diag.residual_before.get("z_crit"),
                         "z_crit_after": diag.residual_after.get("z_crit"), "alpha": diag.options.alpha},
        "residual_before": {k: v for k, v in diag.residual_before.items() if k != "modes"},
        "residual_after": {k: v for k, v in diag.residual_after.items() if k != "modes"},
        "predictions": predictions(diag, n_max),
        "options": {"noise_floor_pct": diag.options.noise_floor_pct, "alpha": diag.options.alpha,
                    "min_t": diag.options.min_t, "max_effects": diag.options.max_effects,
                    "seed": diag.options.seed, "free": list(diag.options.free)},
    }
