"""Set-aside modes that are a spatial alias of another order, relabelled under the current model."""

from __future__ import annotations

import dataclasses

import numpy as np

from tiremodal_cli.diagnose.refit import refit_robust
from tiremodal_cli.tyre.frequencies import model_frequencies
from tiremodal_cli.tyre.robust import RobustFit

__all__ = ["recheck"]


def recheck(rf: RobustFit, n_points, opt) -> tuple[RobustFit, list[dict]]:
    """Set-aside modes that are a spatial alias of another order, relabelled and fitted
    again; returns the fit (``rf`` itself when nothing was relabelled) and what was."""
    new_modes, changed = _misreads(rf, n_points, opt)
    if not changed:
        return rf, []
    return refit_robust(rf.fit, new_modes, opt), changed


def _misreads(rf: RobustFit, n_points, opt) -> tuple[list, list]:
    """Set-aside modes that are a spatial alias of another order, read under the current model.

    A grid of N points sees order n also as N − n, N + n, …: a set-aside mode is relabelled
    to the alias (either branch) the current model puts within 3 σ of it, if that
    (n, branch) is not measured already. Returns every mode (relabelled) and what was
    relabelled. Without N (a CSV table) nothing is relabelled.
    """
    modes = list(rf.modes)
    if not n_points or not rf.set_aside:
        return modes, []
    current = rf.fit
    taken = {(m.n, m.branch) for m in modes}
    out, changed = list(modes), []
    n_max = max(x.n for x in modes) + n_points
    for a in rf.set_aside:
        m = a.mode
        i = modes.index(m)
        sig = m.uncertainty_hz / m.frequency_hz
        aliases = sorted({k for j in range(0, n_max // n_points + 2) for k in (j * n_points - m.n, j * n_points + m.n)
                          if 0 <= k <= n_max and k != m.n})
        best = None
        for k in aliases:
            for b in ("same", "opposite"):
                if (k, b) in taken:
                    continue
                f = model_frequencies(current.parameters, [k], [b], current.effects or None)[0]
                e = abs(f / m.frequency_hz - 1)
                if np.isfinite(f) and e <= 3 * sig and (best is None or e < best[2]):
                    best = (k, b, e, f)
        if best is not None:
            k, b, _, f = best
            out[i] = dataclasses.replace(m, n=k, branch=b, member=None,
                                         source=f"{m.source} (read as n = {m.n} {m.branch}: a spatial alias)")
            taken.add((k, b))
            changed.append({"frequency_hz": m.frequency_hz, "read_as": {"n": m.n, "branch": m.branch},
                            "relabelled": {"n": k, "branch": b}, "model_hz": float(f),
                            "reason": f"spatial alias on {n_points} points: the model puts n = {k} {b} at "
                                      f"{f:.2f} Hz"})
    # a split pair that lost a member is one mode again
    count = {}
    for m in out:
        if m.member:
            count[(m.n, m.branch)] = count.get((m.n, m.branch), 0) + 1
    out = [dataclasses.replace(m, member=None) if m.member and count[(m.n, m.branch)] < 2 else m for m in out]
    return out, changed
