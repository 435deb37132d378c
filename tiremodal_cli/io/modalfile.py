"""The modal file (``tiremodal.modal``, version 1) and its table forms (JSON, CSV).

HDF5: root attributes ``format``, ``format_version``, ``tiremodal_version``, ``input_file``,
``input_sha256``, ``form``, ``meta`` (JSON: band and its reason, options, exponential window,
``crowds``: modes whose order cannot be told, each with ``n_candidates``),
``clusters`` (JSON: every cluster of every group with its decision), ``rejected`` (JSON);
datasets per mode ``frequency_hz``, ``damping_ratio``, ``pole`` (complex, as estimated,
rad/s), ``mpc``, ``significance``, ``group``, ``n`` (−1: none), ``n_spatial``,
``n_confidence``, ``branch`` (str, "" none), ``branch_confidence``, ``pair`` (−1: none),
``splitting_hz`` (NaN: none), ``in_order`` (bool: within its branch's dispersion order),
``frequency_std_hz`` (Hz: the mode's frequency scatter over the model orders, as the modal
stage carried it to identify and diagnose; NaN: none; absent in files written before
session 12, where :func:`tiremodal_cli.modal.table.frequency_uncertainty` rebuilds it from
the clusters),
``shapes`` (n_modes, n_channels, n_points) complex residues;
geometry ``point_angle``, ``point_index``, ``channel_name``, ``channel_location``,
``channel_angle``; ``fit_error`` (n_channels, n_points); ``channel_live`` (n_channels,
bool): false for a dead channel, whose entries in ``shapes``, ``fit_error`` and
``synthesis`` hold the fill value 0 — each of those datasets says so in its attributes
``null_fill``, ``null_where``, ``null_reason`` (no NaN is stored for them; ``read_modal``
gives NaN there in memory); the per-mode NaN of ``n_confidence``, ``branch_confidence``,
``splitting_hz`` is a "none" named in their ``null_value`` / ``null_reason`` attributes;
the stabilization diagram
``diagram`` (n_poles, 5): group, order, frequency_hz, damping_ratio, status code
(0 new, 1 f, 2 fd, 3 fv, 4 stable); optionally the re-synthesised FRFs of the modal
model (with its residual terms) ``synthesis`` (n_channels, n_points, n_band) complex64
on the lines ``synthesis_freq_hz`` (n_band,), for measured-against-synthesised plots.
"""

from __future__ import annotations

import csv
import io
import json
import re
from collections import Counter

import h5py
import numpy as np

from tiremodal_cli import __version__
from tiremodal_cli.conventions import BRANCHES
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import atomic_path
from tiremodal_cli.io.measurement import attr_str, open_hdf5, read_strings
from tiremodal_cli.modal.table import COLUMNS, ModalTable, channel_live, to_rows

__all__ = ["FORMAT_NAME", "write_modal", "read_modal", "to_csv", "read_modal_csv", "describe_modal",
           "no_usable_modes", "N_ORDER_MAX"]

FORMAT_NAME = "tiremodal.modal"
FORMAT_VERSION = 1


def to_csv(t: ModalTable) -> str:
    """The modal table as CSV text (``lsce --csv``, ``modes.csv``): :data:`COLUMNS`, empty for none."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=COLUMNS, extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in to_rows(t):
        w.writerow({k: ("" if r.get(k) is None else r.get(k, "")) for k in COLUMNS})
    return buf.getvalue()


def write_modal(path, t: ModalTable, *, input_file: str = "", input_sha256: str = "", overwrite=False):
    """Write a modal file (layout in the module docstring) atomically.

    Parameters
    ----------
    path : path-like
    t : ModalTable
    input_file, input_sha256 : str
        What the table was estimated from (recorded as provenance).
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
            a["format"], a["format_version"], a["tiremodal_version"] = FORMAT_NAME, FORMAT_VERSION, __version__
            a["input_file"], a["input_sha256"], a["form"] = str(input_file), input_sha256, t.form
            a["meta"] = json.dumps(t.meta or {}, default=float)
            a["clusters"] = json.dumps(t.clusters or [], default=float)
            a["rejected"] = json.dumps(t.rejected or [], default=float)
            live = channel_live(t)
            h.create_dataset("channel_live", data=live)
            h["channel_live"].attrs["meaning"] = DEAD_REASON
            for name in ("frequency_hz", "damping_ratio", "pole", "mpc", "significance", "group", "n", "n_spatial",
                         "n_confidence", "branch_confidence", "pair", "splitting_hz", "in_order", "point_angle",
                         "point_index", "channel_angle", "diagram"):
                h.create_dataset(name, data=np.asarray(getattr(t, name)))
                if name in PER_MODE_NULL:
                    h[name].attrs["null_value"], h[name].attrs["null_reason"] = "NaN", PER_MODE_NULL[name]
            per_channel = [("shapes", np.asarray(t.shapes), 1, {}), ("fit_error", np.asarray(t.fit_error), 0, {})]
            if t.synthesis is not None and t.synthesis_freq_hz is not None:
                per_channel.append(("synthesis", np.asarray(t.synthesis, np.complex64), 0, {"compression": "gzip"}))
                h.create_dataset("synthesis_freq_hz", data=np.asarray(t.synthesis_freq_hz, float))
            for name, arr, axis, kw in per_channel:
                h.create_dataset(name, data=_fill_dead(arr, live, axis, name), **kw)
                h[name].attrs["null_fill"] = 0.0
                h[name].attrs["null_where"] = "channels whose channel_live is false"
                h[name].attrs["null_reason"] = DEAD_REASON
            for name in ("branch", "channel_name", "channel_location"):
                h.create_dataset(name, data=list(getattr(t, name)), dtype=s)
            if t.frequency_std_hz is not None:  # the stage's own numbers: a rebuild can swap a split pair's
                h.create_dataset("frequency_std_hz", data=np.asarray(t.frequency_std_hz, float))
                h["frequency_std_hz"].attrs["null_value"] = "NaN"
                h["frequency_std_hz"].attrs["null_reason"] = "no adopted cluster of the mode's group to take it from"


