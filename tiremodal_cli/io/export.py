"""Mode shapes out, in forms other programs animate: UFF 15/82/55 and CSV.

The geometry is one ring of nodes per measured location — tread, sidewall, rim — at the
impact points' angles, on circles of the given radii in the x–y plane (the tyre's plane;
z along the axle). A mode's shape on a ring is the residues that location's sensor saw
over the impact points (the roving hammer measures the tread's shape; a fixed sensor's
residues over the points are that shape scaled by the sensor's own participation, so with
co-located sensors the sidewall ring is the tread shape times the sidewall-to-tread ratio:
the report's polar plots use the same convention). Radial motion u at angle θ is written as
the Cartesian displacement (u cos θ, u sin θ, 0). Each mode is scaled by one complex
factor so that its largest tread value is 1 (a shape, not a mass-normalised vector: the
residues of a roving-hammer test without a driving point at every sensor do not give the
modal mass).

Node numbers: tread 1001…, sidewall 2001…, rim 3001… (+ the point's index in the file);
trace lines close each ring. The nodes are written twice, as UFF 15 and as UFF 2411.

References
----------
Universal File Format datasets 15 (nodes), 82 (trace lines), 55 (data at nodes),
as read and written by pyuff (https://pypi.org/project/pyuff/).
"""

from __future__ import annotations

import csv
import io
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.io.files import check_overwrite, install_dir

__all__ = ["ShapeSet", "shape_set", "uff_datasets", "write_uff", "shapes_csv", "nodes_csv", "RING_BASE",
           "DEFAULT_RADII_M", "FORMATS", "export_folder"]

#: Export formats: "uff" — shapes.uff (UFF 15 + 82 + 55); "csv" — nodes.csv and shapes.csv.
FORMATS = ("uff", "csv")

#: First node number of each ring.
RING_BASE = {"tread": 1000, "sidewall": 2000, "rim": 3000}

#: Radii of the rings when not given (m): the paper's tread radius, the middle of a
#: 16.00R20 sidewall, a 20-inch rim's bead seat.
DEFAULT_RADII_M = {"tread": 0.65, "sidewall": 0.45, "rim": 0.254}


@dataclass(frozen=True)
class ShapeSet:
    """Mode shapes on the rings of nodes.

    Attributes
    ----------
    node : (n_nodes,) int ndarray             node numbers
    ring : tuple of str                       each node's ring
    angle_rad : (n_nodes,) ndarray, rad
    xyz_m : (n_nodes, 3) ndarray, m           node coordinates
    frequency_hz, damping_ratio : (n_modes,) ndarray
    pole : (n_modes,) complex ndarray, rad/s    −ζω + iω√(1 − ζ²) from the table's
        frequency and damping (the estimator's raw pole still holds the exponential
        window's added damping, which the table's damping ratio has had removed)
    label : tuple of str                      "n=3 same" etc.
    radial : (n_modes, n_nodes) complex ndarray   radial shape, largest tread value 1
    left_out : tuple of str                   locations not exported, with the reason
    """

    node: np.ndarray
    ring: tuple
    angle_rad: np.ndarray
    xyz_m: np.ndarray
    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    pole: np.ndarray
    label: tuple
    radial: np.ndarray
    left_out: tuple

    def displacement(self) -> np.ndarray:
        """(n_modes, n_nodes, 3) complex: the radial shape as (x, y, z) displacements."""
        c, s = np.cos(self.angle_rad), np.sin(self.angle_rad)
        return np.stack([self.radial * c, self.radial * s, np.zeros_like(self.radial)], axis=-1)


