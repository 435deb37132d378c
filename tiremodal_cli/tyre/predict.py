"""The fitted model's predictions with their uncertainty, and the fit's JSON report.
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.conventions import BRANCHES
from tiremodal_cli.tyre.evaluate import apply_parameters
from tiremodal_cli.tyre.fit_types import FitResult
from tiremodal_cli.tyre.frequencies import model_frequencies

__all__ = ['predict_table', 'fit_report']


def predict_table(res: FitResult, n_max: int, *, measured=()) -> list[dict]:
    """Model frequencies of every (n, branch) up to ``n_max`` with 1σ uncertainty.

    The uncertainty propagates the fit's covariance (in log parameters) through a
    numerical Jacobian of each frequency.
    """
    names = res.free
    logx = np.log(res.values)
    opt = res.options
    base = res.parameters
    ns = np.repeat(np.arange(0, n_max + 1), 2)
    br = np.array(list(BRANCHES) * (n_max + 1))

    def f_of(lx):
        p, eff = apply_parameters(base, opt, names, lx)
        return model_frequencies(p, ns, br, eff or None)

    f0 = f_of(logx)
    J = np.empty((f0.size, logx.size))
    for i in range(logx.size):
        d = np.zeros_like(logx)
        d[i] = 1e-6
        J[:, i] = (f_of(logx + d) - f_of(logx - d)) / 2e-6
    var = np.einsum("ij,jk,ik->i", J, res.covariance_log, J)
    meas = {(m["n"], m["branch"]) for m in measured}
    # a frequency the model cannot differentiate at the fit (a NaN in its Jacobian: the
    # rim-coupled n = 1 root switching branch under the step) has no σ: an explicit null
    return [{"n": int(n), "branch": b, "model_hz": float(f),
             "std_hz": float(np.sqrt(max(v, 0))) if np.isfinite(v) else None,
             **({} if np.isfinite(v) else {"std_reason": "not computable: the model frequency is not "
                                                         "differentiable in the parameters here"}),
             "measured": (int(n), b) in meas} for n, b, f, v in zip(ns, br, f0, var)]


def fit_report(res, skipped, predictions) -> dict:
    """An identification as JSON-ready data (the keys of ``identify --json``):
    :meth:`FitResult.to_dict` with the rows left out and the predictions."""
    d = res.to_dict()
    head = ("parameters", "all_parameters", "effects", "correlation", "undetermined", "rms_error_pct",
            "max_error_pct", "modes", "not_followed")
    return {**{k: d[k] for k in head}, "skipped_rows": skipped, "predictions": predictions,
            "history": d["history"], "search": d["search"]}
