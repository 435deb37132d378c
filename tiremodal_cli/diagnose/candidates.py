"""Every candidate (an effect, or a nominal parameter that is off) fitted on top of the current model and judged."""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.special

from tiremodal_cli.diagnose.cavity import CavitySpec, try_cavity
from tiremodal_cli.diagnose.options import PARAMETER_CANDIDATES, fit_options, search_start
from tiremodal_cli.diagnose.refit import Scoring, Trial, aligned, judge, refit_on, testimony
from tiremodal_cli.diagnose.result import Candidate, no_evidence
from tiremodal_cli.diagnose.statistics import residual_analysis
from tiremodal_cli.tyre.effects import get_effect
from tiremodal_cli.tyre.fit_types import DEFAULT_BOUNDS
from tiremodal_cli.tyre.model import NOMINAL_RIM_KG
from tiremodal_cli.tyre.robust import RobustFit, robust_fit

__all__ = ["try_candidate", "adopt_reason", "choose", "split_evidence", "on_ridge", "too_few_modes"]


def _effect_spec(name, fixed_effects):
    eff = get_effect(name)
    fitted = eff.fitted_parameters()
    fixed = {p.name: eff.diagnose_fixed.get(p.name, p.default) for p in eff.parameters if p not in fitted}
    effects = {k: dict(v) for k, v in fixed_effects.items()}
    effects[name] = fixed
    return eff, fitted, effects


def try_candidate(name: str, trial: Trial) -> Candidate:
    """Refit every mode (the set-aside ones too) with one more candidate on top of the
    current model, robustly; judge it on the modes either model keeps."""
    if name in ("m_w", "rim_fixture") and trial.opt.rim == "clamped":
        common = dict(kind="parameter" if name == "m_w" else "structural", round=trial.rnd, signature="",
                      title=f"nominal {name} is off" if name == "m_w" else get_effect(name).title)
        return no_evidence(name, "no evidence: the rim channel recorded no signal (a clamped rim)", common)
    if name in PARAMETER_CANDIDATES:
        return _try_parameter(name, trial)
    return _try_effect(name, trial)


def _free_split(cur) -> tuple[tuple, tuple]:
    """The current fit's free structural parameters and its effects' (effect, parameter) pairs."""
    free = tuple(cur.free)
    return tuple(f for f in free if "." not in f), tuple(tuple(f.split(".", 1)) for f in free if "." in f)


def _try_parameter(name: str, trial: Trial) -> Candidate:
    """A nominal parameter freed on top of the current model ("a parameter value is off")."""
    cur = trial.current.fit
    struct_free, prev_eff_free = _free_split(cur)
    lo, hi = DEFAULT_BOUNDS[name]
    fo = dataclasses.replace(fit_options(trial.opt, free=struct_free + (name,), effects=dict(cur.effects),
                                         effect_free=prev_eff_free, start=search_start(cur)), bounds={})
    start = cur.parameters
    p0 = start if name != "m_w" or start.m_w is not None else start.replace(m_w=NOMINAL_RIM_KG)
    common = dict(kind="parameter", title=f"nominal {name} is off", round=trial.rnd,
                  signature="a parameter value is off, not missing physics")
    return _judged(name, common, trial, p0, fo, Scoring((name,), {name: (lo, hi)}, trial.opt, trial.n_tried))


