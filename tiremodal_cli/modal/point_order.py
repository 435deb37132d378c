"""The points of a test taken in the order of their angles (``lsce``'s canonical order).

The modal estimate is a sum over the points (the spatial transform, the principal
responses, the sweeps' normal matrices): stored in another order — from point 11 on, or in
decreasing angle — its floating-point sums differ in the last digits, and a mode at a
threshold's edge (a significance, a crowd's order confidence) can fall either way. The
stage therefore takes the points in the order of their angles and gives every output back
in the stored order: every storage gives the same numbers to the bit.
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["angle_order", "frf_points_taken", "result_points_taken", "table_points_taken", "stored_order"]


def angle_order(point_angle) -> np.ndarray | None:
    """(n_points,) the points' order by angle in [0, 2π) (stable), or None when they are
    stored so (or have fewer than two finite angles)."""
    a = np.mod(np.asarray(point_angle, dtype=float), 2 * np.pi)
    if a.size < 2 or not np.all(np.isfinite(a)):
        return None
    order = np.argsort(a, kind="stable")
    return None if np.array_equal(order, np.arange(a.size)) else order


def frf_points_taken(r, idx):
    """The FRFResult ``r`` with its points taken in the order ``idx``."""
    return dataclasses.replace(r, H=r.H[:, idx], coherence=r.coherence[:, idx], n_averages=r.n_averages[idx],
                               point_index=r.point_index[idx], point_angle=r.point_angle[idx],
                               force_autospectrum=None if r.force_autospectrum is None else r.force_autospectrum[idx])


def result_points_taken(res, idx):
    """A ModalResult with its point axis (shapes, fit error, synthesis) taken in the order ``idx``."""
    return dataclasses.replace(res, shapes=res.shapes[:, :, idx], fit_error=res.fit_error[:, idx],
                               synthesis=res.synthesis[:, idx])


def table_points_taken(t, idx):
    """A ModalTable with its point axis (shapes, fit error, angles, indices, synthesis) taken
    in the order ``idx``."""
    return dataclasses.replace(t, shapes=t.shapes[:, :, idx], fit_error=t.fit_error[:, idx],
                               point_angle=t.point_angle[idx], point_index=t.point_index[idx],
                               synthesis=None if t.synthesis is None else t.synthesis[:, idx])


def stored_order(table_and_result, order):
    """(ModalTable, ModalResult) estimated with the points taken in ``order``, given back in
    the stored order."""
    table, res = table_and_result
    inv = np.argsort(order)
    return table_points_taken(table, inv), result_points_taken(res, inv)
