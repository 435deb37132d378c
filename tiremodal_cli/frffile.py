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
import os
from pathlib import Path

import h5py
import numpy as np
import pyuff

from . import __version__
from .errors import DataFormatError
from .files import atomic_path
from .frf import FRFResult, Rejection
from .measurement import _attr_str, _strings, open_hdf5

__all__ = ["FORMAT_NAME", "write_frf", "read_frf", "write_frf_uff", "describe_frf", "UNITS"]

FORMAT_NAME = "tiremodal.frf"
FORMAT_VERSION = 1
UNITS = {"accelerance": "m/s^2/N", "mobility": "m/s/N", "receptance": "m/N"}
_SPEC = {"accelerance": 12, "mobility": 11, "receptance": 8}  # UFF specific data types


def write_frf(path, r: FRFResult, *, input_file: str = "", input_sha256: str = "",
              overwrite: bool = False) -> Path:
    """Write an FRF file atomically."""
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
    """Read an FRF file written by :func:`write_frf`; DataFormatError on anything else."""
    where = str(path)
    with open_hdf5(path) as h:
        fmt = _attr_str(h.attrs, "format")
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
            names, locs, dead = (_strings(h[k]) for k in ("channel_name", "channel_location", "dead_channels"))
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
    """
    import datetime
    import logging

    from . import __version__

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


def read_frf_uff(path, *, channels: dict | None = None, points: dict | None = None) -> FRFResult:
    """FRFs from UFF dataset 58 (function type 4), e.g. exported by other modal software.

    Channels are the response DOFs ``"node:dir"``, points the reference DOFs (their node);
    a mapping (as for ``ingest``) gives names, locations and angles. Without one, angles are
    unknown (NaN) and locations ``"unknown"``: the data are treated as any structure's.
    The form follows the ordinate type (12 acceleration, 11 velocity, 8 displacement).
    """
    where = str(path)
    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises bare Exception/ValueError/IndexError on bad files
        raise DataFormatError(f"{where}: not a readable UFF file ({exc.__class__.__name__}: {exc})") from None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    frfs = [s for s in sets if s.get("type") == 58 and int(s.get("func_type", 0)) == 4]
    if not frfs:
        raise DataFormatError(f"{where}: no FRF (dataset 58, function type 4)")
    x0 = np.asarray(frfs[0]["x"], dtype=float)
    spec = {int(s.get("ordinate_spec_data_type", 12) or 12) for s in frfs}
    if len(spec) != 1 or spec.pop() not in _FORM_OF_SPEC:
        raise DataFormatError(f"{where}: FRFs must share one ordinate type among 12, 11, 8")
    form = _FORM_OF_SPEC[int(frfs[0].get("ordinate_spec_data_type", 12) or 12)]
    rsp = sorted({(int(s["rsp_node"]), int(s["rsp_dir"])) for s in frfs})
    ref = sorted({int(s["ref_node"]) for s in frfs})
    H = np.full((len(rsp), len(ref), x0.size), np.nan + 0j)
    for s in frfs:
        x = np.asarray(s["x"], dtype=float)
        if x.shape != x0.shape or not np.allclose(x, x0):
            raise DataFormatError(f"{where}: FRFs have different frequency axes")
        H[rsp.index((int(s["rsp_node"]), int(s["rsp_dir"]))), ref.index(int(s["ref_node"]))] = s["data"]
    if np.isnan(H).any():
        raise DataFormatError(f"{where}: not every response has an FRF for every reference")
    keys = [f"{n}:{d}" for n, d in rsp]
    ch = {k: (channels or {}).get(k, (k, "unknown", np.nan)) for k in keys}
    ang = np.array([(points or {}).get(str(n), np.nan) for n in ref], dtype=float)
    return FRFResult(freq_hz=x0, H=H, coherence=np.full(H.shape, np.nan), n_averages=np.zeros(len(ref), int),
                     point_index=np.arange(len(ref)), point_angle=ang,
                     channel_name=tuple(ch[k][0] for k in keys), channel_location=tuple(ch[k][1] for k in keys),
                     channel_angle=np.array([ch[k][2] for k in keys], dtype=float), rejections=(),
                     dead_channels=(), estimator="unknown", form=form, exp_tau_s=None, sample_rate=np.nan,
                     n_samples=0, meta={"source": where, "reference_nodes": ref})
