"""A folder of CSV files → the measurement layout.

Accepted (``docs/ingest.md``):

* ``point<P>_hit<H>.csv``: one file per point and hit, columns ``time_s``, ``force_N`` and
  one column per response channel (m/s²), header on the first line; or
* ``point<P>.csv``: one file per point with hits stacked, an extra first column ``hit``.

P and H are integers (any zero padding). Channels are the response columns in header
order; their location and angle come from the mapping (keyed by column name) or from
``channels.csv`` in the folder (columns ``name,location,angle_deg``). Point angles come
from the mapping's ``[points]`` (keyed by P), or ``points.csv`` (``point,angle_deg``), or
are uniform in P order.
"""

from __future__ import annotations

import csv
import re
from collections import defaultdict
from pathlib import Path

import numpy as np

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.measurement import Measurement
from tiremodal_cli.io.ingest import parse_channel, point_angles

__all__ = ["read_csv_folder"]

_HIT = re.compile(r"^point(\d+)_hit(\d+)\.csv$", re.IGNORECASE)
_POINT = re.compile(r"^point(\d+)\.csv$", re.IGNORECASE)


def _table(path: Path):
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            header = next(csv.reader(fh))
    except (StopIteration, UnicodeDecodeError, csv.Error):
        raise DataFormatError(f"{path}: empty or not a CSV text file") from None
    header = [h.strip() for h in header]
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as exc:
        # numpy counts the data rows from 0 after the header and the columns from 1: say the
        # file's own line (1-based, the header is line 1) and the column's name
        m = re.search(r"string '(.*)' to \S+ at row (\d+), column (\d+)", str(exc))
        if m is None:
            raise DataFormatError(f"{path}: non-numeric value ({exc}); allowed: numbers") from None
        col = int(m.group(3))
        name = f" ({header[col - 1]!r})" if 0 < col <= len(header) else ""
        raise DataFormatError(f"{path}: line {int(m.group(2)) + 2}, column {col}{name}: {m.group(1)!r} is not a "
                              "number; allowed: numbers") from None
    if data.shape[1] != len(header):
        raise DataFormatError(f"{path}: {data.shape[1]} columns of data, {len(header)} in the header")
    return header, data


def _side_table(path: Path, cols):
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    for c in cols:
        if rows and c not in rows[0]:
            raise DataFormatError(f"{path}: column {c!r} is missing; expected {', '.join(cols)}")
    return rows


def read_csv_folder(folder, channels: dict | None = None, points: dict | None = None, **attrs) -> Measurement:
    """Build a Measurement from a CSV folder (see the module docstring for the layout)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise DataFormatError(f"{folder}: not a folder")
    records = _records(folder)
    pts = sorted(records)
    n_hits = {len(records[p]) for p in pts}
    if len(n_hits) != 1:
        raise DataFormatError(f"{folder}: points have different numbers of hits ({sorted(n_hits)})")
    header0 = next(iter(records[pts[0]].values()))[0]
    if header0[:2] != ["time_s", "force_N"] or len(header0) < 3:
        raise DataFormatError(f"{folder}: columns must start time_s,force_N and name ≥ 1 channel; got {header0}")
    ch_names = header0[2:]
    chans = _channel_table(folder, ch_names, channels)
    pts_map = dict(points or {})
    side = folder / "points.csv"
    if side.is_file() and not pts_map:
        pts_map = {str(int(r["point"])): float(np.deg2rad(float(r["angle_deg"])))
                   for r in _side_table(side, ("point", "angle_deg"))}
    F, Y, dt = _arrays(folder, records, header0, n_hits.pop())
    return Measurement(force=F, response=Y, sample_rate=float(f"{1.0 / dt:.9g}"),
                       point_angle=point_angles([str(p) for p in pts], pts_map, str(folder)),
                       channel_name=tuple(ch_names), channel_location=tuple(chans[c][1] for c in ch_names),
                       channel_angle=np.array([chans[c][2] for c in ch_names]),
                       inflation_pressure=attrs.get("inflation_pressure"), tire=attrs.get("tire"),
                       description=attrs.get("description"))


def _records(folder: Path) -> dict:
    """``{point: {hit: (header, data)}}`` from either layout (one file per hit, or per point
    with a ``hit`` column), never both."""
    per_hit, per_point = {}, {}
    for f in sorted(folder.iterdir()):
        if m := _HIT.match(f.name):
            per_hit[(int(m[1]), int(m[2]))] = f
        elif m := _POINT.match(f.name):
            per_point[int(m[1])] = f
    if per_hit and per_point:
        raise DataFormatError(f"{folder}: both point<P>_hit<H>.csv and point<P>.csv files; use one layout")
    if not per_hit and not per_point:
        raise DataFormatError(f"{folder}: no point<P>_hit<H>.csv or point<P>.csv files")
    records = defaultdict(dict)  # P -> H -> (header, data)
    if per_hit:
        for (p, h), f in per_hit.items():
            records[p][h] = _table(f)
        return records
    for p, f in per_point.items():
        header, data = _table(f)
        if header[0].lower() != "hit":
            raise DataFormatError(f"{f}: first column must be 'hit' in a per-point file")
        for h in np.unique(data[:, 0]).astype(int):
            records[p][int(h)] = (header[1:], data[data[:, 0] == h, 1:])
    return records


def _channel_table(folder: Path, ch_names: list[str], channels: dict | None) -> dict:
    """``{name: (name, location, angle_rad)}``: the mapping's channels, else ``channels.csv``'s;
    every column of the records needs one."""
    chans = dict(channels or {})
    side = folder / "channels.csv"
    if side.is_file():
        for row in _side_table(side, ("name", "location", "angle_deg")):
            chans.setdefault(row["name"], parse_channel(row["name"], row))
    missing = [c for c in ch_names if c not in chans]
    if missing:
        raise DataFormatError(f"{folder}: channel column {missing[0]!r} has no location/angle "
                              "(add it to channels.csv or the mapping)")
    return chans


def _arrays(folder: Path, records: dict, header0: list[str], n_h: int):
    """Force (n_points, n_hits, n_samples), responses (n_points, n_hits, n_channels,
    n_samples) and the sample interval (s), every record checked against the first."""
    pts = sorted(records)
    ns = next(iter(records[pts[0]].values()))[1].shape[0]
    F = np.zeros((len(pts), n_h, ns))
    Y = np.zeros((len(pts), n_h, len(header0) - 2, ns))
    dt = None
    for ip, p in enumerate(pts):
        for ih, h in enumerate(sorted(records[p])):
            header, data = records[p][h]
            where = f"{folder}: point {p} hit {h}"
            if header != header0:
                raise DataFormatError(f"{where}: columns {header} differ from {header0}")
            if data.shape[0] != ns:
                raise DataFormatError(f"{where}: {data.shape[0]} samples, expected {ns}")
            t = data[:, 0]
            d = np.diff(t)
            if d.size == 0 or d[0] <= 0 or not np.allclose(d, d[0], rtol=1e-6, atol=1e-12):
                raise DataFormatError(f"{where}: time_s is not evenly spaced and increasing")
            if dt is None:
                dt = (t[-1] - t[0]) / (ns - 1)
            F[ip, ih] = data[:, 1]
            Y[ip, ih] = data[:, 2:].T
    return F, Y, dt
