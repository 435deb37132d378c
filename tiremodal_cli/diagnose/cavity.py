"""The air-cavity candidate: its evidence (an unexplained n = 1 mode in the cavity band) and its fit."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tiremodal_cli.diagnose.options import cavity_band_hz, fit_options, search_start
from tiremodal_cli.diagnose.refit import Scoring, Trial, aligned, judge, refit_on, restrict, testimony
from tiremodal_cli.diagnose.result import Candidate, no_evidence
from tiremodal_cli.diagnose.statistics import weighted_rss
from tiremodal_cli.tyre.frequencies import model_frequencies
from tiremodal_cli.tyre.measured import MeasuredMode
from tiremodal_cli.tyre.robust import RobustFit, robust_fit

__all__ = ["CavitySpec", "try_cavity", "band_modes", "unexplained_band_modes"]


@dataclass(frozen=True)
class CavitySpec:
    """The cavity effect's set-up on top of the current model: effects with their fixed
    values, the free (effect, parameter) pairs, bounds and names of the fitted parameters,
    and the free structural parameters."""

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
    structural (n, branch) — or the n = 1 row kept, when the unexplained one is the structure's.
    A mode lsce found in a crowd (several orders alike: an alias of a high order of the
    flat top of the same branch, read as n = 1 on N ± 1 points) shows no n = 1 pattern."""
    lo, hi = cavity_band_hz(current.fit.parameters.R, opt)
    cands = []
    for u in band_modes(extra, lo, hi, current):
        cands.append({"frequency_hz": u["frequency_hz"], "displaced": None, "row": u.get("row")})
        for m in current.modes:
            if m.n == 1 and m.branch == u.get("branch") and lo <= m.frequency_hz <= hi:
                cands.append({"frequency_hz": m.frequency_hz, "displaced": u["frequency_hz"], "row": None})
    return cands


def band_modes(extra, lo: float, hi: float, current: RobustFit) -> list[dict]:
    """The rows that fit no structural (n, branch), show an n = 1 pattern (their order, or
    the order read on the points, is 1) and lie in the cavity band [lo, hi] Hz — not in a
    crowd (lsce: its order cannot be told, no n = 1 pattern to testify), and not a row
    labelled n = 1 of a branch whose structural n = 1 no other row holds: that row may be
    the structural mode itself, out of its branch's dispersion order (the ring's n = 1
    opposite lies above n = 3 with a free rim and with a tangential belt), and a model that
    misplaces it has a structural error, not a cavity."""
    held = {m.branch for m in current.modes if m.n == 1}
    out = []
    for u in extra:
        if u.get("crowd") or (u.get("n") == 1 and u.get("branch") not in held):
            continue
        n_ok = u.get("n") == 1 or (u.get("n_spatial") is not None and int(u["n_spatial"]) == 1)
        if n_ok and lo <= u["frequency_hz"] <= hi and not _of_a_flat_branch(u, extra):
            out.append(u)
    return out


def _of_a_flat_branch(u: dict, extra) -> bool:
    """Whether the unexplained row ``u`` has unexplained rows of other orders within its
    half-power bandwidth 2ζf: several orders at one frequency are a structural branch the
    model lacks (a resonance of the sidewall alone, flat over n), whose n = 1 member ``u``
    is — the cavity couples to n = 1 only and adds one mode (seen: the ring's sidewall
    shear puts n = 1 … 6 of such a branch at 93.6–98.3 Hz, ζ = 2 %; its n = 1, a pinned
    mode 0.03 Hz from the n = 4 one, was taken for a cavity with no coupling). Rows lsce
    found in a crowd count too: a crowd is several orders at one frequency, the flat branch
    itself (the passenger-car tyre's in-phase crowd at 303 Hz, inside its cavity band: its
    n = 35 on 36 points, read n = 1 on the other branch at 302.9 Hz, ζ = 2 %, beside eleven
    crowd rows within 1.3 Hz, was taken for a cavity with no coupling on a test with none)."""
    z = u.get("damping_ratio")
    if not z or u.get("n_spatial") is None:
        return False
    bw = 2 * z * u["frequency_hz"]
    return any(v is not u and v.get("n_spatial") is not None
               and int(v["n_spatial"]) != int(u["n_spatial"]) and abs(v["frequency_hz"] - u["frequency_hz"]) <= bw
               for v in extra)


def unexplained_band_modes(current: RobustFit, extra, opt, explained=()) -> list[dict]:
    """The cavity band's n = 1 modes that fit no structural (n, branch) (:func:`band_modes`),
    each with its normalised distance from the current model's nearest n = 1 mode:
    ``z`` = |f_model / f − 1| / floor. They are measured modes the model must explain
    like any other: a model without a mode there leaves them at that distance (the
    residual χ² counts them). ``explained``: frequencies (Hz) an adopted cavity took."""
    par = current.fit.parameters
    lo, hi = cavity_band_hz(par.R, opt)
    done = {round(float(f), 6) for f in explained}
    effects = current.fit.effects or None
    branches = ["same", "opposite"] + (["cavity"] if effects and "air_cavity" in effects else [])
    out = []
    for u in band_modes(extra, lo, hi, current):
        f = float(u["frequency_hz"])
        if round(f, 6) in done:
            continue
        near = model_frequencies(par, [1] * len(branches), branches, effects, meas_hz=[f] * len(branches))
        near = near[np.isfinite(near)]
        m = float(near[np.argmin(np.abs(near / f - 1))]) if near.size else float("nan")
        d = abs(m / f - 1) if near.size else np.inf
        out.append({"frequency_hz": f, "n": u.get("n"), "branch": u.get("branch"), "model_hz": m,
                    "z": float(d / (opt.noise_floor_pct / 100))})
    return out


