"""What a diagnosis found: the candidates with their verdicts, the diagnosis, its prose and JSON."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tiremodal_cli.diagnose.options import DiagnoseOptions
from tiremodal_cli.tyre.fit_types import FitResult
from tiremodal_cli.tyre.predict import predict_table
from tiremodal_cli.tyre.robust import RobustFit

__all__ = ["Candidate", "no_evidence", "Diagnosis", "verdict_text", "predictions", "mode_table", "report"]


@dataclass(frozen=True)
class Candidate:
    """One candidate tried on top of a model, with its score and verdict.

    name, kind : effect name or parameter; "structural", "coupling", "acoustic" or "parameter"
    round : 1 for the first effect, 2 for one on top of it
    parameters : {name: {"value", "std_error", "t"}} its fitted parameters
    rms_error_pct, aicc, delta_aicc : the refit's RMS error and AICc, and AICc − the current model's
    f_p_value : nested F-test p-value against the current model
    adopted : bool ; reason : why adopted or rejected ; passes : every test passed
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
    #: every test passed (adoptable); ``reason`` then says why it was or was not adopted
    passes: bool = False
    #: base parameters the candidate frees but its fit cannot determine (:func:`on_ridge`),
    #: held at the current model's values, and why; None when none
    held: str | None = None



def no_evidence(name: str, reason: str, common: dict) -> Candidate:
    """A candidate not fitted: it lacks the evidence it needs (``reason``)."""
    return Candidate(name=name, parameters={}, rms_error_pct=None, aicc=None, delta_aicc=None, f_p_value=None,
                     adopted=False, reason=reason, **common)


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
    #: the final model's rim-mass profile when it frees m_w
    #: (:func:`tiremodal_cli.diagnose.identifiability.profile_rim_mass`)
    rim_profile: dict | None = None

    def to_dict(self, n_max: int = 12) -> dict:
        """The diagnosis as JSON-ready data (:func:`report`; predictions up to order ``n_max``)."""
        return report(self, n_max)


def profile_text(profile: dict | None) -> str:
    """The rim-mass profile's verdict in words ("" when m_w is not fitted or is determined)."""
    if not profile or profile["determined"]:
        return ""
    lo, hi = min(profile["inside"]), max(profile["inside"])
    r = profile.get("ridge")
    line = (f"; what they determine is the rim's frequency on its supports, k_f = {r['k0_n_per_m']:.3g} N/m + "
            f"m_w (2π · {r['f_w_hz']:.3g} Hz)² (within {100 * r['max_rel_deviation']:.1f} % along the set)"
            if r else "")
    return (f"the rim mass is not unique: the modes fit within the χ² limit for m_w from {lo:.3g} to {hi:.3g} kg"
            + (f" ({', '.join(profile['moves'])} moving with it)" if profile["moves"] else "") + line)


def verdict_text(adopted, tried, before, after, unexplained, max_effects: int | None = None) -> str:
    """The diagnosis in one sentence. A residual above the noise is said to be one no
    candidate explains only when the search could go on; with ``max_effects`` effects
    adopted it stopped at that limit, and the verdict says so (a candidate might explain
    the rest: a test with two effects and a breathing mode the model lacks)."""
    capped = max_effects is not None and len(adopted) >= max_effects
    remains = (f"a residual remains: the search stopped at max_effects = {max_effects} (raise it to try more)"
               if capped else "a residual remains that no candidate explains")
    if not before["exceeds_noise"] and not adopted:
        v = ("no effect needed: the base model's residual is at the level of the noise "
             f"(RMS {before['rms_error_pct']:.3f} %, χ² p = {before['p_value']:.2g})")
    elif adopted:
        what = ", ".join(adopted)
        v = (f"adopted {what}: RMS error {before['rms_error_pct']:.3f} % → {after['rms_error_pct']:.3f} %, "
             f"max {before['max_error_pct']:.3f} % → {after['max_error_pct']:.3f} %")
        if after["exceeds_noise"]:
            v += (f"; {remains} ("
                  + "; ".join([f for f in after["pattern"]["findings"] if not f.startswith("the residual exceeds")]
                              or ["no clear pattern"]) + ")")
    else:
        v = f"{remains}: " + "; ".join(before["pattern"]["findings"])
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
              "reason": c.reason, "signature": c.signature, "brings_back": list(c.brought_back),
              "held": c.held}
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
        "rim_mass_profile": diag.rim_profile,
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
