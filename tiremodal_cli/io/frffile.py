"""The FRF file (``tiremodal.frf``, version 1) and its UFF 58 export.

HDF5 layout (``docs/format.md``): root attributes ``format``, ``format_version``,
``estimator``, ``form``, ``sample_rate``, ``n_samples``, ``exp_tau_s`` (absent: no
exponential window), ``tiremodal_version``, ``input_file``, ``input_sha256``, ``meta``
(JSON), ``rejections`` (JSON list); datasets ``freq_hz`` (n_freq,), ``frf``
(n_channels, n_points, n_freq) complex128, ``coherence`` (same shape, float64),
``n_averages`` and ``point_index`` (n_points,), ``point_angle`` (n_points,) rad,
``channel_name``, ``channel_location`` (n_channels,) str, ``channel_angle`` (n_channels,) rad,
``dead_channels`` (str).
"""

from __future__ import annotations

import json
import re
import os
from pathlib import Path

import h5py
import numpy as np
import pyuff

from tiremodal_cli import __version__
from tiremodal_cli.conventions import FORM_UNITS
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import atomic_path
from tiremodal_cli.frf.estimate import FRFResult, Rejection
from tiremodal_cli.io.measurement import attr_str, open_hdf5, read_strings

__all__ = ["FORMAT_NAME", "write_frf", "read_frf", "write_frf_uff", "read_frf_uff", "describe_frf", "describe_frf_uff",
           "is_uff", "UNITS", "RESPONSE_UNITS", "FORCE_UNITS"]

FORMAT_NAME = "tiremodal.frf"
FORMAT_VERSION = 1
UNITS = FORM_UNITS
_SPEC = {"accelerance": 12, "mobility": 11, "receptance": 8}  # UFF specific data types


def write_frf(path, r: FRFResult, *, input_file: str = "", input_sha256: str = "",
              overwrite: bool = False) -> Path:
    """Write an FRF file (layout in the module docstring) atomically.

    Parameters
    ----------
    path : path-like
    r : FRFResult
    input_file, input_sha256 : str
        What the FRFs were estimated from (recorded as provenance).
    overwrite : bool
        Replace an existing file (else OutputExistsError).

    Returns
    -------
    pathlib.Path
    """
    s = h5py.string_dtype("utf-8")
    with atomic_path(path, overwrite=overwrite) as tmp:
        with h5py.File(tmp, "w") as h:
            a = h.attrs
            a["format"], a["format_version"] = FORMAT_NAME, FORMAT_VERSION
            a["estimator"], a["form"], a["units"] = r.estimator, r.form, UNITS[r.form]
            a["sample_rate"], a["n_samples"] = r.sample_rate, r.n_samples
            if r.exp_tau_s is not None:
                a["exp_tau_s"] = r.exp_tau_s
            a["tiremodal_version"] = __version__
            a["input_file"], a["input_sha256"] = str(input_file), input_sha256
            a["meta"] = json.dumps(r.meta)
            a["rejections"] = json.dumps([x.to_dict() for x in r.rejections])
            h.create_dataset("freq_hz", data=r.freq_hz)
            h.create_dataset("frf", data=r.H.astype(np.complex128))
            h.create_dataset("coherence", data=r.coherence)
            h.create_dataset("n_averages", data=r.n_averages)
            h.create_dataset("point_index", data=r.point_index)
            h.create_dataset("point_angle", data=r.point_angle)
            h.create_dataset("channel_name", data=list(r.channel_name), dtype=s)
            h.create_dataset("channel_location", data=list(r.channel_location), dtype=s)
            h.create_dataset("channel_angle", data=r.channel_angle)
            h.create_dataset("dead_channels", data=list(r.dead_channels), dtype=s)
    return Path(path)


