"""Parameter sensitivity of the tyre model's frequencies.

Two views of one question, as in the paper's Section 5 (Tables 4–9, Figs. 13–14):

* **single-variable study**: each parameter at 80 %, 100 % and 120 % of its value, the
  others fixed, and the frequencies of every (n, branch);
* **normalised sensitivity coefficients** S = ∂ln f / ∂ln p per mode and parameter (central
  differences of ±0.1 % in p): a 1 % change of p moves f by S %.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from tiremodal_cli.conventions import BRANCHES
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.frequencies import model_frequencies
from tiremodal_cli.tyre.model import TyreParameters

__all__ = ["PAPER_STUDY", "single_variable", "coefficients"]

#: The parameters of the paper's Tables 4–9, in its order.
PAPER_STUDY = ("EI", "rhoA", "b", "m_s", "k_r1", "k_r2")


def _modes(n_max):
    ns = np.repeat(np.arange(1, n_max + 1), 2)
    br = np.array(list(BRANCHES) * n_max)
    return ns, br


def _check(p, names):
    bad = [n for n in names if n not in TyreParameters.UNITS or (n == "m_w" and p.m_w is None)]
    if bad:
        raise ParameterError(f"no sensitivity to {bad[0]!r}; allowed: "
                             f"{', '.join(k for k in TyreParameters.UNITS if k != 'm_w' or p.m_w is not None)}")


def single_variable(p: TyreParameters, names=PAPER_STUDY, factors=(0.8, 1.0, 1.2), n_max: int = 10,
                    effects=None) -> list[dict]:
    """Frequencies of n = 1 … n_max, both branches, with each parameter scaled by each factor.

    Returns rows {parameter, factor, n, branch, frequency_hz, change_pct}.
    """
    _check(p, names)
    ns, br = _modes(n_max)
    f0 = model_frequencies(p, ns, br, effects)
    rows = []
    for name in names:
        for fac in factors:
            q = dataclasses.replace(p, **{name: getattr(p, name) * fac})
            f = model_frequencies(q, ns, br, effects)
            rows += [{"parameter": name, "factor": float(fac), "n": int(n), "branch": b, "frequency_hz": float(x),
                      "change_pct": float(100 * (x / x0 - 1))} for n, b, x, x0 in zip(ns, br, f, f0)]
    return rows


def coefficients(p: TyreParameters, names=PAPER_STUDY, n_max: int = 10, effects=None, *, ns=None, branches=None):
    """Normalised sensitivities ∂ln f/∂ln p.

    Returns
    -------
    ns, branches : (n_modes,) arrays ; S : (n_modes, len(names)) ndarray
    """
    _check(p, names)
    if ns is None:
        ns, branches = _modes(n_max)
    ns, branches = np.asarray(ns), np.asarray(branches)
    S = np.empty((ns.size, len(names)))
    h = 1e-3
    for j, name in enumerate(names):
        v = getattr(p, name)
        up = model_frequencies(dataclasses.replace(p, **{name: v * (1 + h)}), ns, branches, effects)
        dn = model_frequencies(dataclasses.replace(p, **{name: v * (1 - h)}), ns, branches, effects)
        S[:, j] = (np.log(up) - np.log(dn)) / (np.log(1 + h) - np.log(1 - h))
    return ns, branches, S
