"""UFF dataset 58 time records (through pyuff) ⇄ the measurement layout.

Reading rules (``docs/ingest.md``):

* function type 1 (time response) only; abscissa evenly spaced, the same for all records;
* a force record has ordinate specific data type 13 (excitation force); its reference
  node is the impact point; every other record is a response, an acceleration (type 12)
  in m/s², keyed ``"rsp_node:rsp_dir"`` in the channel mapping;
* hits are told apart by the load case number (record 6, field 4) within one reference
  node, in increasing order; when all load cases are equal, by order of appearance.
"""

from __future__ import annotations

import os
from collections import defaultdict
from pathlib import Path

import numpy as np

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import atomic_path
from tiremodal_cli.io.measurement import Measurement
from tiremodal_cli.io.ingest import point_angles

__all__ = ["read_uff_time", "write_uff_time", "uff_files"]

FORCE, ACCELERATION = 13, 12
# Record 8–11 fields that pyuff's writer requires; SI units, exponents 0.
_UNITS = {f"{axis}_{what}": 0 for axis in ("abscissa", "ordinate", "orddenom", "z_axis")
          for what in ("len_unit_exp", "force_unit_exp", "temp_unit_exp")}
_UNITS.update(abscissa_axis_units_lab="s", orddenom_spec_data_type=0, orddenom_axis_units_lab="NONE",
              z_axis_spec_data_type=0, z_axis_axis_units_lab="NONE", z_axis_value=0.0)


def uff_files(paths) -> list[Path]:
    """Expand files and folders (``*.uff``, ``*.unv``) into a sorted list of files."""
    out = []
    for p in map(Path, paths):
        if p.is_dir():
            out.extend(sorted(q for q in p.iterdir() if q.suffix.lower() in (".uff", ".unv")))
        elif p.is_file():
            out.append(p)
        else:
            raise DataFormatError(f"{p}: no such file or folder")
    if not out:
        raise DataFormatError(f"no UFF files (*.uff, *.unv) in {', '.join(map(str, paths))}")
    return out


def _sets(path: Path) -> list[dict]:
    import pyuff  # (imported when used: 20 ms of every start-up otherwise)
    try:
        sets = pyuff.UFF(str(path)).read_sets()
    except Exception as exc:  # pyuff raises bare Exception/ValueError/IndexError on bad files
        raise DataFormatError(f"{path}: not a readable UFF file ({exc.__class__.__name__}: {exc})") from None
    sets = [sets] if isinstance(sets, dict) else list(sets)
    return [s for s in sets if s.get("type") == 58]


def read_uff_time(paths, channels: dict, points: dict | None = None, **attrs) -> Measurement:
    """Build a Measurement from UFF 58 time records.

    Parameters
    ----------
    paths : sequence of path-like      files or folders
    channels : mapping ``{"node:dir": (name, location, angle_rad)}``
    points : mapping ``{"node": angle_rad}``, optional (uniform in node order if empty)
    attrs : inflation_pressure, tire, description
    """
    files = uff_files(paths)
    force, resp, dt = _collect(files, channels)
    if not force:
        raise DataFormatError(f"{files[0]}: no force record (ordinate specific data type 13)")
    ch_keys = list(channels)
    nodes, F, Y = _arrays(force, resp, ch_keys)
    # The abscissa increment field (%13.5e) carries 6 significant digits: round 1/Δt to those.
    return Measurement(force=F, response=Y, sample_rate=float(f"{1.0 / dt:.6g}"),
                       point_angle=point_angles(nodes, points or {}, str(files[0])),
                       channel_name=tuple(channels[k][0] for k in ch_keys),
                       channel_location=tuple(channels[k][1] for k in ch_keys),
                       channel_angle=np.array([channels[k][2] for k in ch_keys]),
                       inflation_pressure=attrs.get("inflation_pressure"),
                       tire=attrs.get("tire"), description=attrs.get("description"))


def _collect(files: list[Path], channels: dict):
    """Every time record of the files, checked: ``force[ref node][hit key]``,
    ``resp[ref node][load case][channel key]`` (a list: hits without a load case), and the
    common sample interval (s). A hit's key is (load case, its order among the point's forces)."""
    force = defaultdict(dict)  # node -> {hit key: data}
    resp = defaultdict(lambda: defaultdict(dict))  # node -> hit key -> channel key -> data
    dt = None
    order = defaultdict(int)
    for f in files:
        sets = _sets(f)
        if not sets:
            raise DataFormatError(f"{f}: no dataset 58 in the file")
        for s in sets:
            where = f"{f}: record node {s.get('rsp_node')}:{s.get('rsp_dir')}"
            d = _time_step(s, where)
            if dt is None:
                dt = d
            elif not np.isclose(d, dt, rtol=1e-9):
                raise DataFormatError(f"{where}: sample interval {d:g} s differs from {dt:g} s")
            ref = str(int(s["ref_node"]))
            lc = int(s.get("load_case_id", 0) or 0)
            data = np.asarray(s["data"])
            if np.iscomplexobj(data):
                raise DataFormatError(f"{where}: complex data; time records are real")
            if int(s.get("ordinate_spec_data_type", 0) or 0) == FORCE:
                key = (lc, order[ref]) if lc else (0, order[ref])
                order[ref] += 1
                force[ref][key] = data
            else:
                resp[ref][lc].setdefault(_channel_key(s, channels, where), []).append(data)
    return force, resp, dt


