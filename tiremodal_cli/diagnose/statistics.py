"""The residual against the noise and the evidence between nested fits (χ², AICc, F-test).

References
----------
Burnham & Anderson (2002), *Model Selection and Multimodel Inference* (AICc).
Seber & Wild (1989), *Nonlinear Regression*, §5.3 (extra-sum-of-squares F-test).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.special

from tiremodal_cli.diagnose.options import DiagnoseOptions
from tiremodal_cli.tyre.fit_types import FitResult
from tiremodal_cli.tyre.robust import RobustFit

__all__ = ["sigma_rel", "residual_analysis", "aicc", "weighted_rss", "f_test_p"]


def sigma_rel(modes) -> np.ndarray:
    return np.array([m.uncertainty_hz / m.frequency_hz for m in modes])


def residual_analysis(rf: RobustFit, opt: DiagnoseOptions, *, n_extra: int = 0, band=()) -> dict:
    """The residual of a robust fit against the noise, and its pattern.

    Returns a dict: per kept mode ``z`` (error / σ), ``chi2``, ``dof``, ``p_value`` of the
    kept modes, ``set_aside`` (the modes the fit set aside, each with its reason) and
    ``exceeds_noise``: the χ² test at level ``alpha`` fails, or a mode was set aside (an
    outlier at the same level); and ``pattern``: per branch the trend
    of the error with n (slope %/order and its t), the number of sign changes along n,
    isolated outliers (|z| > 3 and > 4 robust deviations from the branch's median), split
    pairs (one (n, branch) measured twice), and a list of plain-language ``findings``.

    ``band``: the cavity band's n = 1 modes that fit no structural (n, branch), each with
    ``z``, its distance from the model's nearest n = 1 mode over the noise floor
    (:func:`tiremodal_cli.diagnose.cavity.unexplained_band_modes`): measured modes the model
    must explain, counted in the χ² (one degree of freedom each) and listed as
    ``unexplained_band_modes``.
    """
    res, modes = rf.fit, list(rf.kept)
    err = np.array([m["error_pct"] for m in res.modes])
    sig = 100 * sigma_rel(modes)
    z = err / sig
    k = len(res.free)
    zb = np.array([b["z"] for b in band], dtype=float)
    dof = max(len(modes) + zb.size - k, 1)
    chi2 = float(np.sum(z**2) + np.sum(np.minimum(zb, 1e6) ** 2))
    p = float(scipy.special.chdtrc(dof, chi2))  # χ² survival function (scipy.stats costs 0.4 s to import)
    pattern = _branch_pattern(modes, err, sig, z)
    pairs = {}
    for m in modes:
        if m.member:
            pairs.setdefault((m.n, m.branch), []).append(m.frequency_hz)
    pattern["split_pairs"] = [{"n": n, "branch": b, "frequencies_hz": sorted(f),
                               "splitting_pct": float(100 * (max(f) - min(f)) / np.mean(f))}
                              for (n, b), f in sorted(pairs.items())]
    pattern["findings"] = _findings(pattern, chi2, dof, p, opt, n_extra, rf.set_aside) + [
        f"n = 1 mode at {b['frequency_hz']:.1f} Hz in the cavity band that no model mode explains "
        f"(nearest n = 1 at {b['model_hz']:.1f} Hz, z = {b['z']:.0f})" for b in band if b["z"] > 3]
    return {"modes": [{**m, "sigma_pct": float(s), "z": float(zz)} for m, s, zz in zip(res.modes, sig, z)],
            "chi2": chi2, "dof": dof, "p_value": p, "exceeds_noise": bool(p < opt.alpha or rf.set_aside),
            "set_aside": [a.to_dict() for a in rf.set_aside], "z_crit": rf.z_crit,
            "unexplained_band_modes": [dict(b) for b in band],
            "rms_error_pct": res.rms_error_pct, "max_error_pct": res.max_error_pct,
            "noise_floor_pct": opt.noise_floor_pct, "pattern": pattern}


def _branch_pattern(modes, err, sig, z) -> dict:
    """Per branch the trend of the error with n, its sign changes, and isolated outliers
    (the ``pattern`` of :func:`residual_analysis`, split pairs and findings still empty)."""
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
    return pattern


def _findings(pattern, chi2, dof, p, opt, n_extra, set_aside=()) -> list[str]:
    out = []
    if p < opt.alpha:
        out.append(f"the residual exceeds the noise: χ² = {chi2:.1f} on {dof} degrees of freedom (p = {p:.2g})")
    if set_aside:
        out.append(f"{len(set_aside)} mode(s) the model cannot represent, set aside: "
                   + ", ".join(f"n = {a.mode.n} {a.mode.branch} at {a.mode.frequency_hz:.1f} Hz"
                               + (f" ({a.error_pct:+.1f} %)" if np.isfinite(a.error_pct) else " (no such model mode)")
                               for a in set_aside))
    if p >= opt.alpha:  # (with modes set aside, the residual that remains is theirs: say whose is at the noise)
        out.append(f"the {'kept modes’ ' if set_aside else ''}residual is at the level of the noise: χ² = {chi2:.1f} "
                   f"on {dof} degrees of freedom (p = {p:.2g})")
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


def aicc(rss: float, n: int, k: int) -> float:
    rss = max(rss, 1e-300)
    corr = 2 * k * (k + 1) / (n - k - 1) if n - k - 1 > 0 else np.inf
    return n * math.log(rss / n) + 2 * k + corr


def weighted_rss(res: FitResult, modes) -> float:
    """Σ (error / σ)² over ``modes`` (the first len(modes) rows of the fit's table)."""
    e = np.array([m["error_pct"] for m in res.modes[:len(modes)]]) / 100 / sigma_rel(modes)
    return float(e @ e)


def f_test_p(rss0, k0, rss1, k1, n) -> float:
    dk, dof1 = k1 - k0, n - k1
    if dk <= 0 or dof1 <= 0:
        return 1.0
    if rss1 <= 0:
        return 0.0
    F = max((rss0 - rss1) / dk, 0.0) / (rss1 / dof1)
    return float(scipy.special.fdtrc(dk, dof1, F))  # F survival function