#: why a channel has no shape, fit error or synthesis (written beside those datasets)
DEAD_REASON = ("dead channel: no signal in any hit (the FRF file's dead_channels); nothing was estimated for it, "
               "its entries hold the fill value 0 (read_modal gives NaN)")
#: per-mode datasets whose NaN is a documented "none", with the reason (an attribute of each)
PER_MODE_NULL = {"n_confidence": "not classified: the points do not go round a tread (n is −1)",
                 "branch_confidence": "not classified, or no sidewall channel to read the branch from",
                 "splitting_hz": "not a member of a split pair (pair is −1)"}


def _fill_dead(arr, live, axis, name):
    """The array with its dead channels (along ``axis``) set to 0; any other NaN is a bug."""
    out = np.array(arr, copy=True)
    idx = [slice(None)] * out.ndim
    idx[axis] = ~live
    out[tuple(idx)] = 0
    if not np.all(np.isfinite(out)):
        raise ValueError(f"modal file: {name} holds non-finite values on a live channel")
    return out


def read_modal(path) -> ModalTable:
    """Read a modal file written by :func:`write_modal`; the dead channels' shapes, fit
    errors and synthesis come back as NaN (in the file: the fill value 0 where
    ``channel_live`` is false).

    Parameters
    ----------
    path : path-like

    Returns
    -------
    ModalTable

    Raises
    ------
    DataFormatError
        Not a modal file, an unknown version, a missing dataset or sizes that do not match.
    """
    where = str(path)
    with open_hdf5(path, "a modal file (HDF5, written by tiremodal lsce)") as h:
        fmt = attr_str(h.attrs, "format")
        if fmt != FORMAT_NAME:
            raise DataFormatError(f"{where}: format={fmt!r} is not a modal file; expected {FORMAT_NAME!r}")
        try:
            d = {k: h[k][()] for k in ("frequency_hz", "damping_ratio", "pole", "mpc", "significance", "group", "n",
                                       "n_spatial", "n_confidence", "branch_confidence", "pair", "splitting_hz",
                                       "in_order",
                                       "shapes", "point_angle", "point_index", "channel_angle", "fit_error",
                                       "diagram")}
            strs = {k: read_strings(h[k]) for k in ("branch", "channel_name", "channel_location")}
            d.update({k: h[k][()] for k in ("synthesis", "synthesis_freq_hz", "frequency_std_hz") if k in h})
            live = h["channel_live"][()].astype(bool) if "channel_live" in h else None
            a = dict(h.attrs)
        except KeyError as exc:
            raise DataFormatError(f"{where}: dataset {exc} is missing") from None
        except (OSError, ValueError) as exc:
            raise DataFormatError(f"{where}: cannot read ({exc}); the file may be truncated") from None

    if "frequency_std_hz" in d and np.shape(d["frequency_std_hz"]) != np.shape(d["frequency_hz"]):
        raise DataFormatError(f"{where}: frequency_std_hz has {np.size(d['frequency_std_hz'])} entries for "
                              f"{np.size(d['frequency_hz'])} modes")
    if live is not None:
        if live.shape != (len(strs["channel_name"]),):
            raise DataFormatError(f"{where}: channel_live has {live.size} entries for {len(strs['channel_name'])} channels")
        for name, axis in (("shapes", 1), ("fit_error", 0), ("synthesis", 0)):
            if name in d:
                arr = np.array(d[name], dtype=complex if np.iscomplexobj(d[name]) else float)
                idx = [slice(None)] * arr.ndim
                idx[axis] = ~live
                arr[tuple(idx)] = np.nan
                d[name] = arr

    def js(k):
        v = a.get(k, "null")
        return json.loads(v.decode() if isinstance(v, bytes) else v)
    return ModalTable(**d, **strs, form=str(a.get("form", "accelerance")), meta=js("meta"), clusters=js("clusters"),
                      rejected=js("rejected"))


