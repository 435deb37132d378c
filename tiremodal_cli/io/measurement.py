"""The measurement file, layout version 1 (``docs/format.md``): read, validate, write.

A roving-hammer test of one tyre at one condition is one HDF5 file holding the hammer
force and every response channel of every hit at every impact point.
"""

from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from tiremodal_cli.frf.hits import clipped_samples
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import atomic_path

__all__ = ["FORMAT_NAME", "FORMAT_VERSION", "LOCATIONS", "Measurement", "read_measurement",
           "write_measurement", "open_hdf5", "validate", "check_finite", "describe", "file_format", "open_measurement",
           "attr_str", "read_strings"]

FORMAT_NAME = "tiremodal.measurement"
FORMAT_VERSION = 1
#: shortest record accepted: 64 samples give 33 spectral lines, the least ``lsce``'s lowest
#: sweep (model order 2 per order and a stabilization over 16 orders) can use; ``simulate``
#: has the same lower bound
MIN_SAMPLES = 64
LOCATIONS = ("tread", "sidewall", "rim")


@dataclass(frozen=True)
class Measurement:
    """One roving-hammer test.

    Attributes
    ----------
    force : (n_points, n_hits, n_samples) ndarray, N
        Hammer force of each hit.
    response : (n_points, n_hits, n_channels, n_samples) ndarray, m/s²
        Radial accelerations (positive outwards) recorded with each hit.
    sample_rate : float, Hz
    point_angle : (n_points,) ndarray, rad
        Circumferential angle of each impact point on the tread.
    channel_name, channel_location : tuple of str, length n_channels
        ``channel_location`` is ``"tread"``, ``"sidewall"`` or ``"rim"``.
    channel_angle : (n_channels,) ndarray, rad
    inflation_pressure : float or None, Pa
    tire, description : str or None
    """

    force: np.ndarray
    response: np.ndarray
    sample_rate: float
    point_angle: np.ndarray
    channel_name: tuple[str, ...]
    channel_location: tuple[str, ...]
    channel_angle: np.ndarray
    inflation_pressure: float | None = None
    tire: str | None = None
    description: str | None = None

    def __post_init__(self):
        validate(self)

    @property
    def n_points(self) -> int:
        return self.force.shape[0]

    @property
    def n_hits(self) -> int:
        return self.force.shape[1]

    @property
    def n_samples(self) -> int:
        return self.force.shape[2]

    @property
    def n_channels(self) -> int:
        return self.response.shape[2]

    @property
    def duration(self) -> float:
        """Record length in s."""
        return self.n_samples / self.sample_rate


def _fail(where: str, what: str) -> None:
    raise DataFormatError(f"{where}: {what}")


