"""The FRF file (``tiremodal.frf``, version 1); UFF 58 is :mod:`tiremodal_cli.io.frfuff`.

HDF5 layout (``docs/format.md``): root attributes ``format``, ``format_version``,
``estimator``, ``form``, ``sample_rate``, ``n_samples``, ``exp_tau_s`` (absent: no
exponential window), ``tiremodal_version``, ``input_file``, ``input_sha256``, ``meta``
(JSON), ``rejections`` (JSON list); datasets ``freq_hz`` (n_freq,), ``frf``
(n_channels, n_points, n_freq) complex128, ``coherence`` (same shape, float64),
``n_averages`` and ``point_index`` (n_points,), ``point_angle`` (n_points,) rad,
``channel_name``, ``channel_location`` (n_channels,) str, ``channel_angle`` (n_channels,) rad,
``dead_channels`` (str), ``channel_live`` (n_channels,) bool: false for a dead channel, whose
entries in ``frf`` and ``coherence`` hold the fill value 0 — both datasets say so in their
attributes ``null_fill``, ``null_where``, ``null_reason`` (no NaN is stored; :func:`read_frf`
gives NaN there in memory, as the estimate has it); ``force_autospectrum`` (n_points, n_freq)
float64, N², optional (absent in files written before session 18 and for FRFs given as UFF 58):
the mean |F|² over each point's accepted hits — what lets ``lsce`` on the file choose the
band ``run`` chose.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import h5py
import numpy as np

from tiremodal_cli import __version__
from tiremodal_cli.conventions import FORM_UNITS
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import atomic_path
from tiremodal_cli.frf.estimate import FRFResult
from tiremodal_cli.frf.screening import Rejection
from tiremodal_cli.io.measurement import attr_str, open_hdf5, read_strings

__all__ = ["FORMAT_NAME", "write_frf", "read_frf", "describe_frf", "UNITS"]

FORMAT_NAME = "tiremodal.frf"
FORMAT_VERSION = 1
UNITS = FORM_UNITS  # the FRF file's ``units`` attribute


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
            live = np.array([c not in set(r.dead_channels) for c in r.channel_name], dtype=bool)
            h.create_dataset("channel_live", data=live)
            h["channel_live"].attrs["meaning"] = DEAD_REASON
            for name, arr in (("frf", r.H.astype(np.complex128)), ("coherence", r.coherence)):
                h.create_dataset(name, data=_fill_dead(arr, live, name))
                h[name].attrs["null_fill"] = 0.0
                h[name].attrs["null_where"] = "channels whose channel_live is false"
                h[name].attrs["null_reason"] = DEAD_REASON
            h.create_dataset("n_averages", data=r.n_averages)
            h.create_dataset("point_index", data=r.point_index)
            h.create_dataset("point_angle", data=r.point_angle)
            h.create_dataset("channel_name", data=list(r.channel_name), dtype=s)
            h.create_dataset("channel_location", data=list(r.channel_location), dtype=s)
            h.create_dataset("channel_angle", data=r.channel_angle)
            h.create_dataset("dead_channels", data=list(r.dead_channels), dtype=s)
            if r.force_autospectrum is not None:
                h.create_dataset("force_autospectrum", data=np.asarray(r.force_autospectrum, dtype=np.float64))
                h["force_autospectrum"].attrs["units"] = "N^2"
                h["force_autospectrum"].attrs["meaning"] = ("mean |F|^2 over each point's accepted hits on the FRF "
                                                            "lines (DFT of the windowed force record)")
    return Path(path)


#: why a dead channel's FRFs and coherence are not numbers (an attribute of each dataset)
DEAD_REASON = ("dead channel: no signal in any hit (listed in dead_channels); nothing was estimated for it, "
               "its entries hold the fill value 0 (read_frf gives NaN)")


def _fill_dead(arr, live, name):
    """The (n_channels, …) array with its dead channels set to 0 (``name`` for messages).
    A live channel's values are written as given: the estimate defines them all (an FRF
    built by hand may not, and the modal stage refuses it with the point and line)."""
    out = np.array(arr, copy=True)
    out[~live] = 0
    return out


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
    with open_hdf5(path, "an FRF file (HDF5, written by tiremodal frf; or UFF 58 FRFs named *.uff or *.unv)") as h:
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
            live = h["channel_live"][()].astype(bool) if "channel_live" in h else None
            gff = np.asarray(h["force_autospectrum"][()], dtype=float) if "force_autospectrum" in h else None
            a = dict(h.attrs)
        except (OSError, ValueError, TypeError) as exc:
            raise DataFormatError(f"{where}: cannot read ({exc}); the file may be truncated") from None
    H = d["frf"]
    n_c, n_p, n_f = (H.shape + (0, 0, 0))[:3] if H.ndim == 3 else (0, 0, 0)
    if H.ndim != 3 or d["freq_hz"].shape != (n_f,) or d["coherence"].shape != H.shape \
            or len(names) != n_c or d["point_angle"].shape != (n_p,):
        raise DataFormatError(f"{where}: sizes do not match (frf {H.shape}, freq_hz {d['freq_hz'].shape}, "
                              f"{len(names)} channels, {d['point_angle'].shape[0]} points)")
    _check_force(gff, where, n_p, n_f)
    if live is not None:  # the dead channels' fill value back to NaN in memory (older files stored NaN)
        if live.shape != (n_c,):
            raise DataFormatError(f"{where}: channel_live has {live.size} entries for {n_c} channels")
        H, coh = np.array(H, dtype=complex), np.array(d["coherence"], dtype=float)
        H[~live], coh[~live] = np.nan, np.nan
        d["coherence"] = coh
    rej = tuple(Rejection(**x) for x in json.loads(_s(a.get("rejections", "[]"))))
    tau = a.get("exp_tau_s")
    return FRFResult(freq_hz=d["freq_hz"], H=H, coherence=d["coherence"], n_averages=d["n_averages"],
                     point_index=d["point_index"], point_angle=d["point_angle"], channel_name=names,
                     channel_location=locs, channel_angle=d["channel_angle"], rejections=rej,
                     dead_channels=dead, estimator=_s(a.get("estimator", "H1")),
                     form=_s(a.get("form", "accelerance")), exp_tau_s=None if tau is None else float(tau),
                     sample_rate=float(a.get("sample_rate", np.nan)), n_samples=int(a.get("n_samples", 0)),
                     meta=json.loads(_s(a.get("meta", "{}"))), force_autospectrum=gff)


def _check_force(gff, where, n_p, n_f):
    """The optional force autospectrum: (n_points, n_freq), finite and ≥ 0, or DataFormatError."""
    if gff is not None and (gff.shape != (n_p, n_f) or not np.all(np.isfinite(gff)) or np.any(gff < 0)):
        raise DataFormatError(f"{where}: force_autospectrum must be ({n_p}, {n_f}) finite values ≥ 0; "
                              f"got shape {gff.shape}")


def _s(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def describe_frf(path: str | os.PathLike) -> dict:
    """What an FRF file holds (``tiremodal info``): form and units, sizes, band, channels, provenance."""
    r = read_frf(path)
    with open_hdf5(path, "an FRF file (HDF5, written by tiremodal frf; or UFF 58 FRFs named *.uff or *.unv)") as h:
        src = {k: _s(h.attrs[k]) for k in ("input_file", "input_sha256", "tiremodal_version") if k in h.attrs}
    return {"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "estimator": r.estimator, "form": r.form,
            "units": UNITS[r.form], "n_channels": len(r.channel_name), "n_points": int(r.point_angle.size),
            "n_freq": int(r.freq_hz.size), "band_hz": [float(r.freq_hz[0]), float(r.freq_hz[-1])],
            "resolution_hz": float(r.freq_hz[1] - r.freq_hz[0]) if r.freq_hz.size > 1 else None,
            "channels": list(r.channel_name), "dead_channels": list(r.dead_channels),
            "n_averages_min": int(r.n_averages.min()), "n_rejections": len(r.rejections),
            "exp_tau_s": r.exp_tau_s, "force_autospectrum": r.force_autospectrum is not None, **src}
