"""Robust identification: modes the model cannot represent are set aside before they move it.

A weighted least-squares fit lets one mode the model cannot represent — the n = 0
breathing mode of a tyre whose belt is extensible, a spatial alias read as a low order, a
fixture mode — pull every parameter, and with them every other mode, by several
standard deviations. :func:`robust_fit` fits, looks at every mode's normalised error
``z = (f_model − f_measured) / σ_f``, and sets aside the worst mode while it is an outlier,
refitting after each step (the worst mode, with every mode at least half as far out, so
that gross outliers go in one step while a mode merely dragged off by them stays, and comes
back once they are gone). A mode set aside earlier comes back as soon as the refit
puts it inside the limit.

The rule
--------
A mode is an outlier when ``|z − median(z)| / s > z_crit`` with

* ``s = max(1, 1.4826 · MAD(z))`` over all modes: the robust spread of the normalised
  errors, never below 1 (the errors cannot be more precise than their uncertainties);
  when the model lacks physics that moves every mode a little, the spread grows and a mode
  is set aside only when it stands out of that spread, not out of the noise;
* ``z_crit = Φ⁻¹(1 − α / (2N))``, the two-sided Bonferroni limit for N modes: when the
  model holds and the errors are Gaussian with the stated σ, the chance that any of the N
  modes is set aside is at most α (the false-rejection rate per fit; ``alpha`` = 0.01 by
  default: 3.4 for 34 modes, 3.6 for 60). Measured on the validation matrix's no-effect
  cases: docs/diagnose.md.

At most fewer than half the modes are set aside (the median and MAD break down at half),
and at least ``k + 2`` modes stay for k free parameters.

References
----------
Rousseeuw & Leroy (1987), *Robust Regression and Outlier Detection* (MAD scale, breakdown).
Hampel et al. (1986), *Robust Statistics* (1.4826 · MAD as a Gaussian σ).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import scipy.special

from tiremodal_cli.tyre.fit import fit

from tiremodal_cli.tyre.fit_types import FitOptions, FitResult

from tiremodal_cli.tyre.frequencies import model_frequencies

from tiremodal_cli.tyre.measured import MeasuredMode
from tiremodal_cli.tyre.model import TyreParameters

__all__ = ["SetAside", "RobustFit", "z_critical", "with_sigma", "robust_fit", "normalised_errors"]


@dataclass(frozen=True)
class SetAside:
    """A measured mode the fit set aside, and why.

    mode : MeasuredMode ; model_hz : the model's frequency of its (n, branch), Hz (NaN:
    the model has no such mode) ; error_pct : (model − measured) / measured, % ;
    z : error / σ ; reason : one sentence
    """

    mode: MeasuredMode
    model_hz: float
    error_pct: float
    z: float
    reason: str

    def to_dict(self) -> dict:
        m = self.mode
        return {"n": int(m.n), "branch": m.branch, "frequency_hz": float(m.frequency_hz),
                **({"member": m.member} if m.member else {}),
                "model_hz": None if not np.isfinite(self.model_hz) else float(self.model_hz),
                "error_pct": None if not np.isfinite(self.error_pct) else float(self.error_pct),
                "z": None if not np.isfinite(self.z) else float(self.z), "reason": self.reason}


@dataclass(frozen=True)
class RobustFit:
    """A fit on the modes the model can represent, with the modes it set aside.

    fit : FitResult on ``kept`` ; kept : the modes fitted (with σ) ; set_aside : the
    others, each with its reason ; z_crit : the outlier limit used ; scale : the robust
    spread s of the kept modes' normalised errors (≥ 1) ; alpha : the false-rejection rate
    the limit was set for ; relabelled : aliased modes whose order the base fit re-read
    (:func:`tiremodal_cli.diagnose.aliases.reread_aliased`), each as a dict
    """

    fit: FitResult
    kept: tuple[MeasuredMode, ...]
    set_aside: tuple[SetAside, ...]
    z_crit: float
    scale: float
    alpha: float
    relabelled: tuple = ()

    @property
    def modes(self) -> tuple[MeasuredMode, ...]:
        """Every usable mode: the kept ones, then the set-aside ones."""
        return self.kept + tuple(s.mode for s in self.set_aside)

    def to_dict(self) -> dict:
        return {"z_crit": self.z_crit, "scale": self.scale, "alpha": self.alpha,
                "kept": len(self.kept), "set_aside": [s.to_dict() for s in self.set_aside]}


def z_critical(n_modes: int, alpha: float) -> float:
    """Two-sided Bonferroni limit Φ⁻¹(1 − α / (2N)) of N normalised errors."""
    return float(-scipy.special.ndtri(alpha / (2 * max(n_modes, 1))))


def with_sigma(modes, floor_pct: float) -> list[MeasuredMode]:
    """Each mode's frequency uncertainty σ_f (Hz): its estimate's scatter (the stabilization's
    ``uncertainty_hz``) and the floor (``floor_pct`` % of f) combined in quadrature."""
    floor = floor_pct / 100
    return [dataclasses.replace(m, uncertainty_hz=m.frequency_hz * math.hypot(floor, (m.uncertainty_hz or 0.0)
                                                                              / m.frequency_hz)) for m in modes]


def normalised_errors(res: FitResult, modes) -> tuple[np.ndarray, np.ndarray]:
    """The fit's model frequencies (Hz) and normalised errors z = (f_model − f) / σ_f of
    ``modes`` (any modes, fitted or not; NaN model → z = inf)."""
    ns = [m.n for m in modes]
    br = [m.branch for m in modes]
    f = np.array([m.frequency_hz for m in modes])
    fm = model_frequencies(res.parameters, ns, br, res.effects or None, [m.member for m in modes], f)
    sig = np.array([m.uncertainty_hz for m in modes])
    z = np.where(np.isfinite(fm), (fm - f) / sig, np.inf)
    return fm, z


def _center_scale(z: np.ndarray) -> tuple[float, float]:
    fin = z[np.isfinite(z)]
    if fin.size == 0:
        return 0.0, 1.0
    med = float(np.median(fin))
    return med, max(1.0, 1.4826 * float(np.median(np.abs(fin - med))))


def robust_fit(modes, base: TyreParameters, opt: FitOptions, *, alpha: float = 0.01,
               protect=lambda m: False, aside=(), scale: float | None = None) -> RobustFit:
    """Fit ``modes`` (with σ, see :func:`with_sigma`) setting aside the outliers (module docstring).

    Parameters
    ----------
    modes : list of MeasuredMode with ``uncertainty_hz``
    base : TyreParameters — the nominal values (and the start of a local search)
    opt : FitOptions — of the first fit; refits after a mode is set aside search locally
        from the fit before
    alpha : the false-rejection rate per fit of the outlier limit
    protect : callable(MeasuredMode) → bool, modes never set aside (the evidence of a
        candidate, such as its cavity mode)
    aside : modes to set aside from the start (those a closely related fit set aside: they
        come back when this fit puts them inside the limit)
    scale : the spread s to use instead of this fit's own: a candidate model is held to the
        current model's ruler (a fit bad everywhere has a wide spread and would keep every
        mode by it)

    Returns
    -------
    RobustFit
    """
    modes = list(modes)
    N = len(modes)
    k = len(opt.free) + len(opt.effect_free)
    z_crit = z_critical(N, alpha)
    max_out = min((N - 1) // 2, N - (k + 2))
    out: set[int] = {i for i, m in enumerate(modes) if m in set(aside)}
    if len(out) > max_out:
        out = set()
    res = fit([modes[i] for i in range(N) if i not in out], base, opt)
    for _ in range(2 * N):
        fm, z = normalised_errors(res, modes)
        med, s = _center_scale(z)
        new_out = _screen(np.abs(z - med) / (s if scale is None else scale), out, z_crit, max_out,
                          [protect(m) for m in modes])
        if new_out is None:
            break
        out = new_out
        kept = [i for i in range(N) if i not in out]
        # one mode more or less moves the optimum a little: least squares from it; the full
        # search ("global") searches again from it (a gross outlier set aside can move the
        # optimum to another basin, which a polish from the old one never reaches)
        res = fit([modes[i] for i in kept], res.parameters,
                  dataclasses.replace(opt, search="global" if opt.search == "global" else "polish",
                                      start=_start_of(res)))
    fm, z = normalised_errors(res, modes)
    med, s = _center_scale(z)
    s = s if scale is None else scale
    aside = tuple(_set_aside(modes[i], fm[i], z[i], (med, s, z_crit, N, alpha))
                  for i in sorted(out, key=lambda i: modes[i].frequency_hz))
    return RobustFit(fit=res, kept=tuple(modes[i] for i in range(N) if i not in out), set_aside=aside,
                     z_crit=z_crit, scale=s, alpha=alpha)


def _screen(t, out: set, z_crit: float, max_out: int, protected) -> set | None:
    """One step of the screen on the distances ``t`` (in spreads) of every mode's z from
    the median: the set-aside modes after it, or None when nothing changes.

    Set-aside modes back inside the limit come back (when no kept mode is out); else the
    worst kept mode beyond it is set aside, and with it every one at least half as far out
    (gross outliers in one step; one dragged off by them comes back at a later step)."""
    kept = [i for i in range(len(t)) if i not in out]
    back = [i for i in out if np.isfinite(t[i]) and t[i] <= z_crit]
    cand = [i for i in kept if t[i] > z_crit and not protected[i]]
    if back and not cand:
        return out - set(back)
    if not (cand and len(out) < max_out):
        return None
    out = set(out)
    worst = max(t[i] for i in cand)
    for i in sorted(cand, key=lambda i: -t[i]):
        if t[i] >= 0.5 * worst and len(out) < max_out:
            out.add(i)
    return out


def _set_aside(m: MeasuredMode, fm: float, z: float, rule: tuple) -> SetAside:
    """A set-aside mode with its reason; ``rule`` = (median z, spread, limit, N, α)."""
    med, s, z_crit, N, alpha = rule
    err = 100 * (fm / m.frequency_hz - 1) if np.isfinite(fm) else float("nan")
    if not np.isfinite(fm):
        why = f"the model has no n = {m.n} {m.branch} mode"
    else:
        why = (f"the model cannot represent it: {err:+.2f} % off ({abs(z - med) / s:.1f} σ from the other "
               f"modes' errors; limit {z_crit:.1f} σ for {N} modes at α = {alpha:g})")
    return SetAside(m, float(fm), float(err), float(z), why)


def _start_of(res: FitResult) -> dict:
    """The optimum of ``res`` as the start of the next search (names as in FitOptions.free)."""
    out = {}
    for name, v in zip(res.free, res.values):
        out[name] = float(v)
    return out