def validate(m: Measurement, where: str = "measurement") -> None:
    """Check the structure of a :class:`Measurement` against layout version 1.

    Shapes, sizes, dtypes, angles and channel locations; see :func:`check_finite` for
    the samples themselves. Raises DataFormatError.
    """
    if not (np.isfinite(m.sample_rate) and m.sample_rate > 0):
        _fail(where, f"sample_rate={m.sample_rate!r} must be a positive finite number of Hz")
    f, r = m.force, m.response
    if f.ndim != 3:
        _fail(where, f"dataset 'force' has shape {f.shape}; expected (n_points, n_hits, n_samples)")
    if r.ndim != 4:
        _fail(where, f"dataset 'response' has shape {r.shape}; expected "
                     "(n_points, n_hits, n_channels, n_samples)")
    n_p, n_h, n_s = f.shape
    if (r.shape[0], r.shape[1], r.shape[3]) != (n_p, n_h, n_s):
        _fail(where, f"sizes do not match: force {f.shape} and response {r.shape} must share "
                     "n_points, n_hits and n_samples")
    if min(n_p, n_h, n_s, r.shape[2]) < 1:
        _fail(where, f"empty dataset: force {f.shape}, response {r.shape}")
    if n_s < MIN_SAMPLES:
        _fail(where, f"records of {n_s} samples; allowed: at least {MIN_SAMPLES} (a spectrum of "
                     f"{MIN_SAMPLES // 2 + 1} lines, the fewest a modal estimate can use)")
    p = m.inflation_pressure
    if p is not None and not (isinstance(p, (int, float, np.floating, np.integer)) and np.isfinite(p) and p > 0):
        _fail(where, f"inflation_pressure={p!r}; allowed: a positive finite pressure in Pa, or none")
    for name, arr in (("force", f), ("response", r)):
        if arr.dtype not in (np.float32, np.float64):
            _fail(where, f"dataset {name!r} has dtype {arr.dtype}; allowed: float32, float64")
    n_c = r.shape[2]
    if m.point_angle.shape != (n_p,):
        _fail(where, f"dataset 'point_angle' has shape {m.point_angle.shape}; expected ({n_p},)")
    for name, val in (("channel_name", m.channel_name), ("channel_location", m.channel_location)):
        if len(val) != n_c:
            _fail(where, f"dataset {name!r} has {len(val)} entries; expected n_channels={n_c}")
    if m.channel_angle.shape != (n_c,):
        _fail(where, f"dataset 'channel_angle' has shape {m.channel_angle.shape}; expected ({n_c},)")
    for name, arr in (("point_angle", m.point_angle), ("channel_angle", m.channel_angle)):
        if not np.all(np.isfinite(arr)):
            _fail(where, f"dataset {name!r} holds non-finite angles")
    bad = [loc for loc in m.channel_location if loc not in LOCATIONS]
    if bad:
        _fail(where, f"channel_location {bad[0]!r} is not allowed; allowed: {', '.join(LOCATIONS)}")
    if "tread" not in m.channel_location:
        _fail(where, "no tread channel; at least one channel_location must be 'tread'")
    if len(set(m.channel_name)) != n_c:
        _fail(where, f"channel names are not unique: {list(m.channel_name)}")


def check_finite(m: Measurement, where: str = "measurement") -> None:
    """Raise DataFormatError if any force or response sample is NaN or infinite."""
    for name, arr in (("force", m.force), ("response", m.response)):
        finite = np.isfinite(arr)
        if not finite.all():
            idx = tuple(int(i) for i in np.argwhere(~finite)[0])
            _fail(where, f"dataset {name!r} holds non-finite samples (first at index {idx})")


def open_hdf5(path: str | os.PathLike, what: str = "a measurement file (HDF5, docs/format.md)") -> h5py.File:
    """Open an HDF5 file read-only, turning every failure into one DataFormatError line
    that says what the file should be (``what``)."""
    path = Path(path)
    if not path.is_file():
        raise DataFormatError(f"{path}: no such file")
    try:
        return h5py.File(path, "r")
    except OSError:
        raise DataFormatError(f"{path}: not a readable HDF5 file (truncated, or another format); "
                              f"allowed: {what}") from None


def read_strings(ds) -> tuple[str, ...]:
    """The strings of an HDF5 string dataset (UTF-8 bytes decoded), as a tuple."""
    return tuple(v.decode("utf-8") if isinstance(v, bytes) else str(v) for v in ds[()])


def attr_str(attrs, name) -> str | None:
    """An HDF5 attribute as a str (UTF-8 bytes decoded); None when absent."""
    if name not in attrs:
        return None
    v = attrs[name]
    return v.decode("utf-8") if isinstance(v, bytes) else str(v)


