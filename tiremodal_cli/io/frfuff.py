"""FRFs in Universal File Format dataset 58 (ASCII or binary): read and write, through pyuff.

Reading takes the FRFs (function type 4) and their coherences (type 9) of a test exported
by Simcenter Testlab, ME'scope or tiremodal itself, with their units (the ordinate's labels,
else the unit record, dataset 164, else SI as assumed), the sign of each record (a negative
direction code), and the impact points' geometry (a mapping's angles, else dataset 15's
nodes). Writing gives one FRF and one coherence set per live channel and point. The
tiremodal FRF file (HDF5) is :mod:`tiremodal_cli.io.frffile`.
"""

from __future__ import annotations

import datetime
import logging
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tiremodal_cli import __version__
from tiremodal_cli.conventions import FORM_UNITS
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.frf.estimate import FRFResult
from tiremodal_cli.io.files import atomic_path
from tiremodal_cli.io.uffgeometry import node_coordinates, node_geometry, point_angles
from tiremodal_cli.io.uffunits import SPEC_OF_FORM, frf_units

__all__ = ["write_frf_uff", "read_frf_uff", "describe_frf_uff", "is_uff", "uff_function_types"]

log = logging.getLogger(__name__)

#: the fields every dataset 58 that tiremodal writes shares, whatever it holds
_COMMON_58 = dict(
    binary=0, load_case_id=0, rsp_dir=3, ref_ent_name="hammer", ref_dir=3,
    abscissa_spacing=1, abscissa_spec_data_type=18,
    abscissa_len_unit_exp=0, abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0,
    ordinate_len_unit_exp=0, ordinate_force_unit_exp=0, ordinate_temp_unit_exp=0,
    orddenom_len_unit_exp=0, orddenom_force_unit_exp=0, orddenom_temp_unit_exp=0,
    z_axis_spec_data_type=0, z_axis_len_unit_exp=0, z_axis_force_unit_exp=0,
    z_axis_temp_unit_exp=0, z_axis_value=0.0, abscissa_axis_units_lab="Hz",
    z_axis_axis_units_lab="NONE")


def write_frf_uff(path, r: FRFResult, *, point_node0: int = 101, test_name: str = "",
                  overwrite: bool = False) -> Path:
    """Write the FRFs and their coherences as UFF datasets 58, ASCII, through pyuff.

    For every live channel and point: an FRF (function type 4, ordinate in the form's
    unit over N) and its coherence (function type 9, unitless). Response nodes are the
    channels ``1 … n_channels``, reference nodes the points ``point_node0 + point_index``,
    direction +Z (3) for both. ID lines: 1 what (tiremodal version, estimator, form),
    2 which (channel / point), 3 the date written, 4 the test (``test_name``), 5 the
    number of averages. A dead channel is left out, with a warning naming it (logged).

    Parameters
    ----------
    path : path-like
    r : FRFResult
    point_node0 : int
        Node number of the first impact point.
    test_name : str
        Written into ID line 4.
    overwrite : bool

    Returns
    -------
    pathlib.Path
    """
    import pyuff  # (imported when used: 20 ms of every start-up otherwise)
    date = datetime.datetime.now().strftime("%d-%b-%y %H:%M:%S")
    sets = []
    for ic, name in enumerate(r.channel_name):
        if name in r.dead_channels:
            log.warning("channel %r left out of the UFF export %s: it is dead (its records hold only noise)",
                        name, path)
            continue
        for ip in range(r.point_angle.size):
            sets += _frf_and_coherence_sets(r, ic, ip, node0=point_node0, date=date, test_name=test_name)
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.unlink()
        pyuff.UFF(str(tmp)).write_sets(sets, mode="add")
    return Path(path)


