"""The modal file (``tiremodal.modal``, version 1) and its table forms (JSON, CSV).

HDF5: root attributes ``format``, ``format_version``, ``tiremodal_version``, ``input_file``,
``input_sha256``, ``form``, ``meta`` (JSON: band and its reason, options, exponential window,
``crowds``: modes whose order cannot be told, each with ``n_candidates``),
``clusters`` (JSON: every cluster of every group with its decision), ``rejected`` (JSON);
datasets per mode ``frequency_hz``, ``damping_ratio``, ``pole`` (complex, as estimated,
rad/s), ``mpc``, ``significance``, ``group``, ``n`` (−1: none), ``n_spatial``,
``n_confidence``, ``branch`` (str, "" none), ``branch_confidence``, ``pair`` (−1: none),
``splitting_hz`` (NaN: none), ``in_order`` (bool: within its branch's dispersion order),
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
from dataclasses import dataclass

import h5py
import numpy as np

from tiremodal_cli import __version__
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import atomic_path
from tiremodal_cli.io.measurement import _attr_str, _strings, open_hdf5

__all__ = ["FORMAT_NAME", "ModalTable", "table_from_result", "write_modal", "read_modal", "to_rows",
           "to_csv", "read_modal_csv", "describe_modal", "STATUS_CODES"]

FORMAT_NAME = "tiremodal.modal"
FORMAT_VERSION = 1
STATUS_CODES = {"new": 0, "f": 1, "fd": 2, "fv": 3, "stable": 4}
COLUMNS = ("mode", "frequency_hz", "damping_ratio", "n", "branch", "n_confidence", "branch_confidence",
           "mpc", "significance", "n_spatial", "n_aliased", "pair", "splitting_hz", "in_order", "group",
           "frequency_uncertainty_hz", "crowd", "n_candidates", "confirmed")


@dataclass(frozen=True)
class ModalTable:
    """A modal table with shapes and geometry (what the modal file holds)."""

    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    pole: np.ndarray
    mpc: np.ndarray
    significance: np.ndarray
    group: np.ndarray
    n: np.ndarray
    n_spatial: np.ndarray
    n_confidence: np.ndarray
    branch: tuple
    branch_confidence: np.ndarray
    pair: np.ndarray
    splitting_hz: np.ndarray
    in_order: np.ndarray
    shapes: np.ndarray
    point_angle: np.ndarray
    point_index: np.ndarray
    channel_name: tuple
    channel_location: tuple
    channel_angle: np.ndarray
    fit_error: np.ndarray
    diagram: np.ndarray
    form: str = "accelerance"
    meta: dict | None = None
    clusters: list | None = None
    rejected: list | None = None
    synthesis: np.ndarray | None = None
    synthesis_freq_hz: np.ndarray | None = None

    @property
    def n_modes(self) -> int:
        return self.frequency_hz.size


def table_from_result(res, classes, *, point_angle, point_index, channel_name, channel_location,
                      channel_angle, form) -> ModalTable:
    """A ModalTable from a ModalResult and its classifications (None: not a tyre)."""
    k = res.freq_hz.size
    cls = classes or [None] * k
    diag, clusters = [], []
    for g, d in res.diagrams:
        diag += [(g, p.order, p.freq_hz, p.damping_ratio, STATUS_CODES[p.status]) for p in d.poles]
        clusters += [{"group": int(g), **c.to_dict()} for c in d.clusters]
    return ModalTable(
        frequency_hz=res.freq_hz, damping_ratio=res.damping_ratio, pole=res.poles, mpc=res.mpc,
        significance=res.significance, group=res.group,
        n=np.array([c.n if c else -1 for c in cls]), n_spatial=np.array([c.n_spatial if c else -1 for c in cls]),
        n_confidence=np.array([c.n_confidence if c else np.nan for c in cls]),
        branch=tuple((c.branch or "") if c else "" for c in cls),
        branch_confidence=np.array([c.branch_confidence if c else np.nan for c in cls]),
        pair=np.array([c.pair if c and c.pair is not None else -1 for c in cls]),
        splitting_hz=np.array([c.splitting_hz if c and c.splitting_hz is not None else np.nan for c in cls]),
        in_order=np.array([c.in_order if c else True for c in cls]),
        shapes=res.shapes, point_angle=np.asarray(point_angle, float), point_index=np.asarray(point_index),
        channel_name=tuple(channel_name), channel_location=tuple(channel_location),
        channel_angle=np.asarray(channel_angle, float), fit_error=res.fit_error,
        diagram=np.array(diag, dtype=float).reshape(-1, 5), form=form, meta=res.meta, clusters=clusters,
        rejected=res.rejected, synthesis=res.synthesis, synthesis_freq_hz=res.band_freq_hz)


def frequency_uncertainty(t: ModalTable) -> np.ndarray:
    """Each mode's frequency scatter (Hz): the standard deviation of its cluster's poles
    over the model orders of the stabilization diagram (the adopted cluster of its group
    nearest in frequency, within 1 %). NaN where none matches (an old file)."""
    out = np.full(t.n_modes, np.nan)
    adopted = [c for c in (t.clusters or []) if c.get("adopted") and "frequency_std_hz" in c]
    for i in range(t.n_modes):
        near = [c for c in adopted if c.get("group") == int(t.group[i])
                and abs(c["frequency_hz"] - t.frequency_hz[i]) <= 0.01 * t.frequency_hz[i]]
        if near:
            out[i] = min(near, key=lambda c: abs(c["frequency_hz"] - t.frequency_hz[i]))["frequency_std_hz"]
    return out


def to_rows(t: ModalTable) -> list[dict]:
    """One dict per mode (the ``--json`` list; n, branch, pair absent when not a tyre).

    Parameters
    ----------
    t : ModalTable

    Returns
    -------
    list of dict
        Keys of :data:`COLUMNS` (``frequency_hz`` in Hz, ``damping_ratio`` a fraction …),
        what ``identify``, ``diagnose`` and :func:`tiremodal_cli.tyre.measured.modes_from_rows` read.
    """
    rows = []
    unc = frequency_uncertainty(t)
    crowds = (t.meta or {}).get("crowds") or []
    n_top = t.point_angle.size // 2
    for i in range(t.n_modes):
        cands = next((c["n_candidates"] for c in crowds if abs(c["frequency_hz"] - t.frequency_hz[i])
                      <= 1e-9 * t.frequency_hz[i]), [])
        row = {"mode": i + 1, "frequency_hz": float(t.frequency_hz[i]), "damping_ratio": float(t.damping_ratio[i]),
               "mpc": float(t.mpc[i]), "significance": float(t.significance[i]), "group": int(t.group[i]),
               "frequency_uncertainty_hz": None if not np.isfinite(unc[i]) else float(unc[i])}
        conf = (t.meta or {}).get("confirmed")
        if conf is not None and len(conf) == t.n_modes:
            row["confirmed"] = bool(conf[i])
        if t.n[i] >= 0:
            row.update(n=int(t.n[i]), branch=t.branch[i] or None, n_confidence=float(t.n_confidence[i]),
                       branch_confidence=float(t.branch_confidence[i]), n_spatial=int(t.n_spatial[i]),
                       n_aliased=bool(t.n[i] != t.n_spatial[i] or any(c > n_top for c in cands)),
                       crowd=bool(cands), n_candidates=" ".join(str(c) for c in cands) or None,
                       pair=None if t.pair[i] < 0 else int(t.pair[i]) + 1,
                       splitting_hz=None if not np.isfinite(t.splitting_hz[i]) else float(t.splitting_hz[i]),
                       in_order=bool(t.in_order[i]))
        rows.append(row)
    return rows


def to_csv(t: ModalTable) -> str:
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


#: why a channel has no shape, fit error or synthesis (written beside those datasets)
DEAD_REASON = ("dead channel: no signal in any hit (the FRF file's dead_channels); nothing was estimated for it, "
               "its entries hold the fill value 0 (read_modal gives NaN)")
#: per-mode datasets whose NaN is a documented "none", with the reason (an attribute of each)
PER_MODE_NULL = {"n_confidence": "not classified: the points do not go round a tread (n is −1)",
                 "branch_confidence": "not classified, or no sidewall channel to read the branch from",
                 "splitting_hz": "not a member of a split pair (pair is −1)"}


def channel_live(t: ModalTable) -> np.ndarray:
    """(n_channels,) bool: False for a dead channel (its fit error and shapes NaN in memory)."""
    fe = np.asarray(t.fit_error, dtype=float)
    if fe.ndim != 2 or fe.shape[0] != len(t.channel_name):
        return np.ones(len(t.channel_name), dtype=bool)
    return ~np.all(np.isnan(fe), axis=1)


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
    with open_hdf5(path) as h:
        fmt = _attr_str(h.attrs, "format")
        if fmt != FORMAT_NAME:
            raise DataFormatError(f"{where}: format={fmt!r} is not a modal file; expected {FORMAT_NAME!r}")
        try:
            d = {k: h[k][()] for k in ("frequency_hz", "damping_ratio", "pole", "mpc", "significance", "group", "n",
                                       "n_spatial", "n_confidence", "branch_confidence", "pair", "splitting_hz",
                                       "in_order",
                                       "shapes", "point_angle", "point_index", "channel_angle", "fit_error",
                                       "diagram")}
            strs = {k: _strings(h[k]) for k in ("branch", "channel_name", "channel_location")}
            d.update({k: h[k][()] for k in ("synthesis", "synthesis_freq_hz") if k in h})
            live = h["channel_live"][()].astype(bool) if "channel_live" in h else None
            a = dict(h.attrs)
        except KeyError as exc:
            raise DataFormatError(f"{where}: dataset {exc} is missing") from None
        except (OSError, ValueError) as exc:
            raise DataFormatError(f"{where}: cannot read ({exc}); the file may be truncated") from None

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
    return rows


def describe_modal(path) -> dict:
    t = read_modal(path)
    return {"format": FORMAT_NAME, "format_version": FORMAT_VERSION, "n_modes": t.n_modes,
            "band_hz": (t.meta or {}).get("band_hz"), "n_channels": len(t.channel_name),
            "n_points": int(t.point_angle.size), "tyre_classified": bool(np.any(t.n >= 0)),
            "modes": to_rows(t)}


def no_usable_modes(source, rows, skipped) -> str:
    """The message for a modal table with no mode a fit can use: the file, how many rows,
    and the commonest reasons the rows were left out."""
    import re
    from collections import Counter

    reasons = Counter(re.sub(r"[-+]?\d[\d.e+-]*", "#", s["reason"]) for s in skipped)
    why = "; ".join(f"{k} ({v}×)" for k, v in reasons.most_common(2)) or "the table is empty"
    return (f"{source}: no usable modes among {len(rows)} row(s) ({why}); allowed: rows with frequency_hz > 0, "
            "an integer n ≥ 0 and branch same/opposite (run lsce with --spatial on for tyre FRFs)")