def read_frf(path) -> FRFResult:
    """Read an FRF file written by :func:`write_frf`.

    Parameters
    ----------
    path : path-like

    Returns
    -------
    FRFResult
        H (n_channels, n_points, n_freq) complex in the form's SI unit per N, coherence,
        geometry (rad), rejections and provenance.

    Raises
    ------
    DataFormatError
        Not an FRF file, an unknown version, a missing dataset or sizes that do not match.
    """
    where = str(path)
    with open_hdf5(path) as h:
        fmt = attr_str(h.attrs, "format")
        if fmt != FORMAT_NAME:
            raise DataFormatError(f"{where}: format={fmt!r} is not an FRF file; expected {FORMAT_NAME!r}")
        if int(h.attrs.get("format_version", -1)) != FORMAT_VERSION:
            raise DataFormatError(f"{where}: unknown format_version {h.attrs.get('format_version')!r}")
        need = ("freq_hz", "frf", "coherence", "n_averages", "point_index", "point_angle",
                "channel_name", "channel_location", "channel_angle", "dead_channels")
        for k in need:
            if k not in h:
                raise DataFormatError(f"{where}: dataset {k!r} is missing")
        try:
            d = {k: h[k][()] for k in need if k not in ("channel_name", "channel_location", "dead_channels")}
            names, locs, dead = (read_strings(h[k]) for k in ("channel_name", "channel_location", "dead_channels"))
            a = dict(h.attrs)
        except (OSError, ValueError, TypeError) as exc:
            raise DataFormatError(f"{where}: cannot read ({exc}); the file may be truncated") from None
    H = d["frf"]
    n_c, n_p, n_f = (H.shape + (0, 0, 0))[:3] if H.ndim == 3 else (0, 0, 0)
    if H.ndim != 3 or d["freq_hz"].shape != (n_f,) or d["coherence"].shape != H.shape \
            or len(names) != n_c or d["point_angle"].shape != (n_p,):
        raise DataFormatError(f"{where}: sizes do not match (frf {H.shape}, freq_hz {d['freq_hz'].shape}, "
                              f"{len(names)} channels, {d['point_angle'].shape[0]} points)")
    rej = tuple(Rejection(**x) for x in json.loads(_s(a.get("rejections", "[]"))))
    tau = a.get("exp_tau_s")
    return FRFResult(freq_hz=d["freq_hz"], H=H, coherence=d["coherence"], n_averages=d["n_averages"],
                     point_index=d["point_index"], point_angle=d["point_angle"], channel_name=names,
                     channel_location=locs, channel_angle=d["channel_angle"], rejections=rej,
                     dead_channels=dead, estimator=_s(a.get("estimator", "H1")),
                     form=_s(a.get("form", "accelerance")), exp_tau_s=None if tau is None else float(tau),
                     sample_rate=float(a.get("sample_rate", np.nan)), n_samples=int(a.get("n_samples", 0)),
                     meta=json.loads(_s(a.get("meta", "{}"))))


def _s(v):
    return v.decode() if isinstance(v, bytes) else str(v)


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
    import datetime
    import logging

    from tiremodal_cli import __version__

    date = datetime.datetime.now().strftime("%d-%b-%y %H:%M:%S")
    sets = []
    for ic, name in enumerate(r.channel_name):
        if name in r.dead_channels:
            logging.getLogger(__name__).warning(
                "channel %r left out of the UFF export %s: it is dead (its records hold only noise)", name, path)
            continue
        for ip in range(r.point_angle.size):
            common = dict(
                binary=0, load_case_id=0, rsp_ent_name=name[:10], rsp_node=ic + 1, rsp_dir=3,
                ref_ent_name="hammer", ref_node=point_node0 + int(r.point_index[ip]), ref_dir=3,
                abscissa_spacing=1, abscissa_min=float(r.freq_hz[0]),
                abscissa_inc=float(r.freq_hz[1] - r.freq_hz[0]), abscissa_spec_data_type=18,
                abscissa_len_unit_exp=0, abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0,
                ordinate_len_unit_exp=0, ordinate_force_unit_exp=0, ordinate_temp_unit_exp=0,
                orddenom_len_unit_exp=0, orddenom_force_unit_exp=0, orddenom_temp_unit_exp=0,
                z_axis_spec_data_type=0, z_axis_len_unit_exp=0, z_axis_force_unit_exp=0,
                z_axis_temp_unit_exp=0, z_axis_value=0.0, abscissa_axis_units_lab="Hz",
                z_axis_axis_units_lab="NONE", id2=f"{name} / point {int(r.point_index[ip]) + 1}",
                id3=date, id4=(test_name or "NONE")[:80],
                id5=f"averages {int(r.n_averages[ip])}",
                x=r.freq_hz)
            sets.append(pyuff.prepare_58(
                func_type=4, ordinate_spec_data_type=_SPEC[r.form], orddenom_spec_data_type=13,
                ordinate_axis_units_lab=UNITS[r.form].split("/N")[0], orddenom_axis_units_lab="N",
                id1=f"tiremodal {__version__} {r.estimator} {r.form}", data=r.H[ic, ip].astype(complex), **common))
            sets.append(pyuff.prepare_58(
                func_type=9, ordinate_spec_data_type=0, orddenom_spec_data_type=0,
                ordinate_axis_units_lab="NONE", orddenom_axis_units_lab="NONE",
                id1=f"tiremodal {__version__} coherence", data=r.coherence[ic, ip].astype(float), **common))
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.unlink()
        pyuff.UFF(str(tmp)).write_sets(sets, mode="add")
    return Path(path)