def _frf_and_coherence_sets(r: FRFResult, ic: int, ip: int, *, node0: int, date: str, test_name: str) -> list:
    """The two datasets 58 of channel ``ic`` and point ``ip``: the FRF and its coherence."""
    import pyuff  # (imported when used: 20 ms of every start-up otherwise)
    name = r.channel_name[ic]
    common = dict(_COMMON_58, rsp_ent_name=name[:10], rsp_node=ic + 1, ref_node=node0 + int(r.point_index[ip]),
                  abscissa_min=float(r.freq_hz[0]), abscissa_inc=float(r.freq_hz[1] - r.freq_hz[0]),
                  id2=f"{name} / point {int(r.point_index[ip]) + 1}", id3=date, id4=(test_name or "NONE")[:80],
                  id5=f"averages {int(r.n_averages[ip])}", x=r.freq_hz)
    return [pyuff.prepare_58(
                func_type=4, ordinate_spec_data_type=SPEC_OF_FORM[r.form], orddenom_spec_data_type=13,
                ordinate_axis_units_lab=FORM_UNITS[r.form].split("/N")[0], orddenom_axis_units_lab="N",
                id1=f"tiremodal {__version__} {r.estimator} {r.form}", data=r.H[ic, ip].astype(complex), **common),
            pyuff.prepare_58(
                func_type=9, ordinate_spec_data_type=0, orddenom_spec_data_type=0,
                ordinate_axis_units_lab="NONE", orddenom_axis_units_lab="NONE",
                id1=f"tiremodal {__version__} coherence", data=r.coherence[ic, ip].astype(float), **common)]


def _read_sets(paths) -> list[dict]:
    """Every dataset of the UFF files, in order."""
    import pyuff  # (imported when used: 20 ms of every start-up otherwise)
    sets = []
    for p in paths:
        try:
            got = pyuff.UFF(str(p)).read_sets()
        except Exception as exc:  # pyuff raises bare Exception/ValueError/IndexError on bad files
            raise DataFormatError(f"{p}: not a readable UFF file ({exc.__class__.__name__}: {exc})") from None
        sets += [got] if isinstance(got, dict) else list(got)
    return sets


def read_frf_uff(path, *, channels: dict | None = None, points: dict | None = None,
                 require_geometry: bool = False) -> FRFResult:
    """FRFs from UFF dataset 58 (function type 4), e.g. exported by Simcenter Testlab or ME'scope.

    Parameters
    ----------
    path : path-like or sequence of path-like
        UFF file(s), ASCII or binary; every FRF of the test (one file, or one per point).
    channels : ``{"node:dir": (name, location, angle_rad)}``, optional
        A mapping's channels (keyed by the response node and its direction, sign dropped).
    points : ``{"node": angle_rad}``, optional
        A mapping's impact-point angles (keyed by the reference node).
    require_geometry : bool
        Raise DataFormatError when neither the mapping nor a dataset 15 in the files says
        where the points are (``run``); otherwise their angles are NaN (any structure).

    Returns
    -------
    FRFResult
        H (n_channels, n_points, n_freq) in SI (form unit per N), positive outwards;
        coherence from the function-type-9 sets when the file has them (else NaN);
        ``meta["uff"]``: the units found and their factor, where the geometry came from,
        the channels whose sign was flipped, the header (dataset 151) when present.

    Notes
    -----
    * Units: the ordinate's axis labels first (``g``, ``m/s^2``, ``mm/s``, ``mm`` … over
      ``N``, ``kN``, ``lbf``), else the unit record (dataset 164) with the ordinate type's
      dimensions, else SI, stated as assumed (:mod:`tiremodal_cli.io.uffunits`).
    * Direction: a negative direction code (e.g. −3, a sensor mounted pointing −Z) means
      the record's sign is the opposite of the node's axis: the FRF is negated (the product
      of the response's and the reference's signs) so every channel is positive outwards.
    * Geometry: point and sensor angles from the mapping when it gives them, else from the
      nodes of dataset 15 (angles about the circle through the impact points). A channel's
      location from the mapping, else from its response entity name (``tread``,
      ``sidewall``, ``rim``, or ``NAME:…``), else ``tread`` when its node lies on the
      points' circle (within 2 % of its radius), else ``"unknown"``.
    """
    paths = [path] if isinstance(path, (str, os.PathLike)) else list(path)
    where = str(paths[0]) if len(paths) == 1 else f"{paths[0]} (and {len(paths) - 1} more)"
    sets = _read_sets(paths)
    frfs = _frf_sets(sets, where)
    form, to_si, units = frf_units(frfs, next((s for s in sets if s.get("type") == 164), None), where)
    grid = _Grid(rsp=sorted({(int(s["rsp_node"]), abs(int(s["rsp_dir"]))) for s in frfs}),
                 ref=sorted({int(s["ref_node"]) for s in frfs}), x0=np.asarray(frfs[0]["x"], dtype=float))
    H, C, flipped, ent = _fill(sets, grid, to_si, where)
    nodes = node_coordinates(sets)
    geo = node_geometry(nodes, grid.ref, points or {}, where)
    ang, geometry = point_angles(geo, grid.ref, points or {}, require_geometry, where)
    keys = [f"{n}:{d}" for n, d in grid.rsp]
    names, locs, cang = _channels(keys, grid.rsp, ent, geo, channels or {}, grid.ref)
    info = {"files": [str(p) for p in paths], "form": form, **units, "geometry": geometry,
            "sign_flipped": sorted(flipped), "coherence": bool(np.isfinite(C).any()),
            "reference_nodes": grid.ref, "response_dofs": keys, **_header(sets)}
    ref = grid.ref
    return FRFResult(freq_hz=grid.x0, H=H, coherence=C, n_averages=np.zeros(len(ref), int),
                     point_index=np.arange(len(ref)), point_angle=ang, channel_name=tuple(names),
                     channel_location=tuple(locs), channel_angle=np.array(cang, dtype=float), rejections=(),
                     dead_channels=(), estimator="unknown", form=form, exp_tau_s=None, sample_rate=np.nan,
                     n_samples=0, meta={"source": where, "uff": info})