def _time_step(s: dict, where: str) -> float:
    """The record's sample interval (s); DataFormatError unless it is a time record evenly sampled."""
    if int(s.get("func_type", 0)) != 1:
        raise DataFormatError(f"{where}: function type {s.get('func_type')} is not 1 (time response)")
    x = np.asarray(s["x"], dtype=float)
    d = x[1] - x[0] if x.size > 1 else 0.0
    if d <= 0 or not np.allclose(np.diff(x), d, rtol=1e-6, atol=0):
        raise DataFormatError(f"{where}: abscissa is not evenly spaced time")
    return d


def _channel_key(s: dict, channels: dict, where: str) -> str:
    """A response record's ``"node:dir"``, checked against the mapping and its ordinate type."""
    kind = int(s.get("ordinate_spec_data_type", 0) or 0)
    if kind not in (ACCELERATION, 0):
        raise DataFormatError(f"{where}: ordinate type {kind} is neither force (13) nor "
                              "acceleration (12)")
    ck = f"{int(s['rsp_node'])}:{int(s['rsp_dir'])}"
    if ck not in channels:
        raise DataFormatError(f"{where}: response {ck} is not in the channel mapping; "
                              f"mapped: {', '.join(channels) or 'none'}")
    return ck


def _arrays(force: dict, resp: dict, ch_keys: list[str]):
    """The point nodes (sorted), force (n_points, n_hits, n_samples) and responses
    (n_points, n_hits, n_channels, n_samples); every hit needs every channel once."""
    nodes = sorted(force, key=lambda k: int(k))
    n_hits = {len(force[n]) for n in nodes}
    if len(n_hits) != 1:
        raise DataFormatError(f"points have different numbers of hits ({sorted(n_hits)}); the layout needs one")
    n_h = n_hits.pop()
    lengths = {v.size for n in nodes for v in force[n].values()}
    if len(lengths) != 1:
        raise DataFormatError(f"records have different lengths ({sorted(lengths)})")
    ns = lengths.pop()
    F = np.zeros((len(nodes), n_h, ns))
    Y = np.zeros((len(nodes), n_h, len(ch_keys), ns))
    for ip, n in enumerate(nodes):
        lcs = sorted(resp[n])
        for ih, hk in enumerate(sorted(force[n])):
            F[ip, ih] = force[n][hk]
            lc = hk[0]
            for ic, ck in enumerate(ch_keys):
                recs = resp[n].get(lc, {}).get(ck, [])
                idx = ih if lc == 0 else 0
                if lc == 0 and len(recs) != n_h or lc != 0 and len(recs) != 1:
                    raise DataFormatError(f"point node {n}, hit {ih + 1}: response {ck} missing or repeated "
                                          f"(load cases seen: {lcs})")
                if recs[idx].size != ns:
                    raise DataFormatError(f"point node {n}, hit {ih + 1}: response {ck} has "
                                          f"{recs[idx].size} samples, force has {ns}")
                Y[ip, ih, ic] = recs[idx]
    return nodes, F, Y


def write_uff_time(folder: str | os.PathLike, m: Measurement, *, point_node0: int = 101,
                   binary: bool = True, overwrite: bool = False) -> tuple[list[Path], dict]:
    """Write ``m`` as UFF 58 time records, one file per impact point, plus its mapping.

    Points are nodes ``point_node0 + i`` (direction +Z = 3, radial), channels nodes
    ``1 … n_channels`` (direction 3). Returns the files and the mapping dict (TOML-ready).
    """
    import pyuff  # (imported when used: 20 ms of every start-up otherwise)
    folder = Path(folder)
    files = []
    for ip in range(m.n_points):
        node = point_node0 + ip
        path = folder / f"point{ip + 1:03d}.uff"
        with atomic_path(path, overwrite=overwrite) as tmp:
            tmp.unlink()
            uff = pyuff.UFF(str(tmp))
            sets = []
            for ih in range(m.n_hits):
                common = dict(binary=int(binary), func_type=1, load_case_id=ih + 1, ref_node=node, ref_dir=3,
                              abscissa_spacing=1, abscissa_min=0.0, abscissa_inc=1.0 / m.sample_rate,
                              abscissa_spec_data_type=17, x=np.arange(m.n_samples) / m.sample_rate,
                              id1=f"tiremodal point {ip + 1} hit {ih + 1}", **_UNITS)
                sets.append(pyuff.prepare_58(**common, rsp_node=node, rsp_dir=3, ordinate_spec_data_type=FORCE,
                                             ordinate_axis_units_lab="N",
                                             data=np.asarray(m.force[ip, ih], dtype=float),
                                             id2="force N"))
                for ic in range(m.n_channels):
                    sets.append(pyuff.prepare_58(**common, rsp_node=ic + 1, rsp_dir=3,
                                                 ordinate_spec_data_type=ACCELERATION,
                                                 ordinate_axis_units_lab="m/s^2",
                                                 data=np.asarray(m.response[ip, ih, ic], dtype=float),
                                                 id2=f"{m.channel_name[ic]} m/s2"))
            # pyuff writes binary 58 in double precision only (its single-precision path packs
            # doubles under a single-precision header), so the files are twice the float32 size.
            uff.write_sets(sets, mode="add")
        files.append(path)
    mapping = {"points": {str(point_node0 + i): float(np.rad2deg(a)) for i, a in enumerate(m.point_angle)},
               "channels": {f"{ic + 1}:3": {"name": m.channel_name[ic], "location": m.channel_location[ic],
                                            "angle_deg": float(np.rad2deg(m.channel_angle[ic]))}
                            for ic in range(m.n_channels)}}
    return files, mapping