def describe_frf(path: str | os.PathLike) -> dict:
    r = read_frf(path)
    with open_hdf5(path) as h:
        src = {k: _s(h.attrs[k]) for k in ("input_file", "input_sha256", "tiremodal_version") if k in h.attrs}
    return {"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "estimator": r.estimator, "form": r.form,
            "units": UNITS[r.form], "n_channels": len(r.channel_name), "n_points": int(r.point_angle.size),
            "n_freq": int(r.freq_hz.size), "band_hz": [float(r.freq_hz[0]), float(r.freq_hz[-1])],
            "resolution_hz": float(r.freq_hz[1] - r.freq_hz[0]) if r.freq_hz.size > 1 else None,
            "channels": list(r.channel_name), "dead_channels": list(r.dead_channels),
            "n_averages_min": int(r.n_averages.min()), "n_rejections": len(r.rejections),
            "exp_tau_s": r.exp_tau_s, **src}


_FORM_OF_SPEC = {12: "accelerance", 11: "mobility", 8: "receptance"}
_G = 9.80665  # standard gravity, m/s² (ISO 80000-3)
#: response units a UFF file may name (lower case, spaces removed) → (form, factor to SI)
RESPONSE_UNITS = {
    "g": ("accelerance", _G), "m/s^2": ("accelerance", 1.0), "mm/s^2": ("accelerance", 1e-3),
    "cm/s^2": ("accelerance", 1e-2), "in/s^2": ("accelerance", 0.0254), "ft/s^2": ("accelerance", 0.3048),
    "m/s": ("mobility", 1.0), "mm/s": ("mobility", 1e-3), "cm/s": ("mobility", 1e-2), "in/s": ("mobility", 0.0254),
    "m": ("receptance", 1.0), "mm": ("receptance", 1e-3), "µm": ("receptance", 1e-6), "um": ("receptance", 1e-6),
    "cm": ("receptance", 1e-2), "in": ("receptance", 0.0254),
}
#: force units a UFF file may name → factor to N
FORCE_UNITS = {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605}
#: length dimension of each form's response (time is always in seconds in UFF)
_FORM_LENGTH = {"accelerance": 1, "mobility": 1, "receptance": 1}


def _norm_unit(label) -> str:
    u = "".join(str(label or "").split()).replace("**", "^").replace("²", "^2").replace("µ", "u").lower()
    u = re.sub(r"/s2(?=$|/)", "/s^2", u)
    return "" if u in ("", "none", "unknown", "-") else u


