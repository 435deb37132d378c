"""Refits of a model on a set of modes, and the judgement of a candidate against the current model."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.special

from tiremodal_cli.diagnose.options import DiagnoseOptions, fit_options, search_start
from tiremodal_cli.diagnose.statistics import aicc, f_test_p, weighted_rss
from tiremodal_cli.tyre.fit import fit
from tiremodal_cli.tyre.fit_types import FitResult
from tiremodal_cli.tyre.robust import RobustFit, robust_fit

__all__ = ["Trial", "Scoring", "judge", "joint_wald_p", "t_level", "testimony", "aligned", "refit_on", "refit_robust",
           "restrict"]


def _param_table(res: FitResult, names) -> dict:
    out = {}
    for nm in names:
        i = res.free.index(nm)
        v, se = float(res.values[i]), float(res.std_errors[i])
        out[nm] = {"value": v, "std_error": se, "t": float(v / se) if se > 0 else float("inf")}
    return out


@dataclass(frozen=True)
class Scoring:
    """What a candidate is judged by: its parameters' names and search bounds
    ({name: (lo, hi[, upper_is_physical])}), the options, and how many candidates the round
    tried (the Bonferroni factor)."""

    names: tuple[str, ...]
    bounds: dict
    opt: DiagnoseOptions
    n_tried: int
    #: parameters that may vanish without refusing the candidate: a coupling the
    #: frequencies cannot see, where the candidate has evidence of its own (the air
    #: cavity's γ when no n = 1 structural mode lies near the cavity's: its mode is the evidence)
    may_vanish: tuple[str, ...] = ()


@dataclass(frozen=True)
class Trial:
    """One round's trial of candidates on top of the current model.

    rnd : 1 for the first effect, 2 for one on top of it
    current : the current model's robust fit
    extra : modal-table rows that fit no structural (n, branch) (the cavity's evidence)
    opt : DiagnoseOptions
    n_tried : candidates tried in this round (the Bonferroni factor)
    nominal : the nominal stiffnesses and masses (a second start of an effect's search)
    """

    rnd: int
    current: RobustFit
    extra: tuple
    opt: DiagnoseOptions
    n_tried: int
    nominal: dict | None = None


def judge(cand_fit: FitResult, current: FitResult, modes, scoring: Scoring, *, missing_evidence: str | None = None,
          extra_point=None):
    """Score a refit against the current model on ``modes``; return (fields, reason or None
    when it passes).

    ``missing_evidence``: why the candidate lacks its own evidence (it fails with that
    reason, scored all the same). ``extra_point`` = (z_current, z_candidate): one more
    measured point (a cavity mode) with its normalised error under either model.
    """
    names, bounds, opt, n_tried = scoring.names, scoring.bounds, scoring.opt, scoring.n_tried
    n_modes = len(modes)
    k0, k1 = len(current.free), len(cand_fit.free)
    rss0, rss1 = weighted_rss(current, modes), weighted_rss(cand_fit, modes)
    if extra_point is not None:
        rss0, rss1, n_modes = rss0 + extra_point[0] ** 2, rss1 + extra_point[1] ** 2, n_modes + 1
    a0, a1 = aicc(rss0, n_modes, k0), aicc(rss1, n_modes, k1)
    p = f_test_p(rss0, k0, rss1, k1, n_modes)
    params = _param_table(cand_fit, names)
    fields = dict(parameters=params, rms_error_pct=cand_fit.rms_error_pct, aicc=a1, delta_aicc=a1 - a0,
                  f_p_value=p, fit=cand_fit)
    if missing_evidence is not None:
        return fields, missing_evidence
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
        # several parameters that vanish together (the effect's null) are tested together:
        # correlated, each |t| may be small while the pair is far from its null
        p_joint = joint_wald_p(cand_fit, [nm for nm in names if bounds[nm][0] == 0])
        if p_joint is None or not p_joint < t_level(opt.min_t):
            return fields, (f"its parameter is not significant (|t| = {max(free_t):.1f} < {opt.min_t}"
                            + ("" if p_joint is None else f"; jointly Wald p = {p_joint:.2g} ≥ "
                                                         f"{t_level(opt.min_t):.2g}") + ")")
    for nm in names:
        lo, hi, hard = (*bounds[nm], False)[:3]
        v = params[nm]["value"]
        # a lower bound of 0 is reached as a vanishing value (the search is in log parameters)
        vanishing = v <= max(lo * 1.001, 1e-6 * hi)
        if vanishing and nm in scoring.may_vanish:
            continue
        if vanishing or (v >= hi * 0.999 and not hard):
            return fields, f"{nm} = {v:.4g} sits at a limit of its search range [{lo:.3g}, {hi:.3g}]"
    return fields, None


def t_level(min_t: float) -> float:
    """The two-sided level of the rule |t| ≥ ``min_t`` for one parameter: 2 Φ(−min_t)
    (0.0027 for 3)."""
    return float(scipy.special.erfc(min_t / np.sqrt(2.0)))


def joint_wald_p(res: FitResult, names) -> float | None:
    """The Wald test that the parameters ``names`` of the fit ``res`` are all zero (their
    null: the model without the effect), or None for fewer than two.

    W = θᵀ C⁻¹ θ, C their covariance (from the fit's covariance of the log parameters,
    C = D C_log D, D = diag θ: so W = 1ᵀ C_log⁻¹ 1), against χ² with as many degrees of
    freedom as parameters (Seber & Wild 1989, §5.3). For one parameter W = t²: the test is
    |t| ≥ z at level 2Φ(−z), which is what :func:`t_level` gives. Correlated parameters
    (a Timoshenko tread's ρI and shear compliance) may each have |t| ≈ 1 while W is large:
    the fit cannot say which of them, but it can say that not both vanish.
    """
    if len(names) < 2:
        return None
    idx = [res.free.index(nm) for nm in names]
    C = np.asarray(res.covariance_log, dtype=float)[np.ix_(idx, idx)]
    one = np.ones(len(idx))
    W = float(one @ np.linalg.pinv(C, rcond=1e-12) @ one)
    return float(scipy.special.chdtrc(len(idx), W))


def testimony(current: RobustFit) -> list:
    """The modes a candidate is fitted to: those the current model keeps and the set-aside
    ones whose order was measured — a set-aside mode above the spatial Nyquist order has its
    n from the model's own dispersion, not from the points, and cannot testify against the
    model (it may still be relabelled as an alias, :func:`tiremodal_cli.diagnose.aliases.recheck`)."""
    return list(current.kept) + [a.mode for a in current.set_aside if not a.mode.aliased]


def aligned(res: FitResult, data) -> FitResult:
    """``res`` with its mode table in the order of ``data`` (fits of the same modes in
    another order)."""
    key = lambda n, b, f, mem: (n, b, round(f, 9), mem)  # noqa: E731
    table = {key(m["n"], m["branch"], m["measured_hz"], m.get("member")): m for m in res.modes}
    rows = [table[key(m.n, m.branch, m.frequency_hz, m.member)] for m in data]
    return dataclasses.replace(res, modes=rows)


def refit_on(res: FitResult, modes, opt) -> FitResult:
    """The model of ``res`` (same free parameters and effects) fitted to ``modes``, from ``res``."""
    o = res.options
    fo = fit_options(opt, free=tuple(f for f in res.free if "." not in f), effects=res.effects,
                   effect_free=tuple(tuple(f.split(".", 1)) for f in res.free if "." in f), start=search_start(res))
    fo = dataclasses.replace(fo, bounds=o.bounds, search="polish")
    return fit(list(modes), res.parameters, fo)


def refit_robust(res: FitResult, modes, opt) -> RobustFit:
    """The model of ``res`` fitted robustly to ``modes`` (relabelled modes, the structure
    without its cavity mode)."""
    fo = fit_options(opt, free=tuple(f for f in res.free if "." not in f), effects=res.effects,
                   effect_free=tuple(tuple(f.split(".", 1)) for f in res.free if "." in f), start=search_start(res))
    return robust_fit(list(modes), res.parameters, dataclasses.replace(fo, bounds=res.options.bounds),
                      alpha=opt.alpha)


def restrict(res: FitResult, k: int) -> FitResult:
    """The fit's structural modes only (the first ``k``): RMS and table recomputed."""
    modes = res.modes[:k]
    e = np.array([m["error_pct"] for m in modes])
    return dataclasses.replace(res, modes=modes, rms_error_pct=float(np.sqrt(np.mean(e**2))),
                               max_error_pct=float(np.max(np.abs(e))))