def _header(sets: list[dict]) -> dict:
    """``{"header": {...}}`` from the file's header (dataset 151) when it has one, else ``{}``."""
    header = next((s for s in sets if s.get("type") == 151), None)
    if not header:
        return {}
    return {"header": {k: str(header.get(k, "")).strip() for k in ("model_name", "description", "program")}}


def _frf_sets(sets: list[dict], where: str) -> list[dict]:
    """The FRFs (dataset 58, function type 4); DataFormatError naming what the file holds instead."""
    frfs = [s for s in sets if s.get("type") == 58 and int(s.get("func_type", 0)) == 4]
    if not frfs:
        kinds = sorted({int(s.get("func_type", 0)) for s in sets if s.get("type") == 58})
        raise DataFormatError(f"{where}: no FRF (dataset 58, function type 4)"
                              + (f"; its datasets 58 are of function type {kinds} (1: time records, "
                                 "read by 'tiremodal ingest')" if kinds else ""))
    return frfs


@dataclass(frozen=True)
class _Grid:
    """Where each FRF goes: response dofs (node, |direction|), reference nodes, frequency lines."""

    rsp: list
    ref: list
    x0: np.ndarray


def _sign(direction) -> float:
    return -1.0 if int(direction) < 0 else 1.0


def _fill(sets: list[dict], grid: _Grid, to_si: float, where: str):
    """H (n_rsp, n_ref, n_freq) in SI, positive outwards, and C the coherences (NaN where the
    file has none); the flipped responses ("node:dir") and each response's entity name."""
    rsp, ref, x0 = grid.rsp, grid.ref, grid.x0
    H = np.full((len(rsp), len(ref), x0.size), np.nan + 0j)
    C = np.full(H.shape, np.nan)
    flipped, ent = set(), {}
    for s in sets:
        if s.get("type") != 58 or int(s.get("func_type", 0)) not in (4, 9):
            continue
        key = (int(s["rsp_node"]), abs(int(s["rsp_dir"])))
        if key not in rsp or int(s["ref_node"]) not in ref:
            continue
        x = np.asarray(s["x"], dtype=float)
        if x.shape != x0.shape or not np.allclose(x, x0):
            raise DataFormatError(f"{where}: FRFs have different frequency axes (node {key[0]}, "
                                  f"{x.size} lines from {x[0]:g} Hz; first FRF {x0.size} from {x0[0]:g} Hz)")
        i, j = rsp.index(key), ref.index(int(s["ref_node"]))
        if int(s["func_type"]) == 9:
            C[i, j] = np.real(np.asarray(s["data"]))
            continue
        sg = _sign(s["rsp_dir"]) * _sign(s.get("ref_dir", 3))
        if sg < 0:
            flipped.add(f"{key[0]}:{int(s['rsp_dir'])}")
        H[i, j] = sg * to_si * np.asarray(s["data"], dtype=complex)
        ent.setdefault(key, str(s.get("rsp_ent_name", "")).strip())
    if np.isnan(H).any():
        i, j = np.argwhere(np.isnan(H[..., 0]))[0]
        raise DataFormatError(f"{where}: response {rsp[i][0]}:{rsp[i][1]} has no FRF for reference node {ref[j]}; "
                              "every response needs an FRF for every reference")
    return H, C, flipped, ent