def _units(frfs: list, units164: dict | None, where: str) -> tuple[str, float, dict]:
    """The FRFs' form and the factor that takes them to SI (form unit per N), and how it was found.

    Order: the ordinate's axis labels (records 9/10 of dataset 58: e.g. ``g`` over ``N``, or
    ``m/s^2/N`` in one label), else the file's unit record (dataset 164: its length and
    force factors, with the ordinate type's dimensions), else SI (stated as assumed).
    """
    spec = {int(s.get("ordinate_spec_data_type", 0) or 0) for s in frfs}
    if len(spec) != 1:
        raise DataFormatError(f"{where}: FRFs of different ordinate types {sorted(spec)}; one test has one form")
    spec = spec.pop()
    if spec and spec not in _FORM_OF_SPEC:
        raise DataFormatError(f"{where}: ordinate type {spec}; allowed: 12 (acceleration), 11 (velocity), "
                              "8 (displacement)")
    labels = {(_norm_unit(s.get("ordinate_axis_units_lab")), _norm_unit(s.get("orddenom_axis_units_lab")))
              for s in frfs}
    if len(labels) != 1:
        raise DataFormatError(f"{where}: FRFs in different units {sorted(labels)}; one test has one unit")
    num, den = labels.pop()
    for f in FORCE_UNITS:  # "g/N" or "m/s^2/N" in the ordinate label alone
        if not den and num.endswith("/" + f) and num[: -len(f) - 1] in RESPONSE_UNITS:
            num, den = num[: -len(f) - 1], f
    if num:
        if num not in RESPONSE_UNITS:
            raise DataFormatError(f"{where}: response unit {num!r} is not one tiremodal knows; known: "
                                  f"{', '.join(RESPONSE_UNITS)}")
        form, k = RESPONSE_UNITS[num]
        if spec and form != _FORM_OF_SPEC[spec]:
            raise DataFormatError(f"{where}: response unit {num!r} is a {form} unit but the ordinate type "
                                  f"{spec} says {_FORM_OF_SPEC[spec]}")
        if den and den not in FORCE_UNITS:
            raise DataFormatError(f"{where}: force unit {den!r} is not one tiremodal knows; known: N, kN, lbf")
        kf = FORCE_UNITS.get(den or "n")
        raw = [str(frfs[0].get(k) or "").strip() for k in ("ordinate_axis_units_lab", "orddenom_axis_units_lab")]
        how = f"the ordinate axis labels ({raw[0]!r} over {raw[1] or 'N, assumed'!r})"
        unit = f"{num}/{den or 'n'}".replace("/n", "/N").replace("/kn", "/kN")
        return form, k / kf, {"unit_in_file": unit, "to_si": k / kf, "from": how}
    if not spec:
        raise DataFormatError(f"{where}: the FRFs say neither their ordinate type (12, 11, 8) nor their unit; "
                              "allowed: an ordinate type or a unit label such as g, m/s^2, mm/s")
    form = _FORM_OF_SPEC[spec]
    if units164:
        try:
            lf, ff = float(units164.get("length")), float(units164.get("force"))
        except (TypeError, ValueError):
            raise DataFormatError(f"{where}: unit record (dataset 164) without length and force factors") from None
        if not (lf > 0 and ff > 0):
            raise DataFormatError(f"{where}: unit record (dataset 164) has factors {lf:g}, {ff:g}; allowed: > 0")
        k = ff / lf ** _FORM_LENGTH[form]  # file units → SI: divide by the factor (dataset 164's rule)
        desc = str(units164.get("units_description", "")).strip() or f"code {units164.get('units_code')}"
        return form, k, {"unit_in_file": desc, "to_si": k,
                         "from": f"the unit record (dataset 164: length factor {lf:g}, force factor {ff:g})"}
    return form, 1.0, {"unit_in_file": UNITS[form], "to_si": 1.0,
                       "from": "assumed SI: the file names no unit (no ordinate label, no dataset 164)"}


def _geometry(nodes: dict, ref: list[int], where: str) -> dict[int, tuple[float, float]]:
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
    return _uniform_grid(out, ref)


#: Largest angle error (rad) of a point written to dataset 15's six significant digits: half a
#: unit in the sixth digit (5e-6 of a coordinate ≲ the radius) on each of two coordinates,
#: √2 · 5e-6, with a factor 10 for the centre's fit. Points marked by hand on a tyre are off a
#: uniform grid by a millimetre or more (1.5e-3 rad at 0.65 m): they are never taken for one.
GRID_TOLERANCE_RAD = 10 * np.sqrt(2) * 5e-6