def _read_header(h, where: str, *, lazy: bool) -> dict:
    """Root attributes and datasets of a measurement file, checked for presence and type."""
    fmt = attr_str(h.attrs, "format")
    if fmt is None:
        _fail(where, f"root attribute 'format' is missing; expected format={FORMAT_NAME!r}")
    if fmt != FORMAT_NAME:
        _fail(where, f"format={fmt!r} is not a measurement; expected {FORMAT_NAME!r}")
    if "format_version" not in h.attrs:
        _fail(where, "root attribute 'format_version' is missing")
    version = h.attrs["format_version"]
    if not (np.ndim(version) == 0 and int(version) == version and int(version) == FORMAT_VERSION):
        _fail(where, f"unknown format_version {np.asarray(version).tolist()!r}; "
                     f"this tiremodal reads version {FORMAT_VERSION}")
    if "sample_rate" not in h.attrs:
        _fail(where, "root attribute 'sample_rate' is missing")
    data = {}
    for name in ("force", "response", "point_angle", "channel_name", "channel_location",
                 "channel_angle"):
        if name not in h:
            _fail(where, f"dataset {name!r} is missing")
        if not isinstance(h[name], h5py.Dataset):
            _fail(where, f"{name!r} is not a dataset")
    try:
        data["force"] = h["force"] if lazy else h["force"][()]
        data["response"] = h["response"] if lazy else h["response"][()]
        data["point_angle"] = np.asarray(h["point_angle"][()], dtype=np.float64)
        data["channel_angle"] = np.asarray(h["channel_angle"][()], dtype=np.float64)
        data["channel_name"] = read_strings(h["channel_name"])
        data["channel_location"] = read_strings(h["channel_location"])
    except (OSError, ValueError, TypeError) as exc:
        _fail(where, f"cannot read the datasets ({exc.__class__.__name__}: {exc}); "
                     "the file may be truncated")
    for name in ("force", "response"):
        if data[name].dtype.kind != "f":
            _fail(where, f"dataset {name!r} has dtype {data[name].dtype}; allowed: float32, float64")
    pressure = h.attrs.get("inflation_pressure")
    sr = h.attrs["sample_rate"]
    try:
        sr = float(sr)
    except (TypeError, ValueError):
        _fail(where, f"sample_rate={sr!r} is not a number")
    if pressure is not None:
        try:
            pressure = float(pressure)
        except (TypeError, ValueError):
            _fail(where, f"inflation_pressure={attr_str(h.attrs, 'inflation_pressure')!r} is not a number; "
                         "allowed: a positive finite pressure in Pa, or no attribute")
    kwargs = dict(sample_rate=sr,
                  inflation_pressure=pressure,
                  tire=attr_str(h.attrs, "tire"),
                  description=attr_str(h.attrs, "description"))
    return {**data, **kwargs}


@contextlib.contextmanager
def open_measurement(path: str | os.PathLike):
    """A validated Measurement whose ``force`` and ``response`` are lazy h5py datasets.

    For stages that work point by point (``m.force[ip]`` reads one point): memory stays
    at one point's records. Samples are not checked for finiteness here.
    """
    where = str(path)
    h = open_hdf5(path)
    try:
        kwargs = _read_header(h, where, lazy=True)
        try:
            m = Measurement(**kwargs)
        except DataFormatError as exc:
            raise DataFormatError(str(exc).replace("measurement: ", f"{where}: ", 1)) from None
        yield m
    finally:
        h.close()


def read_measurement(path: str | os.PathLike, *, allow_nonfinite: bool = False) -> Measurement:
    """Read and validate a measurement file (layout version 1).

    Parameters
    ----------
    path : path-like
    allow_nonfinite : bool, keyword-only
        Accept NaN/inf samples (the FRF stage rejects such hits itself); by default a
        non-finite sample is a format error.

    Raises
    ------
    DataFormatError
        With one line naming the file and what is wrong.
    """
    where = str(path)
    with open_hdf5(path) as h:
        kwargs = _read_header(h, where, lazy=False)
    try:
        m = Measurement(**kwargs)
    except DataFormatError as exc:
        raise DataFormatError(str(exc).replace("measurement: ", f"{where}: ", 1)) from None
    if not allow_nonfinite:
        check_finite(m, where)
    return m


