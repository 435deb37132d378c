"""What a fit takes and gives: its options (free parameters, bounds, the search) and its
result (values, standard errors, the mode table), and the default search bounds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tiremodal_cli.tyre.model import TyreParameters

__all__ = ['DEFAULT_BOUNDS', 'PAPER_GA', 'FitOptions', 'FitResult']


#: Search bounds of each parameter (SI; see docs/model.md for units).
DEFAULT_BOUNDS = {"k_r1": (1e5, 1e8), "k_r2": (1e5, 1e8), "EI": (0.1, 1e4), "rhoA": (1.0, 200.0),
                  "m_s": (0.5, 200.0), "m_w": (1.0, 1e5), "b": (0.02, 2.0)}


#: The paper's genetic-algorithm settings, mapped onto differential evolution.
PAPER_GA = {"population": 20, "generations": 300, "crossover": 0.7, "mutation": 0.1}


#: How each ``FitOptions.search`` finds the optimum (identify.json's "search.method").
_METHODS = {"global": "differential_evolution + least_squares",
            "local": "least_squares from the start + differential_evolution safeguard",
            "polish": "least_squares from the start"}


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
    search : "global" (differential evolution, then least squares) or "local" (least
        squares from ``start`` — without one, from the closed-form estimate of
        :mod:`tiremodal_cli.tyre.closed_form`, or the global search where it does not
        apply — safeguarded by ``safeguard`` generations of the evolutionary search; the
        base fit and the refits of ``diagnose``) or "polish" (with a ``start``: least
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
    #: where ``start`` came from ("given", or "closed form" when the fit made it)
    start_from: str = "given"


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

    def to_dict(self) -> dict:
        """The fit as JSON-ready data (the keys of ``identify --json`` but the skipped rows
        and the predictions, which :func:`tiremodal_cli.tyre.predict.fit_report` adds)."""
        names = list(self.free)
        o = self.options
        return {
            "parameters": {n: {"value": float(v), "std_error": float(s), "relative_std_error_pct": float(100 * s / v)}
                           for n, v, s in zip(names, self.values, self.std_errors)},
            "all_parameters": self.parameters.to_dict(), "effects": self.effects,
            "correlation": {"names": names, "matrix": np.round(self.correlation, 6).tolist()},
            "undetermined": self.undetermined,
            "rms_error_pct": self.rms_error_pct, "max_error_pct": self.max_error_pct,
            "modes": self.modes,
            "not_followed": [m for m in self.modes if abs(m["error_pct"]) > max(2.0, 2 * self.rms_error_pct)],
            "history": [{"generation": g, "rms_error_pct": 100 * v} for g, v in self.history],
            "search": {"method": _METHODS[o.search], "start": o.start_from if o.start else None, "seed": o.seed,
                       "population": o.population, "generations": o.generations,
                       "crossover": o.crossover, "mutation": o.mutation, "weights": o.weights},
        }