def _channels(keys: list[str], rsp: list, ent: dict, geo: dict, channels: dict, ref: list[int]):
    """Each response's name, location and angle: the mapping's, else read from the file
    (entity name, dataset 15 node); names made unique with their dof when they repeat."""
    r_pts = np.median([geo[n][1] for n in ref]) if geo else np.nan
    names, locs, cang = [], [], []
    for k, (n, d) in zip(keys, rsp):
        if k in channels:
            name, loc, a = channels[k]
        else:
            e = ent.get((n, d), "")
            name = e if e and e.upper() != "NONE" else k
            head = e.split(":")[0].lower()
            if head in ("tread", "sidewall", "rim"):
                loc = head
            elif n in geo and abs(geo[n][1] - r_pts) <= 0.02 * r_pts:
                loc = "tread"
            else:
                loc = "unknown"
            a = geo[n][0] if n in geo else np.nan
        names.append(name), locs.append(loc), cang.append(a)
    if len(set(names)) != len(names):
        names = [f"{nm} ({k})" for nm, k in zip(names, keys)]
    return names, locs, cang


def describe_frf_uff(path) -> dict:
    """What a UFF file of FRFs holds (``tiremodal info``): form and units found, sizes, band,
    channels with their locations, where the geometry comes from, flipped channels."""
    r = read_frf_uff(path)
    u = r.meta["uff"]
    return {"format": "UFF 58 FRFs", "form": r.form, "units": FORM_UNITS[r.form], "unit_in_file": u["unit_in_file"],
            "to_si": u["to_si"], "units_from": u["from"], "n_channels": len(r.channel_name),
            "n_points": int(r.point_angle.size), "n_freq": int(r.freq_hz.size),
            "band_hz": [float(r.freq_hz[0]), float(r.freq_hz[-1])],
            "resolution_hz": float(r.freq_hz[1] - r.freq_hz[0]) if r.freq_hz.size > 1 else None,
            "channels": [f"{n} ({loc}, {k})" for n, loc, k in zip(r.channel_name, r.channel_location,
                                                                  u["response_dofs"])],
            "geometry": u["geometry"], "sign_flipped": u["sign_flipped"], "coherence": u["coherence"],
            **({"header": u["header"]} if "header" in u else {})}


def is_uff(path) -> bool:
    """True for a path named as a UFF file (``*.uff``, ``*.unv``)."""
    return Path(path).suffix.lower() in (".uff", ".unv")



def uff_function_types(paths) -> set[int]:
    """Function types of the datasets 58 in UFF files (1: time records, 4: FRFs, 9: coherence)."""
    return {int(s.get("func_type", 0)) for s in _read_sets(paths) if s.get("type") == 58}