def write_measurement(path: str | os.PathLike, m: Measurement, *, overwrite: bool = False,
                      compression: str | None = None, extra: dict | None = None) -> Path:
    """Write ``m`` as a layout-version-1 file, atomically.

    Parameters
    ----------
    compression : {None, "gzip"}, keyword-only
        HDF5 filter for the two record datasets (``gzip`` with shuffle keeps sample data small).
    extra : dict, optional
        Additional root attributes (readers ignore them).
    """
    comp = dict(compression="gzip", compression_opts=6, shuffle=True) if compression else {}
    str_dt = h5py.string_dtype("utf-8")
    with atomic_path(path, overwrite=overwrite) as tmp:
        with h5py.File(tmp, "w") as h:
            h.attrs["format"] = FORMAT_NAME
            h.attrs["format_version"] = FORMAT_VERSION
            h.attrs["sample_rate"] = float(m.sample_rate)
            if m.inflation_pressure is not None:
                h.attrs["inflation_pressure"] = float(m.inflation_pressure)
            for name in ("tire", "description"):
                if getattr(m, name) is not None:
                    h.attrs[name] = getattr(m, name)
            for k, v in (extra or {}).items():
                h.attrs[k] = v
            h.create_dataset("force", data=m.force, **comp)
            h.create_dataset("response", data=m.response, **comp)
            h.create_dataset("point_angle", data=np.asarray(m.point_angle, dtype=np.float64))
            h.create_dataset("channel_name", data=list(m.channel_name), dtype=str_dt)
            h.create_dataset("channel_location", data=list(m.channel_location), dtype=str_dt)
            h.create_dataset("channel_angle", data=np.asarray(m.channel_angle, dtype=np.float64))
    return Path(path)


def file_format(path: str | os.PathLike,
                what: str = "a tiremodal HDF5 file (measurement, FRFs or modes), or UFF named *.uff or *.unv") -> str:
    """The ``format`` attribute of a tiremodal HDF5 file (DataFormatError if none; ``what``:
    what the caller reads, said when the file is not HDF5 at all)."""
    with open_hdf5(path, what) as h:
        fmt = attr_str(h.attrs, "format")
    if fmt is None:
        raise DataFormatError(f"{path}: not a tiremodal file (no root attribute 'format')")
    return fmt


def describe(m: Measurement) -> dict:
    """Summary of a measurement: sizes, rate, duration, peak force, clipped samples.

    Clipped samples are those in runs at a record's extreme value
    (:func:`tiremodal_cli.frf.hits.clipped_samples`).
    """
    fin_f = np.isfinite(m.force)
    return {
        "format": FORMAT_NAME, "format_version": FORMAT_VERSION,
        "n_points": m.n_points, "n_hits": m.n_hits, "n_channels": m.n_channels,
        "n_samples": m.n_samples, "sample_rate": m.sample_rate, "duration_s": m.duration,
        "frequency_resolution_hz": m.sample_rate / m.n_samples,
        "channels": [{"name": n, "location": loc, "angle_deg": float(np.rad2deg(a))}
                     for n, loc, a in zip(m.channel_name, m.channel_location, m.channel_angle)],
        "point_angle_deg": [float(x) for x in np.rad2deg(m.point_angle)],
        "peak_force_n": float(np.max(np.abs(np.where(fin_f, m.force, 0)))),
        "clipped_samples": {"force": int(clipped_samples(np.nan_to_num(m.force)).sum()),
                            **{n: int(clipped_samples(np.nan_to_num(m.response[:, :, i])).sum())
                               for i, n in enumerate(m.channel_name)}},
        "non_finite_samples": int((~fin_f).sum() + (~np.isfinite(m.response)).sum()),
        "inflation_pressure_pa": m.inflation_pressure, "tire": m.tire, "description": m.description,
        "dtype": str(m.response.dtype),
    }