def _try_effect(name: str, trial: Trial) -> Candidate:
    """An effect of :mod:`tiremodal_cli.tyre.effects` added to the current model."""
    cur = trial.current.fit
    struct_free, prev_eff_free = _free_split(cur)
    eff, fitted, effects = _effect_spec(name, dict(cur.effects))
    efree = prev_eff_free + tuple((name, p.name) for p in fitted)
    bounds = {f"{name}.{p.name}": (p.lower, p.upper, p.upper_is_physical) for p in fitted}
    pnames = tuple(f"{name}.{p.name}" for p in fitted)
    common = dict(kind=eff.kind, title=eff.title, round=trial.rnd, signature=eff.signature)
    if eff.kind == "coupling" and not any(m.member for m in trial.current.modes):
        return no_evidence(name, "no evidence: no split pair in the modal table", common)
    if eff.kind == "acoustic":
        return try_cavity(name, CavitySpec(effects, efree, bounds, list(pnames), struct_free), trial, common)
    if eff.extra.get("needs_free_rim") and cur.parameters.m_w is None:
        return no_evidence(name, "no evidence: the rim is clamped (its channel recorded no signal, or the "
                                 "parameters say so)", common)
    also = tuple(a for a in eff.extra.get("also_free", ()) if a not in struct_free)
    if also:  # the effect's own parameter and the seed model's that it acts with (the rim mass)
        struct_free = struct_free + also
        pnames = pnames + also
        bounds = {**bounds, **{a: DEFAULT_BOUNDS[a] for a in also}}
    own = {f"{name}.{p.name}": p.default for p in fitted}
    nominal = trial.nominal
    fo = fit_options(trial.opt, free=struct_free, effects=effects, effect_free=efree,
                     start={**search_start(cur), **own},
                     extra_starts=({**search_start(cur), **(nominal or {}), **own},) if nominal else ())
    c = _judged(name, common, trial, cur.parameters, fo, Scoring(pnames, bounds, trial.opt, trial.n_tried))
    ridge = [a for a in also if c.fit is not None and on_ridge(c.fit, a)]
    if ridge:
        # the modes do not determine them (a flat ridge): the point on the ridge is the one
        # with them at the current model's values — found with them held, then polished with
        # them free again (the gradient along the ridge is nil: they stay), so that the next
        # round starts from the same model whatever path the search took along the ridge
        held = {a: float(getattr(cur.parameters, a)) for a in ridge}
        fo_h = dataclasses.replace(fo, free=tuple(f for f in fo.free if f not in ridge))
        pn_h = tuple(q for q in pnames if q not in ridge)
        c_h = _judged(name, common, trial, cur.parameters, fo_h,
                      Scoring(pn_h, {k: v for k, v in bounds.items() if k in pn_h}, trial.opt, trial.n_tried))
        if c_h.fit is not None:
            start = {**search_start(c_h.fit), **held}
            fo_p = dataclasses.replace(fo, start=start, start_from="the ridge point", search="polish")
            c = _judged(name, common, trial, c_h.fit.parameters, fo_p,
                        Scoring(pnames, bounds, trial.opt, trial.n_tried))
            stayed = c.fit is not None and all(abs(float(getattr(c.fit.parameters, k)) / v - 1) < 1e-6
                                               for k, v in held.items())
            if stayed:  # (else the polish found a slope: no ridge there, and nothing to say)
                c = dataclasses.replace(c, held=", ".join(f"{k} = {v:.4g}" for k, v in held.items())
                                        + " kept at the current model's value: the modes determine only a "
                                          f"combination of it with {name}'s own parameters (a flat ridge of the fit)")
    if eff.kind == "coupling" and c.passes:
        missing = split_evidence(c, trial.opt)[1]
        if missing:
            return dataclasses.replace(c, passes=False, reason=missing)
    return c


def on_ridge(res, name: str) -> bool:
    """True when the fit ``res`` does not determine the free parameter ``name``: it takes part
    in a direction of the log parameters along which the modes do not change (a null
    vector of the Jacobian).

    A rim on its fixture seen through one n = 1 mode is the case: the modes fix the rim's
    frequency on the fixture, √(k_f / m_w) in effect, and any m_w fits as well with its k_f
    (the χ² flat to 1e-12 over four decades). The Jacobian there is singular; its standard
    errors from the pseudo-inverse are those of the determined directions only and say
    nothing of the ridge. Null: a singular value below 1e-6 of the largest (the covariance's
    pseudo-inverse cut-off, 1e-12 on JᵀJ; the central differences' error is ~1e-9 of the
    largest), with the parameter's share of that singular vector above 0.1 (a 1 % part of
    the direction's length squared; below that the direction is another parameter's).
    """
    if name not in res.free:
        return False
    J = np.asarray(res.jacobian, dtype=float)
    if J.size == 0 or not np.all(np.isfinite(J)):
        return False
    _, sv, vt = np.linalg.svd(J, full_matrices=True)
    sv = np.concatenate([sv, np.zeros(vt.shape[0] - sv.size)])
    i = list(res.free).index(name)
    null = sv < 1e-6 * sv.max() if sv.max() > 0 else np.ones(sv.size, bool)
    return bool(np.any(np.abs(vt[null, i]) > 0.1))


