"""The classical flexible-tread model, fitted beside the paper's coupled model.

The paper compares its coupled model (tread, sidewall mass, rim) with the flexible-tread
model of the literature: the tread, an Euler beam under the inflation tension, on a
plain elastic foundation of stiffness k per length (sidewall and pressure as springs, no
sidewall mass). It has one mode per order,

    ρA ω² = EI n⁴/R⁴ + T n²/R² + k,        T = P0 b R,

and the paper states it holds only to about 180 Hz, where the opposite-direction modes of
the sidewall begin, while the coupled model holds to 300 Hz (Table A1). This module fits
it to the same measured modes as the coupled model so that the claim is a number.

Fitting: the model is linear in (EI, k) once ω is measured, so the start is the linear
least squares of ρA ω² − T n²/R² on (n⁴/R⁴, 1), each row divided by ρA ω² (relative);
the answer is then polished on the relative frequency errors (scipy.optimize.least_squares,
EI and k ≥ 0: a parameter the data drive to zero is reported at its bound). The model's one mode of each order is the tread moving with its
foundation, i.e. the same-direction branch: it is fitted to the same-direction modes, and
its frequency of each order is then set against the opposite-direction modes too. (Fitted
to both branches at once it is a compromise that holds nowhere: 30 % RMS on Table A1.) The
per-branch and per-band errors show where the model stops holding.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.tyre.model import TyreParameters

__all__ = ["FlexibleTreadFit", "flexible_tread_hz", "fit_flexible_tread", "errors_by_branch", "BAND_EDGE_HZ"]

#: The paper's limit of the flexible-tread model (Hz): errors are also reported below and above it.
BAND_EDGE_HZ = 180.0


@dataclass(frozen=True)
class FlexibleTreadFit:
    """A fit of the flexible-tread model.

    Attributes
    ----------
    EI : N·m², k : N/m²                the fitted bending and foundation stiffness
    std_errors : dict name → same unit
    modes : list of dict               n, branch, measured_hz, model_hz, error_pct
    rms_error_pct : float              over all modes
    by_branch : dict                   branch → RMS error %, and "below/above 180 Hz"
    at_bound : tuple of str            parameters the fit drove to zero
    """

    EI: float
    k: float
    std_errors: dict
    modes: list
    rms_error_pct: float
    by_branch: dict
    at_bound: tuple = ()

    def to_dict(self) -> dict:
        return {"model": "flexible tread (Euler beam under tension on an elastic foundation)",
                "parameters": {"EI": {"value": self.EI, "std_error": self.std_errors["EI"], "unit": "N·m²"},
                               "k": {"value": self.k, "std_error": self.std_errors["k"], "unit": "N/m²"}},
                "at_bound": list(self.at_bound), "rms_error_pct": self.rms_error_pct, "by_branch": self.by_branch,
                "modes": self.modes}


def flexible_tread_hz(n, EI: float, k: float, p: TyreParameters) -> np.ndarray:
    """Frequencies (Hz) of the flexible-tread model for orders ``n`` (array-like)."""
    n = np.asarray(n, dtype=float)
    w2 = (EI * n**4 / p.R**4 + p.T * n**2 / p.R**2 + k) / p.rhoA
    return np.sqrt(np.clip(w2, 0, None)) / (2 * np.pi)


def errors_by_branch(rows, *, edge_hz: float = BAND_EDGE_HZ) -> dict:
    """RMS of ``error_pct`` per branch and below/above ``edge_hz`` (rows with n, branch,
    measured_hz, error_pct — identify's and this module's mode tables)."""
    out = {}
    groups = {}
    for r in rows:
        groups.setdefault(r["branch"], []).append(r["error_pct"])
        key = f"below {edge_hz:g} Hz" if r["measured_hz"] < edge_hz else f"above {edge_hz:g} Hz"
        groups.setdefault(key, []).append(r["error_pct"])
    for key, e in groups.items():
        out[key] = {"rms_error_pct": float(np.sqrt(np.mean(np.square(e)))), "n_modes": len(e)}
    return out


def fit_flexible_tread(modes, p: TyreParameters = TyreParameters()) -> FlexibleTreadFit:
    """Fit EI and k of the flexible-tread model to the same-direction modes, and compare its
    frequency of each order with every measured mode.

    Parameters
    ----------
    modes : sequence of MeasuredMode (n, branch, frequency_hz)
    p : TyreParameters   R, b, P0 and ρA are taken as known (as in the coupled fit)

    Returns
    -------
    FlexibleTreadFit   (``modes`` lists every measured mode; each row's ``fitted`` says
        whether it entered the fit)
    """
    fitted = [m for m in modes if m.branch == "same"]
    n = np.array([m.n for m in fitted], dtype=float)
    f = np.array([m.frequency_hz for m in fitted], dtype=float)
    if n.size < 2:
        raise DataFormatError(f"{n.size} same-direction modes: the flexible-tread fit needs at least 2")
    w2 = (2 * np.pi * f) ** 2
    y = (p.rhoA * w2 - p.T * n**2 / p.R**2) / (p.rhoA * w2)
    A = np.stack([n**4 / p.R**4, np.ones_like(n)], axis=1) / (p.rhoA * w2)[:, None]
    start = np.linalg.lstsq(A, y, rcond=None)[0]
    # scales of the two stiffnesses for the search: the paper's EI, and the stiffness that
    # holds the tread's mass at the lowest measured frequency
    scale = np.array([max(abs(start[0]), 1.0), max(abs(start[1]), p.rhoA * w2.min())])
    start = np.clip(start, 0, None)

    def res(x):
        return flexible_tread_hz(n, x[0], x[1], p) / f - 1

    ls = scipy.optimize.least_squares(res, start, bounds=(0, np.inf), x_scale=scale, xtol=1e-12, ftol=1e-12)
    EI, k = ls.x
    r = res(ls.x)
    dof = max(n.size - 2, 1)
    cov = float(r @ r) / dof * np.linalg.pinv(ls.jac.T @ ls.jac)
    se = np.sqrt(np.clip(np.diag(cov), 0, None))
    at_bound = [name for name, v, sc in (("EI", EI, scale[0]), ("k", k, scale[1])) if v <= 1e-9 * sc]
    f_mod = flexible_tread_hz([m.n for m in modes], EI, k, p)
    rows = [{"n": int(m.n), "branch": m.branch, "measured_hz": float(m.frequency_hz), "model_hz": float(fm),
             "error_pct": float(100 * (fm / m.frequency_hz - 1)), "fitted": m.branch == "same"}
            for m, fm in zip(modes, f_mod)]
    err = np.array([x["error_pct"] for x in rows])
    return FlexibleTreadFit(EI=float(EI), k=float(k), std_errors={"EI": float(se[0]), "k": float(se[1])},
                            modes=rows, rms_error_pct=float(np.sqrt(np.mean(err**2))), by_branch=errors_by_branch(rows),
                            at_bound=tuple(at_bound))