#: highest circumferential order a table may name (``predict --n-max``'s bound: beyond it
#: the model's n⁴ bending term leaves any tyre's measurable band many times over)
N_ORDER_MAX = 200

#: numeric columns of a modal CSV: (low, high, low open, integer, nan allowed); empty cells are "unknown"
_CSV_NUMBERS = {
    "mode": (1, None, False, True, False),
    "frequency_hz": (0.0, None, True, False, False),
    "damping_ratio": (0.0, 1.0, False, False, True),
    "n": (-1, N_ORDER_MAX, False, True, False),
    "n_spatial": (-1, N_ORDER_MAX, False, True, True),
    "n_confidence": (0.0, 1.0, False, False, True),
    "branch_confidence": (0.0, 1.0, False, False, True),
    "mpc": (0.0, 1.0, False, False, True),
    "significance": (0.0, None, False, False, True),
    "frequency_uncertainty_hz": (0.0, None, False, False, True),
    "splitting_hz": (0.0, None, False, False, True),
}


def _check_csv_cell(path, row: int, key: str, text: str) -> None:
    lo, hi, lo_open, integer, nan_ok = _CSV_NUMBERS[key]
    allowed = (("an integer" if integer else "a finite number") + f" {'>' if lo_open else '≥'} {lo}"
               + (f" and ≤ {hi}" if hi is not None else "") + (", nan" if nan_ok else "") + ", or empty")
    try:
        v = float(text)
    except ValueError:
        v = None
    if v is not None and np.isnan(v) and nan_ok:
        return
    ok = (v is not None and np.isfinite(v) and (v > lo if lo_open else v >= lo) and (hi is None or v <= hi)
          and (not integer or v == int(v)))
    if not ok:
        raise DataFormatError(f"{path}: row {row}: {key}={text!r} is not allowed; allowed: {allowed}")


def read_modal_csv(path) -> list[dict]:
    """Rows of a modal CSV (``lsce --csv``, or the paper's Table A1 layout): dicts of strings.

    Every number is checked (finite, in range, integer where it must be; see
    ``_CSV_NUMBERS``): a bad cell raises DataFormatError naming the file, row (1-based,
    after the header), column, value and what is allowed.
    """
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise DataFormatError(f"{path}: cannot read as CSV ({exc})") from None
    for i, r in enumerate(rows):
        for key in _CSV_NUMBERS:
            v = r.get(key)
            if isinstance(v, str) and v.strip() != "":
                _check_csv_cell(path, i + 1, key, v.strip())
        b = r.get("branch")
        if isinstance(b, str) and b.strip() != "" and b.strip().lower() not in BRANCHES:
            # (a typo would leave the row out of every fit, silently)
            raise DataFormatError(f"{path}: row {i + 1}: branch={b!r} is not allowed; allowed: "
                                  f"{', '.join(BRANCHES)} or empty (unknown)")
    return rows


def describe_modal(path) -> dict:
    """What a modal file holds (``tiremodal info``): sizes, band, whether classified, the rows."""
    t = read_modal(path)
    return {"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "n_modes": t.n_modes,
            "band_hz": (t.meta or {}).get("band_hz"), "n_channels": len(t.channel_name),
            "n_points": int(t.point_angle.size), "tyre_classified": bool(np.any(t.n >= 0)),
            "modes": to_rows(t)}


def no_usable_modes(source, rows, skipped) -> str:
    """The message for a modal table with no mode a fit can use: the file, how many rows,
    and the commonest reasons the rows were left out."""
    reasons = Counter(re.sub(r"[-+]?\d[\d.e+-]*", "#", s["reason"]) for s in skipped)
    why = "; ".join(f"{k} ({v}×)" for k, v in reasons.most_common(2)) or "the table is empty"
    return (f"{source}: no usable modes among {len(rows)} row(s) ({why}); allowed: rows with frequency_hz > 0, "
            "an integer n ≥ 0 and branch same/opposite (run lsce with --spatial on for tyre FRFs)")