def split_evidence(c: Candidate, opt) -> tuple[list[dict], str | None]:
    """Does a coupling candidate's fit reproduce the split pairs that are its evidence?

    Per measured pair (both members in the candidate's fit): the splitting Δ = f_upper −
    f_lower with σ_Δ = √(σ_lower² + σ_upper²) (the members' frequency uncertainties); the
    pair is a split beyond its measurement uncertainty when Δ > z σ_Δ, and the fit explains
    it when |Δ − Δ_model| ≤ z σ_Δ, z = Φ⁻¹(1 − α/2). Every other candidate is axisymmetric
    (Δ_model = 0), so a split the coupling's fit does not reproduce testifies for nothing:
    a pair of two orders read as one, a crowd's poles. Returns (the pairs, each with Δ,
    σ_Δ, Δ_model, "real", "explained"; None when at least one real split is explained, else
    why not)."""
    z = float(scipy.special.ndtri(1 - opt.alpha / 2))
    sig = {(m.n, m.branch, m.member): m.uncertainty_hz for m in (c.robust.kept if c.robust else ()) if m.member}
    rows = {(r["n"], r["branch"], r.get("member")): r for r in (c.fit.modes if c.fit else ())}
    pairs = []
    for (n, b, mem), s_lo in sig.items():
        if mem != "lower" or (n, b, "upper") not in sig or (n, b, "lower") not in rows or (n, b, "upper") not in rows:
            continue
        lo, up = rows[(n, b, "lower")], rows[(n, b, "upper")]
        d, dm = up["measured_hz"] - lo["measured_hz"], up["model_hz"] - lo["model_hz"]
        s_d = float(np.hypot(s_lo, sig[(n, b, "upper")]))
        pairs.append({"n": n, "branch": b, "splitting_hz": d, "sigma_hz": s_d, "model_splitting_hz": dm,
                      "real": d > z * s_d, "explained": abs(d - dm) <= z * s_d})
    if any(p["real"] and p["explained"] for p in pairs):
        return pairs, None
    what = "; ".join(f"n = {p['n']} {p['branch']}: measured {p['splitting_hz']:.2f} ± {p['sigma_hz']:.2f} Hz, "
                     f"model {p['model_splitting_hz']:.2f} Hz" for p in pairs) or "no pair kept in its fit"
    return pairs, ("no evidence: its fit reproduces no measured split pair beyond the splitting's "
                   f"uncertainty (z = {z:.2f}; {what})")


def _judged(name, common, trial: Trial, p0, fo, scoring: Scoring) -> Candidate:
    """A candidate judged against the current model on the modes the current model keeps
    plus the set-aside modes the candidate brings back.

    Every mode enters the candidate's fit; those the current model keeps stay in it (the
    candidate must carry what the current model carries), and a set-aside mode comes back
    only when the candidate holds it inside the current model's outlier limit with all of
    them in the fit — a candidate cannot buy a mode back by bending the others."""
    current, opt = trial.current, trial.opt
    kept = set(current.kept)
    few = too_few_modes(len(testimony(current)), len(fo.free) + len(fo.effect_free))
    if few:
        return no_evidence(name, few, common)
    rc = robust_fit(testimony(current), p0, fo, alpha=opt.alpha, scale=current.scale, protect=lambda m: m in kept)
    data = rc.kept
    cur = current.fit if set(data) == kept else aligned(refit_on(current.fit, data, opt), data)
    fields, why = judge(rc.fit, cur, list(data), scoring)
    back = tuple(a.to_dict() for a in current.set_aside if a.mode in set(rc.kept))
    return Candidate(name=name, reason=why or "passes", passes=why is None, adopted=False, robust=rc,
                     data=tuple(data), brought_back=back, bounds=scoring.bounds, **fields, **common)


def too_few_modes(n_modes: int, k: int) -> str | None:
    """Why a candidate of ``k`` free parameters cannot be judged on ``n_modes`` modes (its fit
    needs a degree of freedom left for the F-test and the χ²), or None."""
    if n_modes > k:
        return None
    return (f"not judged: {n_modes} modes for its {k} free parameters (a judgement needs more modes than "
            "parameters: longer records or a wider band give more)")


def adopt_reason(c: Candidate, runner: Candidate | None) -> str:
    what = "a parameter value is off" if c.kind == "parameter" else "missing physics"
    s = (f"adopted ({what}): RMS {c.rms_error_pct:.3f} %, ΔAICc {c.delta_aicc:+.1f}, F-test p = {c.f_p_value:.2g}, "
         + ", ".join(f"{k} = {v['value']:.4g} ± {v['std_error']:.2g}" for k, v in c.parameters.items()))
    if c.held:
        s += f"; {c.held}"
    if c.brought_back:
        s += "; brings back " + ", ".join(f"n = {b['n']} {b['branch']} at {b['frequency_hz']:.1f} Hz"
                                          for b in c.brought_back)
    if runner is not None:  # (a runner-up with more evidence was refused: say why, or the reader is left puzzled)
        s += (f"; runner-up {runner.name} (ΔAICc {runner.delta_aicc:+.1f}"
              + ("" if runner.passes else f", refused: {runner.reason}") + ")")
    return s


