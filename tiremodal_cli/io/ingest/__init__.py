"""Other sources turned into the measurement layout: UFF 58 time records, CSV folders.

Both readers take the same small mapping (``docs/ingest.md``): impact points by node
or number with their angles, and response channels with name, location and angle.
"""

from __future__ import annotations

import numpy as np

from tiremodal_cli.io.config import load_mapping
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.io.measurement import LOCATIONS

__all__ = ["ChannelMap", "load_channel_map", "point_angles", "source_kind", "read_source", "test_folder_kind"]


class ChannelMap(dict):
    """``{key: (name, location, angle_rad)}`` with key ``"node:dir"`` (UFF) or column name (CSV)."""


def parse_channel(key: str, spec) -> tuple[str, str, float]:
    """A channel spec: a mapping with name/location/angle_deg, or ``"name,location,angle_deg"``."""
    if isinstance(spec, str):
        parts = [s.strip() for s in spec.split(",")]
        if len(parts) != 3:
            raise ParameterError(f"channel {key!r}: {spec!r} must be NAME,LOCATION,ANGLE_DEG")
        spec = {"name": parts[0], "location": parts[1], "angle_deg": parts[2]}
    try:
        name, loc, ang = str(spec["name"]), str(spec["location"]), float(spec.get("angle_deg", 0.0))
    except (KeyError, TypeError, ValueError):
        raise ParameterError(f"channel {key!r}: needs name, location and a numeric angle_deg") from None
    if loc not in LOCATIONS:
        raise ParameterError(f"channel {key!r}: location {loc!r}; allowed: {', '.join(LOCATIONS)}")
    return name, loc, float(np.deg2rad(ang))


def load_channel_map(mapping_file=None, channel_options=()) -> tuple[ChannelMap, dict]:
    """Channels and point angles from a mapping file and ``KEY=NAME,LOCATION,ANGLE`` options.

    Returns
    -------
    channels : ChannelMap
    points : dict  ``{point key: angle_rad}`` (empty: uniform spacing in key order)
    """
    data = load_mapping(mapping_file) if mapping_file else {}
    chans = ChannelMap()
    for k, v in (data.get("channels") or {}).items():
        chans[str(k)] = parse_channel(str(k), v)
    for opt in channel_options:
        if "=" not in opt:
            raise ParameterError(f"--channel {opt!r} must be KEY=NAME,LOCATION,ANGLE_DEG")
        k, v = opt.split("=", 1)
        chans[k.strip()] = parse_channel(k.strip(), v)
    points = {}
    for k, v in (data.get("points") or {}).items():
        try:
            points[str(k)] = float(np.deg2rad(float(v)))
        except (TypeError, ValueError):
            raise ParameterError(f"point {k!r}: angle {v!r} is not a number of degrees") from None
    return chans, points


def point_angles(keys, points: dict, where: str) -> np.ndarray:
    """Angles of the points ``keys`` (in file order): from ``points``, or uniform."""
    if not points:
        return 2 * np.pi * np.arange(len(keys)) / len(keys)
    missing = [k for k in keys if str(k) not in points]
    if missing:
        raise DataFormatError(f"{where}: point {missing[0]!r} has no angle in the mapping's [points]")
    return np.array([points[str(k)] for k in keys])


def test_folder_kind(folder) -> str | None:
    """What a folder holds as one test: ``"csv"`` (``point*.csv``), ``"uff"`` (``*.uff``/``*.unv``)
    or None (neither)."""
    from pathlib import Path

    folder = Path(folder)
    if not folder.is_dir():
        return None
    names = [q.name.lower() for q in folder.iterdir() if q.is_file()]
    if any(n.startswith("point") and n.endswith(".csv") for n in names):
        return "csv"
    if any(n.endswith((".uff", ".unv")) for n in names):
        return "uff"
    return None


def source_kind(sources) -> str:
    """``"csv"`` for one folder of ``point*.csv`` files, else ``"uff"``."""
    from pathlib import Path

    sources = [Path(s) for s in sources]
    return "csv" if len(sources) == 1 and test_folder_kind(sources[0]) == "csv" else "uff"


def read_source(sources, kind: str = "auto", mapping=None, channel_options=(), **attrs):
    """A Measurement from UFF 58 files/folders or one CSV folder (``docs/ingest.md``).

    Parameters
    ----------
    sources : sequence of paths
    kind : "auto", "uff" or "csv"
    mapping : path of the mapping file (TOML/JSON), optional
    channel_options : ``KEY=NAME,LOCATION,ANGLE_DEG`` strings
    attrs : inflation_pressure (Pa), tire, description — recorded in the measurement
    """
    # a cycle: the readers import this package's helpers (parse_channel, point_angles)
    from tiremodal_cli.io.ingest.csv import read_csv_folder
    from tiremodal_cli.io.ingest.uff import read_uff_time

    chans, points = load_channel_map(mapping, channel_options)
    kind = source_kind(sources) if kind == "auto" else kind
    if kind == "csv":
        if len(sources) != 1:
            raise ParameterError("CSV ingest takes one folder")
        return read_csv_folder(sources[0], chans, points, **attrs)
    if not chans:
        raise ParameterError("UFF ingest needs the channels: a mapping file's [channels] or "
                             "--channel NODE:DIR=NAME,LOCATION,ANGLE_DEG")
    return read_uff_time(sources, chans, points, **attrs)
