"""A grid's missing points read from their mirror images, when the test shows the symmetry that allows it.

A structure with a plane of symmetry through a sensor gives that sensor the same FRF from
two points mirrored about the plane: H_c(θ_c + δ) = H_c(θ_c − δ) (reciprocity and the
symmetry; :mod:`~tiremodal_cli.modal.symmetry`). An axisymmetric tyre has every such plane.
A point whose hits all failed leaves the circumferential grid with a gap, and a gap leaks
every order into every other (:func:`~tiremodal_cli.modal.spatial.leakage`: 9.5 % of each
order's coefficients into each other group on 23 of 24 points), which biases, merges and
mislabels the crowded aliased orders of a one-hit test (``benchmarks/gaps_sweep.py``). When
the test's own mirrored pairs show the symmetry — their antisymmetric part, above the noise,
under :data:`~tiremodal_cli.modal.merge.COPY_MAX_AMPLITUDE` of the symmetric part, the bound
under which the merge already treats the order groups as orthogonal — a missing point's FRF
at channel c is its mirror image's about that channel's angle, and the grid is complete.
A point that is its own mirror (on a sensor's plane, or opposite it) or whose mirror is
missing too stays a gap; a lumped mass or any asymmetry the check sees leaves every gap
as it is (the gappy-grid path, :mod:`~tiremodal_cli.modal.gaps`). The filled points serve the
estimate only: the modal table's shapes, fit errors and syntheses hold the measured points.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.modal.merge import COPY_MAX_AMPLITUDE
from tiremodal_cli.modal.spatial import GRID_TOL_STEPS, grid_points
from tiremodal_cli.modal.symmetry import antisymmetric_share

log = logging.getLogger(__name__)

__all__ = ["mirror_filled"]


def _grid_index(angle: float, first: float, n_grid: int) -> int | None:
    """The grid node (0 … n_grid − 1, counted from ``first``) an angle lies on, or None (also
    for an angle not known: a UFF file's response without geometry has NaN)."""
    if not np.isfinite(angle):
        return None
    x = (angle - first) / (2 * np.pi) * n_grid
    k = int(np.round(x))
    return k % n_grid if abs(x - k) <= GRID_TOL_STEPS else None


def mirror_filled(r, band_hz) -> tuple[object, np.ndarray | None, dict | None]:
    """The FRFResult ``r`` with its grid's missing points filled from their mirror images.

    Parameters
    ----------
    r : FRFResult            points stored in the order of their angles
    band_hz : (lo, hi)       the analysis band, Hz (where the symmetry is measured)

    Returns
    -------
    r_full : FRFResult       ``r`` itself when nothing is filled; else every point, the filled
                             ones in their angle's place (their ``point_index`` −1)
    measured : (n_points_full,) bool or None   the measured points of ``r_full`` (None: nothing filled)
    info : dict or None      what was filled (``filled``: angle, each channel's source point), the
                             gaps left (``gaps_deg``), the measured ``antisymmetric_share`` and
                             the ``reason`` (``meta["mirrored_points"]``); None for a complete grid
    """
    th = np.asarray(r.point_angle, dtype=float)
    n_p = th.size
    n_grid = grid_points(th)
    chan = None if r.channel_angle is None else np.asarray(r.channel_angle, dtype=float)
    if n_grid == n_p or chan is None or chan.size != r.H.shape[0]:
        return r, None, None
    live = np.array([n not in r.dead_channels for n in r.channel_name])
    sel = (r.freq_hz >= band_hz[0]) & (r.freq_hz <= band_hz[1])
    # measured in accelerance, as the stage estimates (a mobility's or receptance's lines near
    # 0 Hz — a free rim's rigid motion and its 1/ω noise — would outweigh the band)
    to_acc = (2j * np.pi * r.freq_hz[sel]) ** (2 - FORM_POWER[r.form])
    share = antisymmetric_share(r.freq_hz[sel], r.H[live][:, :, sel] * to_acc, th, chan[live], r.exp_tau_s)
    node = {_grid_index(a, th[0], n_grid): i for i, a in enumerate(th)}
    missing = [k for k in range(n_grid) if k not in node]
    deg = lambda ks: [float(np.mod(np.round(np.rad2deg(th[0] + 2 * np.pi * k / n_grid), 6), 360.0)) for k in ks]
    if share is None or not share < COPY_MAX_AMPLITUDE:
        why = ("no sensor has mirrored points to measure the symmetry" if share is None else
               f"the test's mirrored points differ: antisymmetric share {share:.3f} ≥ {COPY_MAX_AMPLITUDE:g}")
        return r, None, {"filled": [], "gaps_deg": deg(missing), "antisymmetric_share": share, "reason": why}
    src = {}
    for k in missing:
        a = th[0] + 2 * np.pi * k / n_grid
        mirrors = [_grid_index(2 * c - a, th[0], n_grid) for c in chan]
        if all(m is not None and m != k and m in node for m, ok in zip(mirrors, live) if ok):
            src[k] = [node[m] if ok else node[next(iter(node))] for m, ok in zip(mirrors, live)]
    if not src:
        return r, None, {"filled": [], "gaps_deg": deg(missing), "antisymmetric_share": share,
                         "reason": "every missing point is its own mirror or has its mirror missing"}
    return _with_points(r, th[0], n_grid, node, src, share, deg)


def _with_points(r, first: float, n_grid: int, node: dict, src: dict, share: float, deg):
    """``r`` with the points ``src`` ({grid node: each channel's mirror point}) added in place."""
    nodes = sorted(set(node) | set(src))
    n_c = r.H.shape[0]
    H = np.empty((n_c, len(nodes), r.H.shape[-1]), dtype=r.H.dtype)
    coh = np.empty((n_c, len(nodes), r.coherence.shape[-1]), dtype=r.coherence.dtype)
    take = []  # the point each new point's averages and force autospectrum come from
    for j, k in enumerate(nodes):
        if k in node:
            H[:, j], coh[:, j] = r.H[:, node[k]], r.coherence[:, node[k]]
            take.append(node[k])
        else:
            for c, p in enumerate(src[k]):
                H[c, j], coh[c, j] = r.H[c, p], r.coherence[c, p]
            take.append(src[k][0])
    take = np.array(take)
    measured = np.array([k in node for k in nodes])
    angle = np.array([r.point_angle[node[k]] if k in node else first + 2 * np.pi * k / n_grid for k in nodes])
    index = np.array([r.point_index[node[k]] if k in node else -1 for k in nodes])
    full = dataclasses.replace(r, H=H, coherence=coh, n_averages=r.n_averages[take], point_index=index,
                               point_angle=angle, force_autospectrum=None if r.force_autospectrum is None
                               else r.force_autospectrum[take])
    filled = [{"angle_deg": deg([k])[0],
               "from_points": [int(r.point_index[p]) for p in src[k]]} for k in sorted(src)]
    gaps = [k for k in range(n_grid) if k not in node and k not in src]
    for f in filled:
        log.warning("missing point at %.1f° read from its mirror image about the sensors' plane (point %s): the "
                    "test's mirrored points agree (antisymmetric share %.3f < %g)", f["angle_deg"],
                    ", ".join(str(p + 1) for p in sorted(set(f["from_points"]))), share, COPY_MAX_AMPLITUDE)
    return full, measured, {"filled": filled, "gaps_deg": deg(gaps), "antisymmetric_share": float(share),
                            "reason": "mirror images about each sensor's plane (the test's mirrored points agree)"}