def choose(cands, current: RobustFit, opt, n_tried, *, needed: bool, smooth_at_noise: bool = False):
    """The round's verdicts: the passing candidate with the most evidence over the current
    model (lowest ΔAICc, each on the modes it was judged on) adopted, the others with the
    reason they were not.

    Each candidate is judged on the modes either it or the current model keeps; a candidate
    that brings back a set-aside mode is judged on one mode more. Its ΔAICc is the evidence
    it has against the current model on its own data, and that is what is compared.

    ``smooth_at_noise``: the kept modes' residual is at the level of the noise (its χ² test
    passes) and only set-aside modes asked for an effect. Then a candidate must explain what
    asked for it — bring a set-aside mode back, or have evidence of its own
    (:func:`own_evidence`): the F-test on residuals already under the noise measures the
    modal estimates' correlated errors, not physics (a nominal m_s adopted at F-test p =
    10⁻⁵ on RMS 0.039 → 0.032 % against a 0.1 % floor, the set-aside row a band-top pole)."""
    if not needed:
        return None, [dataclasses.replace(c, reason="not needed: the residual is at the level of the noise"
                                          + ("" if c.passes else f"; besides, {c.reason}")) for c in cands]
    cands = [_closure(c, opt) for c in cands]
    if smooth_at_noise:
        cands = [_explains_set_aside(c) for c in cands]
    passing = [c for c in cands if c.passes]
    best = min(passing, key=lambda c: c.delta_aicc) if passing else None
    runner = min((c for c in cands if c is not best and c.delta_aicc is not None), key=lambda c: c.delta_aicc,
                 default=None)
    out = []
    for c in cands:
        if c is best:
            out.append(dataclasses.replace(best, adopted=True, reason=adopt_reason(best, runner)))
        elif c.passes:
            out.append(dataclasses.replace(c, reason=f"passes, but {best.name} explains more "
                                                     f"(ΔAICc {c.delta_aicc - best.delta_aicc:+.1f} above it)"))
        else:
            out.append(c)
    return best, out


def own_evidence(c: Candidate) -> str | None:
    """What a candidate explains besides the smooth residual, or None: the measured mode
    it takes as its own (the cavity's), the split pairs it needs (a lumped mass), or a
    mode the current model set aside that it brings back."""
    if c.cavity_mode is not None:
        return f"the cavity mode at {c.cavity_mode['frequency_hz']:.1f} Hz"
    if c.kind == "coupling":
        return "the split pairs"
    if c.brought_back:
        return "the set-aside mode(s) it brings back"
    return None


def _explains_set_aside(c: Candidate) -> Candidate:
    """A passing candidate without evidence of its own refused where the kept modes'
    residual is already at the noise (:func:`choose`'s ``smooth_at_noise``)."""
    if not c.passes or own_evidence(c) is not None:
        return c
    return dataclasses.replace(c, passes=False, reason=(
        f"improves the fit (F-test p = {c.f_p_value:.2g}) but the kept modes' residual is already at the level "
        "of the noise, and it brings back none of the set-aside modes that asked for an effect (no evidence of "
        "its own): what it fits is the modal estimates' correlated error, not missing physics"))


def _closure(c: Candidate, opt) -> Candidate:
    """From the second round on, a candidate without evidence of its own must bring the
    residual to the level of the noise.

    Once the adopted model's residual still exceeds the noise, either a second effect is
    present or the adopted effect's form differs from the tyre's; in the second case the
    residual is systematic, not noise, and the F-test's null (independent errors of the
    fitted variance) does not hold: any smooth parameter (a nominal value, another smooth
    effect) buys a part of it beyond "chance". What tells a second effect from compensation
    is what it explains besides the smooth residual (:func:`own_evidence`) or that it
    leaves nothing but noise (the χ² test that asked for an effect in the first place)."""
    if c.round < 2 or not c.passes or own_evidence(c) is not None or c.robust is None:
        return c
    after = residual_analysis(c.robust, opt)
    if not after["exceeds_noise"]:
        return c
    what = (f"χ² = {after['chi2']:.1f} on {after['dof']} (p = {after['p_value']:.2g})"
            + (f", {len(after['set_aside'])} mode(s) set aside" if after["set_aside"] else ""))
    return dataclasses.replace(c, passes=False, reason=(
        f"improves the fit (F-test p = {c.f_p_value:.2g}) but leaves a residual above the noise ({what}) and "
        "explains nothing of its own (no mode brought back, no evidence of its own): on top of an adopted "
        "effect that is compensation of a model-form error, not a second effect"))
