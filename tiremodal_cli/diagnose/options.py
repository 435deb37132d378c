"""How a diagnosis is made: its options, and the fit options and start of every refit."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.effects import EFFECTS
from tiremodal_cli.tyre.fit_types import FitOptions, FitResult
from tiremodal_cli.tyre.model import TyreParameters

__all__ = ["PARAMETER_CANDIDATES", "DiagnoseOptions", "cavity_band_hz", "fit_options", "search_start"]


#: Nominal values that may be off: freed one at a time ("a parameter value is off").
PARAMETER_CANDIDATES = ("rhoA", "m_s", "m_w", "b")


@dataclass(frozen=True)
class DiagnoseOptions:
    """How to diagnose (fractions, not per cent, unless the name says so).

    free : parameters of the base fit (and of every candidate's refit)
    noise_floor_pct : floor of each mode's relative frequency uncertainty, %
    alpha : level of the residual χ² test and of the candidates' F-tests
    min_t : smallest |value / standard error| of an adopted effect's parameter (its level,
        2Φ(−min_t), is also that of the joint Wald test of parameters that vanish together)
    max_effects : effects adopted on top of one another at most
    candidates : names of the candidates to try (default: every effect and parameter)
    seed, population, generations, tol : the evolutionary search of every fit
    search : "local" (default): the base fit by the evolutionary search, every refit on
        top of a fitted model by least squares from it, safeguarded by a short evolutionary search
        (:class:`tiremodal_cli.tyre.fit_types.FitOptions`); "global": the full search every time
    speed_of_sound : m/s, for the cavity band c / (2π r_c)
    cavity_radius : (lo, hi) fractions of the tread radius R the cavity's mean radius
        may take (default 0.4 … 1.0)
    rim : "clamped" or "free" when the test's rim channel showed it (``run``), else "from
        parameters"; a rim the data show clamped has no mass or fixture to fit (the
        candidates m_w and rim_fixture are not tried)
    orders_mix : why the modal stage found the test's circumferential orders mixed (its
        ``orders_mix`` note's reason: a lumped asymmetry), or None (they do not, or not
        known: a table of modes); the verdict then says what the test cannot tell apart
        (:func:`~tiremodal_cli.diagnose.identifiability.lumped_mass_note`)
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
    orders_mix: str | None = None

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


def cavity_band_hz(R: float, opt: DiagnoseOptions) -> tuple[float, float]:
    """Frequencies c / (2π r_c) of a cavity whose mean radius is ``cavity_radius`` × R."""
    lo, hi = opt.cavity_radius
    return opt.speed_of_sound / (2 * np.pi * hi * R), opt.speed_of_sound / (2 * np.pi * lo * R)


def fit_options(opt: DiagnoseOptions, **kw) -> FitOptions:
    # the base fit (from the closed-form estimate) and the refits (from the current model)
    # search locally with a short global safeguard unless the options ask for the full
    # search every time
    search = opt.search
    return FitOptions(free=kw.pop("free", opt.free), seed=opt.seed, population=opt.population, weights="uncertainty",
                      generations=opt.generations, tol=opt.tol, error_floor=opt.noise_floor_pct / 100,
                      search=search, **kw)


def search_start(current: FitResult) -> dict:
    """The current optimum as a start of the next search (DE's x0)."""
    out = {k: float(getattr(current.parameters, k)) for k in ("k_r1", "k_r2", "EI", "rhoA", "m_s", "b")}
    if current.parameters.m_w is not None:
        out["m_w"] = float(current.parameters.m_w)
    for e, vals in current.effects.items():
        out.update({f"{e}.{k}": float(v) for k, v in vals.items()})
    return out
