"""Is the rim mass determined? Its profile over the whole search range.

A free rim's mass m_w and a fixture's stiffness k_f (``rim_fixture``) act on the n = 1
block only, and the measured n = 1 modes can be matched by two different rigs: a heavy rim
on a stiff fixture (the rim mode is the rim bouncing on the fixture, the tread sees a nearly
clamped hub) and a light rim on a soft one. Both are minima of the same weighted residual,
and the least-squares standard error of the one found (from the curvature at it) says
nothing about the other. The profile does: m_w is fixed at each point of a grid over its
search range and every other free parameter refitted, each point from its neighbour's
optimum (continuation, outward from the optimum), giving the profile RSS(m_w).

The rule (profile likelihood, Venzon & Moolgavkar 1988): the confidence set of m_w at
level 1 − α is every m_w whose profile RSS lies within χ²₁(1 − α) · s² of the minimum
(s² = max(1, RSS_min / dof): the residual's own scale when it exceeds the noise). Its width
in ln m_w, divided by 2 z₁₋α/₂, is an equivalent standard error of ln m_w; m_w is
*undetermined* when that exceeds 0.5 — the rule the fit applies to a parameter's
curvature-based standard error (:func:`tiremodal_cli.tyre.fit.fit`, "relative standard
error > 50 %"). So is every other free parameter whose value along the confidence set
spans that much (k_f, which moves with m_w from one rig to the other).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.special

from tiremodal_cli.diagnose.options import DiagnoseOptions, fit_options
from tiremodal_cli.diagnose.statistics import weighted_rss
from tiremodal_cli.tyre.fit import fit
from tiremodal_cli.tyre.fit_types import DEFAULT_BOUNDS, FitResult
from tiremodal_cli.tyre.robust import RobustFit

__all__ = ["GRID_POINTS", "profile_rim_mass", "mark_undetermined", "lumped_mass_note"]

#: Points of the profile grid over m_w's search range (1 kg … 100 t: a factor 1.9 apart).
GRID_POINTS = 19

#: ln-standard error above which a parameter is undetermined (fit.py's 50 % rule).
SE_LOG_LIMIT = 0.5


def _start(res: FitResult, values: dict) -> dict:
    out = {k: float(getattr(res.parameters, k)) for k in ("k_r1", "k_r2", "EI", "rhoA", "m_s", "b")}
    for e, vals in res.effects.items():
        out.update({f"{e}.{k}": float(v) for k, v in vals.items()})
    out.update(values)
    return out


def _fixed_fit(res: FitResult, modes, m_w: float, start: dict, opt: DiagnoseOptions) -> FitResult:
    """``res``'s model with m_w fixed at ``m_w``, every other free parameter refitted (least
    squares from ``start``)."""
    free = tuple(f for f in res.free if f != "m_w")
    fo = fit_options(opt, free=tuple(f for f in free if "." not in f), effects=res.effects,
                     effect_free=tuple(tuple(f.split(".", 1)) for f in free if "." in f), start=start)
    fo = dataclasses.replace(fo, bounds=res.options.bounds, search="polish")
    return fit(list(modes), res.parameters.replace(m_w=float(m_w)), fo)


def _walk(res: FitResult, modes, grid, i0: int, opt) -> list:
    """Profile fits at every grid point, outward from index ``i0`` (the optimum's place),
    each from its neighbour's optimum."""
    out = [None] * len(grid)
    for step in (1, -1):
        prev = _start(res, {})
        for i in range(i0 if step == 1 else i0 - 1, len(grid) if step == 1 else -1, step):
            r = _fixed_fit(res, modes, grid[i], prev, opt)
            out[i] = r
            prev = _start(r, {})
    return out


def profile_rim_mass(rf: RobustFit, opt: DiagnoseOptions) -> dict | None:
    """The profile of the rim mass of a fit that frees it (None otherwise): ``grid`` (kg),
    ``rss`` (weighted, over the kept modes), ``limit`` (the confidence set's RSS bound),
    ``inside`` (the m_w of the confidence set), ``se_log`` (its equivalent ln-standard error),
    ``determined``, ``moves`` ({parameter: (min, max)} along the set) and ``ridge`` (the
    combination the modes determine, :func:`_ridge`)."""
    res, modes = rf.fit, list(rf.kept)
    if "m_w" not in res.free or res.parameters.m_w is None:
        return None
    lo, hi = DEFAULT_BOUNDS["m_w"]
    m0 = float(res.parameters.m_w)
    grid = np.unique(np.append(np.geomspace(lo, hi, GRID_POINTS), m0))
    i0 = int(np.searchsorted(grid, m0))
    fits = _walk(res, modes, grid, i0, opt)
    rss = np.array([weighted_rss(f, modes) for f in fits])
    rss = np.where(np.isfinite(rss), rss, np.inf)  # a mass at which the model loses a measured mode
    rss_min = min(float(rss.min()), weighted_rss(res, modes))
    dof = max(len(modes) - len(res.free), 1)
    limit = rss_min + float(scipy.special.chdtri(1, opt.alpha)) * max(1.0, rss_min / dof)
    inside = np.flatnonzero(rss <= limit)
    z = float(scipy.special.ndtri(1 - opt.alpha / 2))
    se_log = math.log(grid[inside].max() / grid[inside].min()) / (2 * z) if inside.size else 0.0
    others = [f for f in res.free if f != "m_w"]
    moves = {}
    for name in others:
        i = fits[0].free.index(name)
        v = np.array([fits[k].values[i] for k in inside])
        if v.size and math.log(v.max() / v.min()) / (2 * z) > SE_LOG_LIMIT:
            moves[name] = (float(v.min()), float(v.max()))
    return {"parameter": "m_w", "grid": grid.tolist(), "rss": rss.tolist(), "rss_min": rss_min, "limit": limit,
            "inside": grid[inside].tolist(), "se_log": se_log, "determined": se_log <= SE_LOG_LIMIT,
            "moves": moves, "ridge": _ridge(grid[inside], [fits[k] for k in inside]), "alpha": opt.alpha}


def _ridge(m_w, fits) -> dict | None:
    """What the modes do determine along the confidence set: the fixture stiffness as a
    line in the rim mass, k_f = k_0 + m_w (2π f_w)² (the rim bouncing at f_w on its supports
    whatever its mass), with the line's largest relative deviation from the profile."""
    if len(fits) < 3 or "rim_fixture.k_f" not in fits[0].free:
        return None
    i = fits[0].free.index("rim_fixture.k_f")
    k = np.array([f.values[i] for f in fits])
    slope, k0 = np.polyfit(m_w, k, 1)
    if slope <= 0:
        return None
    dev = float(np.max(np.abs(k0 + slope * m_w - k) / k))
    return {"k0_n_per_m": float(k0), "f_w_hz": float(np.sqrt(slope) / (2 * np.pi)), "max_rel_deviation": dev}


def mark_undetermined(res: FitResult, profile: dict | None) -> FitResult:
    """``res`` with m_w, and every parameter that moves with it, listed as undetermined
    when the profile says so (its reason names the range the modes allow)."""
    if not profile or profile["determined"]:
        return res
    lo, hi = min(profile["inside"]), max(profile["inside"])
    why = (f"not unique: the modes fit within the χ² limit (α = {profile['alpha']:g}) for m_w from "
           f"{lo:.3g} to {hi:.3g} kg")
    und = dict(res.undetermined)
    und["m_w"] = why
    for name, (a, b) in profile["moves"].items():
        und[name] = f"{why}, it moving with m_w from {a:.3g} to {b:.3g}"
    return dataclasses.replace(res, undetermined=und)


def lumped_mass_note(adopted, orders_mix: str | None) -> str:
    """What a test whose orders mix cannot tell, when the diagnosis read a mass change as a
    uniform one ("" otherwise).

    A lumped mass mixes the circumferential orders (the modal stage's ``orders_mix``); on the
    sensors' plane it also hides every pair's other member, whose node is at the sensors, so
    the table holds one member per order and no split pair testifies for the mass. The one
    member's lowering is then nearly uniform over the orders, and a uniform mass change
    (``rhoA``) fits it as well (docs/diagnose.md, "Mixed orders as a mass's evidence":
    ΔAICc −48.5 for rhoA against −39.5 for the mass on a 0.5 kg mass's own noise-free
    frequencies). The verdict says so rather than let rhoA stand for what it cannot tell."""
    if not orders_mix or "rhoA" not in adopted or "added_mass" in adopted:
        return ""
    return ("the test's orders mix (a lumped asymmetry: " + orders_mix + "), so the mass change read as rhoA may "
            "be a mass lumped at the sensors' angle, whose split pairs the sensors cannot see: one member per "
            "order does not tell the two apart")