def shape_set(table, *, radii_m: dict | None = None) -> ShapeSet:
    """Shapes of a modal table on rings of nodes (the module docstring).

    Parameters
    ----------
    table : ModalTable
    radii_m : dict location → radius in m, optional (default :data:`DEFAULT_RADII_M`)

    Returns
    -------
    ShapeSet

    Raises
    ------
    DataFormatError
        When the table has no modes or no tread channel with finite residues.
    """
    radii = {**DEFAULT_RADII_M, **(radii_m or {})}
    if table.n_modes == 0:
        raise DataFormatError("the modal table has no modes to export")
    locs = list(table.channel_location)
    rings, left = [], []
    for loc in ("tread", "sidewall", "rim"):
        if loc not in locs:
            continue
        c = locs.index(loc)
        v = table.shapes[:, c, :]
        if not np.all(np.isfinite(v)) or not np.any(np.abs(v) > 0):
            left.append(f"{loc}: channel {table.channel_name[c]!r} has no usable residues (a dead channel)")
            continue
        rings.append((loc, c))
    if not rings or rings[0][0] != "tread":
        raise DataFormatError("no tread channel with usable residues: the shapes cannot be scaled")
    ang = np.asarray(table.point_angle, dtype=float)
    idx = np.asarray(table.point_index, dtype=int)
    node, ring, angle, xyz, cols = [], [], [], [], []
    for loc, c in rings:
        r = radii[loc]
        node += list(RING_BASE[loc] + 1 + idx)
        ring += [loc] * ang.size
        angle += list(ang)
        xyz += [(r * np.cos(a), r * np.sin(a), 0.0) for a in ang]
        cols.append(table.shapes[:, c, :])
    radial = np.concatenate(cols, axis=1).astype(complex)
    tread = radial[:, :ang.size]
    peak = tread[np.arange(tread.shape[0]), np.argmax(np.abs(tread), axis=1)]
    radial = radial / np.where(peak == 0, 1, peak)[:, None]
    labels = tuple(_label(table, k) for k in range(table.n_modes))
    return ShapeSet(node=np.array(node, dtype=int), ring=tuple(ring), angle_rad=np.array(angle),
                    xyz_m=np.array(xyz, dtype=float), frequency_hz=np.asarray(table.frequency_hz, dtype=float),
                    damping_ratio=np.asarray(table.damping_ratio, dtype=float),
                    pole=_pole(table.frequency_hz, table.damping_ratio), label=labels, radial=radial,
                    left_out=tuple(left))


def _pole(freq_hz, zeta) -> np.ndarray:
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    z = np.asarray(zeta, dtype=float)
    return -z * w + 1j * w * np.sqrt(1 - z**2)


def _label(table, k) -> str:
    n = int(table.n[k])
    b = table.branch[k]
    return f"n={n} {b}" if n >= 0 and b else "unclassified"


def uff_datasets(s: ShapeSet, *, name: str = "tiremodal") -> list[dict]:
    """UFF 15 and 2411 (the nodes, single- and double-precision records: older readers
    know the first, some newer ones only the second, e.g. SDynPy), 82 (one closed trace
    line per ring) and 55 (one complex shape per mode: analysis type 3, complex eigenvalue,
    with the pole as eigenvalue) as pyuff dataset dictionaries."""
    import pyuff  # (imported when used: 20 ms of every start-up otherwise)
    nodes = dict(node_nums=s.node.tolist(), def_cs=[0] * s.node.size, disp_cs=[0] * s.node.size,
                 color=[1] * s.node.size, x=s.xyz_m[:, 0].tolist(), y=s.xyz_m[:, 1].tolist(),
                 z=s.xyz_m[:, 2].tolist())
    out = [pyuff.prepare_15(**nodes), pyuff.prepare_2411(**nodes)]
    for t, loc in enumerate(dict.fromkeys(s.ring), 1):
        nodes = s.node[np.array(s.ring) == loc]
        out.append(pyuff.prepare_82(trace_num=t, n_nodes=nodes.size + 1, color=t, id=f"{loc} ring",
                                    nodes=np.concatenate([nodes, nodes[:1]])))
    d = s.displacement()
    for k in range(s.frequency_hz.size):
        out.append(pyuff.prepare_55(
            id1=f"{name} mode {k + 1}: {s.label[k]}", id2=f"f = {s.frequency_hz[k]:.4f} Hz, "
            f"zeta = {100 * s.damping_ratio[k]:.3f} %", id3="radial shape, largest tread value 1",
            id4="NONE", id5="NONE", model_type=1, analysis_type=3, data_ch=2, spec_data_type=8,
            data_type=5, n_data_per_node=3, r1=d[k, :, 0], r2=d[k, :, 1], r3=d[k, :, 2],
            node_nums=s.node.tolist(), load_case=1, mode_n=k + 1, eig=complex(s.pole[k]),
            modal_a=0j, modal_b=0j))
    return out