def _ordered_union(first, *others):
    seen, out = set(), []
    for group in (first, *others):
        for m in group:
            if m not in seen:
                seen.add(m)
                out.append(m)
    return tuple(out)


def try_cavity(name, spec: CavitySpec, trial: Trial, common: dict) -> Candidate:
    """The air cavity: a mode with an n = 1 tread pattern in the cavity band that fits no
    structural (n, branch) (or that displaced the structural n = 1 from its label)."""
    current, opt = trial.current, trial.opt
    lo, hi = cavity_band_hz(current.fit.parameters.R, opt)
    cands = _cavity_evidence(current, trial.extra, opt)
    if not cands:
        return no_evidence(name, f"no evidence: no unexplained n = 1 mode in the cavity band {lo:.0f}–{hi:.0f} Hz",
                           common)
    from tiremodal_cli.diagnose.candidates import too_few_modes  # (candidates imports this module)

    few = too_few_modes(len(testimony(current)) + 1, len(spec.struct_free) + len(spec.efree))
    if few:
        return no_evidence(name, few, common)
    _, cav, rc, struct, cav_mode = min((_cavity_fit(name, spec, cav, current, opt) for cav in cands),
                                       key=lambda t: t[0])
    kept_struct = [m for m in rc.kept if m.branch != "cavity"]
    # judged on the structural modes either model keeps, plus the cavity mode as one more point
    data = _ordered_union([m for m in current.kept if m in set(struct)], kept_struct)
    cand_all = aligned(refit_on(rc.fit, list(data) + [cav_mode], opt), list(data) + [cav_mode])
    cav_err = cand_all.modes[-1]
    cur_on = aligned(refit_on(current.fit, data, opt), data)
    f_c = cav["frequency_hz"]
    near = model_frequencies(cur_on.parameters, [1, 1], ["same", "opposite"], cur_on.effects or None)
    e0 = float(np.nanmin(np.abs(near / f_c - 1))) / (opt.noise_floor_pct / 100)
    e1 = cav_err["error_pct"] / opt.noise_floor_pct
    missing = (None if abs(cav_err["error_pct"]) <= 3 * opt.noise_floor_pct else
               f"the model's cavity mode misses the measured one by {cav_err['error_pct']:+.2f} %")
    fields, why = judge(restrict(cand_all, len(data)), cur_on, list(data),
                        Scoring(tuple(spec.pnames), spec.bounds, opt, trial.n_tried,
                                may_vanish=tuple(p for p in spec.pnames if p.endswith(".gamma"))),
                        missing_evidence=missing, extra_point=(e0, e1))
    fields["fit"] = cand_all
    g = next((p for p in spec.pnames if p.endswith(".gamma")), None)
    if g is not None and g in fields["parameters"]:
        lo_g, hi_g = spec.bounds[g][:2]
        if fields["parameters"][g]["value"] <= max(lo_g * 1.001, 1e-6 * hi_g):
            fields["held"] = (f"{g} vanishes: no n = 1 structural mode near the cavity's shows its coupling, "
                              "which the frequencies therefore do not determine; the cavity is identified by its mode")
    cavity_mode = {"frequency_hz": cav["frequency_hz"], "n": 1, "model_hz": cav_err["model_hz"],
                   "displaced": cav["displaced"], "band_hz": [lo, hi]}
    back = tuple(a.to_dict() for a in current.set_aside if a.mode in set(kept_struct))
    return Candidate(name=name, reason=why or "passes", passes=why is None, adopted=False, cavity_mode=cavity_mode,
                     robust=rc, data=tuple(data), brought_back=back, bounds=spec.bounds, **fields, **common)


def _cavity_fit(name, spec: CavitySpec, cav: dict, current: RobustFit, opt):
    """The robust fit with ``cav`` as the cavity mode; returns (score, cav, fit, structural
    modes, cavity mode), the score being the kept structural modes' χ² less their number."""
    cur = current.fit
    struct, _ = _modes_for_cavity(testimony(current), cav, opt)
    cav_mode = MeasuredMode(1, "cavity", cav["frequency_hz"], source="cavity mode",
                            uncertainty_hz=cav["frequency_hz"] * opt.noise_floor_pct / 100)
    eff_start = {**spec.effects, name: {**spec.effects[name],
                                        "f_cavity_hz": float(np.clip(cav["frequency_hz"], 50.0, 400.0))}}
    fo = fit_options(opt, free=spec.struct_free, effects=eff_start, effect_free=spec.efree,
                     start={**search_start(cur), **{f"{name}.{k}": v for k, v in eff_start[name].items()}})
    kept = set(current.kept)
    rc = robust_fit(struct + [cav_mode], cur.parameters, fo, alpha=opt.alpha,
                    protect=lambda m: m.branch == "cavity" or m in kept, scale=current.scale)
    kept_struct = [m for m in rc.kept if m.branch != "cavity"]
    score = weighted_rss(restrict(aligned(rc.fit, rc.kept), len(kept_struct)), kept_struct) - len(kept_struct)
    return score, cav, rc, struct, cav_mode
