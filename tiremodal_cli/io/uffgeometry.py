"""Where a UFF file's impact points and sensors are: angles about the tyre's axis.

From a mapping's ``[points]`` angles when it gives them, else from the nodes of the
geometry datasets (15, 2411): the impact points lie on a circle in a coordinate plane, and
every node's angle is taken about that circle's centre (Kåsa's algebraic fit). Points
written from a uniform grid are put back on it (:data:`GRID_TOLERANCE_RAD`).
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.errors import DataFormatError

__all__ = ["GRID_TOLERANCE_RAD", "node_coordinates", "node_geometry", "point_angles", "snap_to_uniform_grid"]


def node_coordinates(sets: list[dict]) -> dict:
    """``{node: [x, y, z]}`` from the geometry datasets (15, 2411)."""
    nodes = {}
    for s in sets:
        if s.get("type") in (15, 2411):
            for n, *p in zip(s["node_nums"], s["x"], s["y"], s["z"]):
                nodes[int(n)] = p
    return nodes


def node_geometry(nodes: dict, ref: list[int], points: dict, where: str) -> dict:
    """:func:`_circle_geometry` of the nodes when they place every impact point; ``{}`` when they
    do not, or when their geometry is odd and the mapping places the points anyway."""
    if not (nodes and all(n in nodes for n in ref) and len(ref) >= 3):
        return {}
    try:
        return _circle_geometry(nodes, ref, where)
    except DataFormatError:
        if not _mapping_has_points(points, ref):
            raise
        return {}  # the mapping places the points; the file's odd geometry is not needed


def _mapping_has_points(points: dict, ref: list[int]) -> bool:
    return bool(points) and all(str(n) in points for n in ref)


def point_angles(geo: dict, ref: list[int], points: dict, require_geometry: bool, where: str):
    """The impact points' angles (rad) and where they came from: the mapping, else dataset 15."""
    if _mapping_has_points(points, ref):
        return np.array([points[str(n)] for n in ref], dtype=float), "the mapping's [points]"
    if geo:
        return np.array([geo[n][0] for n in ref]), "the nodes of dataset 15"
    if require_geometry:
        raise DataFormatError(f"{where}: nothing says where the impact points are (reference nodes "
                              f"{ref[0]}…{ref[-1]}): the file has no dataset 15 with their nodes and no mapping "
                              "gives their angles; allowed: a UFF 15 geometry in the file, or --mapping with [points]")
    return np.full(len(ref), np.nan), "none (angles unknown)"


def _circle_geometry(nodes: dict, ref: list[int], where: str) -> dict[int, tuple[float, float]]:
    """``{node: (angle_rad, radius_m)}`` from dataset 15 coordinates, for a tyre whose impact
    points lie on a circle in a coordinate plane (the axis is the coordinate along which the
    points do not spread); angles about the circle's centre, in the plane's right-handed sense."""
    xyz = np.array([nodes[n] for n in ref], dtype=float)
    spread = np.ptp(xyz, axis=0)
    axis = int(np.argmin(spread))
    if spread[axis] > 1e-3 * spread.max():
        raise DataFormatError(f"{where}: the impact points' nodes (dataset 15) do not lie in one coordinate "
                              f"plane (spread x, y, z = {', '.join(f'{v:.3g}' for v in spread)}); "
                              "allowed: a tyre in the XY, YZ or ZX plane, or a mapping's [points] angles")
    u, v = [(1, 2), (2, 0), (0, 1)][axis]
    # circle through the points (Kåsa's algebraic fit): x² + y² = 2ax + 2by + c
    A = np.column_stack([2 * xyz[:, u], 2 * xyz[:, v], np.ones(len(ref))])
    (a, b, _), *_ = np.linalg.lstsq(A, xyz[:, u] ** 2 + xyz[:, v] ** 2, rcond=None)
    out = {}
    for n, p in nodes.items():
        du, dv = p[u] - a, p[v] - b
        out[n] = (float(np.arctan2(dv, du)), float(np.hypot(du, dv)))
    return snap_to_uniform_grid(out, ref)


#: Largest angle error (rad) of a point written to dataset 15's six significant digits: half a
#: unit in the sixth digit (5e-6 of a coordinate ≲ the radius) on each of two coordinates,
#: √2 · 5e-6, with a factor 10 for the centre's fit. Points marked by hand on a tyre are off a
#: uniform grid by a millimetre or more (1.5e-3 rad at 0.65 m): they are never taken for one.
GRID_TOLERANCE_RAD = 10 * np.sqrt(2) * 5e-6


def snap_to_uniform_grid(out: dict, ref: list[int]) -> dict:
    """The impact points' angles put exactly on the uniform grid they were written from, when
    every one lies within :data:`GRID_TOLERANCE_RAD` of it (dataset 15 keeps six digits: the
    modal stage's reading of the order N/2, sampled at its zeros, turns on 1e-7 rad)."""
    N = len(ref)
    if N < 3:
        return out
    th = np.array([out[n][0] for n in ref])
    step = np.angle(np.exp(1j * np.diff(th)))
    d = 2 * np.pi / N * np.sign(np.median(step))
    k = np.arange(N)
    theta0 = float(np.angle(np.mean(np.exp(1j * (th - k * d)))))
    grid = theta0 + k * d
    if np.max(np.abs(np.angle(np.exp(1j * (th - grid))))) > GRID_TOLERANCE_RAD:
        return out
    out = dict(out)
    for n, g in zip(ref, grid):
        out[n] = (float(np.angle(np.exp(1j * g))), out[n][1])
    return out