def write_uff(path, s: ShapeSet, *, name: str = "tiremodal") -> None:
    """Write :func:`uff_datasets` to one UFF file at ``path`` (which must not exist: the
    caller writes into a temporary name and renames it, see ``files.atomic_path``)."""
    import pyuff  # (imported when used: 20 ms of every start-up otherwise)
    u = pyuff.UFF(str(path))
    for ds in uff_datasets(s, name=name):
        u.write_sets(ds, mode="add")


def nodes_csv(s: ShapeSet) -> str:
    """The geometry as CSV: node, ring, angle_deg, x_m, y_m, z_m."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["node", "ring", "angle_deg", "x_m", "y_m", "z_m"])
    for i in range(s.node.size):
        w.writerow([int(s.node[i]), s.ring[i], f"{np.rad2deg(s.angle_rad[i]):.6g}",
                    *(f"{v:.9g}" for v in s.xyz_m[i])])
    return buf.getvalue()


def shapes_csv(s: ShapeSet) -> str:
    """The shapes as CSV, one row per mode and node: mode, frequency_hz, damping_ratio,
    label, node, ring, radial_re, radial_im."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["mode", "frequency_hz", "damping_ratio", "label", "node", "ring", "radial_re", "radial_im"])
    for k in range(s.frequency_hz.size):
        for i in range(s.node.size):
            v = s.radial[k, i]
            w.writerow([k + 1, f"{s.frequency_hz[k]:.9g}", f"{s.damping_ratio[k]:.6g}", s.label[k],
                        int(s.node[i]), s.ring[i], f"{v.real:.9g}", f"{v.imag:.9g}"])
    return buf.getvalue()


def export_folder(table, outdir, *, fmt: str = "uff", radii_m: dict | None = None, gif: bool = False,
                  name: str = "tiremodal", overwrite: bool = False, progress=None) -> dict:
    """Write a modal table's shapes into the folder ``outdir``, whole or not at all.

    The files are written into a private folder beside ``outdir`` and renamed into place
    when complete (an existing ``outdir`` is replaced only with ``overwrite``).

    Parameters
    ----------
    table : ModalTable
    outdir : path of the folder to create
    fmt : {"uff", "csv"}
    radii_m : ring radii (m), optional
    gif : also ``modes/mode_NN.gif``, each mode moving (:func:`tiremodal_cli.plots.iter_mode_gifs`)
    progress : callable(done, total), optional

    Returns
    -------
    dict : the files written (relative to ``outdir``), the modes, and what was left out.
    """
    if fmt not in FORMATS:
        raise ParameterError(f"format={fmt!r}; allowed: {', '.join(FORMATS)}")
    outdir = Path(outdir)
    check_overwrite(outdir, overwrite)
    s = shape_set(table, radii_m=radii_m)
    outdir.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{outdir.name}.partial.", dir=outdir.parent))
    files = []
    try:
        if fmt == "uff":
            write_uff(tmp / "shapes.uff", s, name=name)
            files.append("shapes.uff")
        else:
            (tmp / "nodes.csv").write_text(nodes_csv(s), encoding="utf-8")
            (tmp / "shapes.csv").write_text(shapes_csv(s), encoding="utf-8")
            files += ["nodes.csv", "shapes.csv"]
        if gif:
            # matplotlib only when GIFs are asked for (start-up time; and io does not import plots at load)
            from tiremodal_cli.plots import iter_mode_gifs

            (tmp / "modes").mkdir()
            for k, gif in enumerate(iter_mode_gifs(s)):
                rel = f"modes/mode_{k + 1:02d}.gif"
                (tmp / rel).write_bytes(gif)
                files.append(rel)
                if progress:
                    progress(k + 1, s.frequency_hz.size)
        install_dir(tmp, outdir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return {"output": str(outdir), "format": fmt, "files": files, "modes": int(s.frequency_hz.size),
            "nodes": int(s.node.size), "rings": list(dict.fromkeys(s.ring)), "left_out": list(s.left_out)}