def _uniform_grid(out: dict, ref: list[int]) -> dict:
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
      dimensions, else SI, stated as assumed (:data:`RESPONSE_UNITS`, :data:`FORCE_UNITS`).
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
    sets = []
    for p in paths:
        try:
            got = pyuff.UFF(str(p)).read_sets()
        except Exception as exc:  # pyuff raises bare Exception/ValueError/IndexError on bad files
            raise DataFormatError(f"{p}: not a readable UFF file ({exc.__class__.__name__}: {exc})") from None
        sets += [got] if isinstance(got, dict) else list(got)
    frfs = [s for s in sets if s.get("type") == 58 and int(s.get("func_type", 0)) == 4]
    if not frfs:
        kinds = sorted({int(s.get("func_type", 0)) for s in sets if s.get("type") == 58})
        raise DataFormatError(f"{where}: no FRF (dataset 58, function type 4)"
                              + (f"; its datasets 58 are of function type {kinds} (1: time records, "
                                 "read by 'tiremodal ingest')" if kinds else ""))
    units164 = next((s for s in sets if s.get("type") == 164), None)
    form, to_si, units = _units(frfs, units164, where)
    x0 = np.asarray(frfs[0]["x"], dtype=float)

    def sign(d):
        return -1.0 if int(d) < 0 else 1.0

    rsp = sorted({(int(s["rsp_node"]), abs(int(s["rsp_dir"]))) for s in frfs})
    ref = sorted({int(s["ref_node"]) for s in frfs})
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
        sg = sign(s["rsp_dir"]) * sign(s.get("ref_dir", 3))
        if sg < 0:
            flipped.add(f"{key[0]}:{int(s['rsp_dir'])}")
        H[i, j] = sg * to_si * np.asarray(s["data"], dtype=complex)
        ent.setdefault(key, str(s.get("rsp_ent_name", "")).strip())
    if np.isnan(H).any():
        i, j = np.argwhere(np.isnan(H[..., 0]))[0]
        raise DataFormatError(f"{where}: response {rsp[i][0]}:{rsp[i][1]} has no FRF for reference node {ref[j]}; "
                              "every response needs an FRF for every reference")
    nodes = {}
    for s in sets:
        if s.get("type") in (15, 2411):
            for n, *p in zip(s["node_nums"], s["x"], s["y"], s["z"]):
                nodes[int(n)] = p
    channels, points = channels or {}, points or {}
    keys = [f"{n}:{d}" for n, d in rsp]
    geo = {}
    have_pts = points and all(str(n) in points for n in ref)
    if nodes and all(n in nodes for n in ref) and len(ref) >= 3:
        try:
            geo = _geometry(nodes, ref, where)
        except DataFormatError:
            if not have_pts:
                raise
            geo = {}  # the mapping places the points; the file's odd geometry is not needed
    if have_pts:
        ang, geometry = np.array([points[str(n)] for n in ref], dtype=float), "the mapping's [points]"
    elif geo:
        ang, geometry = np.array([geo[n][0] for n in ref]), "the nodes of dataset 15"
    elif require_geometry:
        raise DataFormatError(f"{where}: nothing says where the impact points are (reference nodes "
                              f"{ref[0]}…{ref[-1]}): the file has no dataset 15 with their nodes and no mapping "
                              "gives their angles; allowed: a UFF 15 geometry in the file, or --mapping with [points]")
    else:
        ang, geometry = np.full(len(ref), np.nan), "none (angles unknown)"
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
    header = next((s for s in sets if s.get("type") == 151), None)
    info = {"files": [str(p) for p in paths], "form": form, **units, "geometry": geometry,
            "sign_flipped": sorted(flipped), "coherence": bool(np.isfinite(C).any()),
            "reference_nodes": ref, "response_dofs": keys}
    if header:
        info["header"] = {k: str(header.get(k, "")).strip() for k in ("model_name", "description", "program")}
    return FRFResult(freq_hz=x0, H=H, coherence=C, n_averages=np.zeros(len(ref), int),
                     point_index=np.arange(len(ref)), point_angle=ang, channel_name=tuple(names),
                     channel_location=tuple(locs), channel_angle=np.array(cang, dtype=float), rejections=(),
                     dead_channels=(), estimator="unknown", form=form, exp_tau_s=None, sample_rate=np.nan,
                     n_samples=0, meta={"source": where, "uff": info})


def describe_frf_uff(path) -> dict:
    """What a UFF file of FRFs holds (``tiremodal info``): form and units found, sizes, band,
    channels with their locations, where the geometry comes from, flipped channels."""
    r = read_frf_uff(path)
    u = r.meta["uff"]
    return {"format": "UFF 58 FRFs", "form": r.form, "units": UNITS[r.form], "unit_in_file": u["unit_in_file"],
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
    out = set()
    for p in paths:
        try:
            got = pyuff.UFF(str(p)).read_sets()
        except Exception as exc:  # pyuff raises bare Exception/ValueError/IndexError on bad files
            raise DataFormatError(f"{p}: not a readable UFF file ({exc.__class__.__name__}: {exc})") from None
        out |= {int(s.get("func_type", 0)) for s in ([got] if isinstance(got, dict) else got) if s.get("type") == 58}
    return out
