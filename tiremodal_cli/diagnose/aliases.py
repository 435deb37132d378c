"""Aliased orders: set-aside modes that are a spatial alias of another order, relabelled under
the current model (:func:`recheck`), and aliased modes re-read within their alias class by the
base fit (:func:`reread_aliased`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from tiremodal_cli.diagnose.refit import refit_robust
from tiremodal_cli.tyre.frequencies import model_frequencies
from tiremodal_cli.tyre.robust import RobustFit, normalised_errors

__all__ = ["recheck", "reread_aliased", "trimmed_loss"]


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


def reread_aliased(modes, base_params, opt, n_points) -> tuple[list, list[dict]]:
    """Re-read each aliased mode's order within its alias class from the model the
    orders read on the points determine.

    A mode flagged ``aliased`` (its order above the grid's spatial Nyquist order N/2) has
    only its alias class from the points — the orders n' ≡ ±n (mod N) — and its order in
    that class from a dispersion curve (the modal stage's starting model). That order is a
    model's reading, not a measurement: the base model is fitted robustly to the modes
    whose order the points read, and each aliased mode takes the order of its class above
    N/2 (same branch) whose frequency that model puts nearest; when two modes want the same
    order, the nearer keeps it. Without N, or with fewer than k + 2 modes read on the
    points, nothing is re-read.

    Parameters
    ----------
    modes : list of MeasuredMode (with σ) ; base_params : TyreParameters ; opt : DiagnoseOptions
    n_points : int or None — the test's number of equally spaced points N

    Returns
    -------
    (modes, changed) : every mode (re-read ones relabelled; a split pair that lost a member
    is one mode again) and, per re-read mode, {"frequency_hz", "read_as", "relabelled",
    "model_hz", "reason"}
    """
    from tiremodal_cli.diagnose.options import fit_options
    from tiremodal_cli.tyre.robust import robust_fit

    modes = list(modes)
    al = [i for i, m in enumerate(modes) if m.aliased]
    read = [m for m in modes if not m.aliased]
    if not n_points or not al or len(read) < len(opt.free) + 2:
        return modes, []
    rf = robust_fit(read, base_params, fit_options(opt), alpha=opt.alpha)
    wants = {}
    for i in al:
        got = _class_reading(modes[i], rf, n_points)
        if got is not None:
            wants[i] = got
    out, changed = _relabel_wanted(modes, wants, n_points)
    if not changed:
        return modes, []
    return _pairs_whole(out), changed


def _class_reading(m, rf: RobustFit, n_points: int):
    """The order of ``m``'s alias class above N/2 (same branch) that the fit ``rf`` puts nearest
    its frequency, as (order, model Hz, |ln(f_model/f)|) — when it differs from the order read
    and the reading is unambiguous: ``rf``'s outlier screen keeps that order and rejects every
    other order of the class, the one read among them (a flat branch top puts many orders of
    a class at one frequency: no reading there), and every other order lies a whole outlier
    limit z_crit farther from the mode (in the fit's spreads) than the chosen one — a model
    cannot choose between two orders it places closer together than its own misfit (session
    25: the ring's sidewall coupling at seed + 3000, its same n = 19 at 265.6 Hz lifted 25 %
    above the base model's flat top, re-read as n = 87 because the model put n = 87 0.4 Hz
    nearer than n = 19 — just inside the screen, the other just outside; protected in every
    candidate's fit, that label kept sidewall_membrane out). None otherwise."""
    model = rf.fit
    _, z_read = normalised_errors(model, rf.kept)
    med = float(np.median(z_read))
    r, top = m.n % n_points, m.n + 2 * n_points
    cls = sorted({k for j in range(0, top // n_points + 1) for k in (j * n_points + r, j * n_points - r)
                  if n_points / 2 < k <= top})
    if m.n not in cls:
        return None
    fm = model_frequencies(model.parameters, cls, [m.branch] * len(cls), model.effects or None)
    err = np.abs(np.log(np.where(np.isfinite(fm) & (fm > 0), fm, np.inf) / m.frequency_hz))
    j = int(np.argmin(err))
    z = np.where(np.isfinite(fm), (fm - m.frequency_hz) / m.uncertainty_hz, np.inf)
    t = np.abs(z - med) / rf.scale
    inside = t <= rf.z_crit
    if cls[j] != m.n and inside[j] and inside.sum() == 1 and np.sort(t)[1] - t[j] > rf.z_crit:
        return cls[j], float(fm[j]), float(err[j])
    return None


def _relabel_wanted(modes, wants: dict, n_points: int) -> tuple[list, list[dict]]:
    """Relabel each wanted mode (nearest first) unless another mode holds that (n, branch)."""
    taken = {(m.n, m.branch): i for i, m in enumerate(modes) if i not in wants}
    out, changed = list(modes), []
    for i in sorted(wants, key=lambda i: wants[i][2]):
        kk, f, _ = wants[i]
        m = modes[i]
        if (kk, m.branch) in taken:
            continue
        taken[(kk, m.branch)] = i
        out[i] = dataclasses.replace(m, n=kk, member=None,
                                     source=f"{m.source} (read as n = {m.n}: its alias class on {n_points} points "
                                            f"re-read from the model)")
        r = min(m.n % n_points, n_points - m.n % n_points)
        changed.append({"frequency_hz": m.frequency_hz, "read_as": {"n": m.n, "branch": m.branch},
                        "relabelled": {"n": kk, "branch": m.branch}, "model_hz": f,
                        "reason": f"aliased order re-read in its class n ≡ ±{r} (mod {n_points}): the model "
                                  f"fitted to the orders the points read puts n = {kk} {m.branch} at {f:.2f} Hz"})
    return out, changed


def _pairs_whole(modes) -> list:
    """A split pair that lost a member is one mode again."""
    count = {}
    for m in modes:
        if m.member:
            count[(m.n, m.branch)] = count.get((m.n, m.branch), 0) + 1
    return [dataclasses.replace(m, member=None) if m.member and count[(m.n, m.branch)] < 2 else m for m in modes]


def trimmed_loss(rf: RobustFit) -> float:
    """The robust fit's loss over all its modes: Σ min(z², z_crit²), z = (f_model − f)/σ_f —
    a kept mode costs its squared normalised error, a set-aside one the limit's square (the
    skipped loss of the outlier screen). Two readings of the same modes (the same N, the
    same z_crit) are compared by it."""
    _, z = normalised_errors(rf.fit, rf.kept)
    return float(np.sum(np.minimum(z**2, rf.z_crit**2)) + len(rf.set_aside) * rf.z_crit**2)
