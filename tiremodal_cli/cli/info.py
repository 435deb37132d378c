"""``tiremodal info``: what a tiremodal file holds."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np
import pyuff

from tiremodal_cli.io import frffile, frfuff, measurement, modalfile
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import echo_json, json_option

DESCRIBERS = {measurement.FORMAT_NAME: lambda p: measurement.describe(
    measurement.read_measurement(p)),
              frffile.FORMAT_NAME: frffile.describe_frf, modalfile.FORMAT_NAME: modalfile.describe_modal}


def _human(d: dict) -> str:
    lines = []
    for k, v in d.items():
        if isinstance(v, list) and v and isinstance(v[0], dict):
            lines.append(f"{k}:")
            lines.extend("  " + ", ".join(f"{a}={b}" for a, b in item.items()) for item in v)
        elif isinstance(v, list) and len(v) > 8:
            lines.append(f"{k}: [{', '.join(f'{x:g}' for x in v[:4])}, …, {v[-1]:g}] ({len(v)})")
        elif isinstance(v, dict):
            lines.append(f"{k}: " + ", ".join(f"{a}={b}" for a, b in v.items()))
        else:
            lines.append(f"{k}: {v}")
    return "\n".join(lines)


@cli.command("info", epilog="\b\nExample:\n  tiremodal info sample_data/gl073a_sim.h5 --json")
@click.argument("file", type=click.Path(dir_okay=False, path_type=Path))
@json_option
def info_cmd(file, as_json):
    """Summarise a tiremodal FILE (measurement, FRF or modal file, or a UFF file).

    A UFF file of FRFs (dataset 58, function type 4) is described as ``run`` reads it: its
    form, the unit found and its factor to SI, the channels and where their locations and
    the points' angles come from; a UFF file of time records by its records.
    """
    if frfuff.is_uff(file):
        d = {"file": str(file), **_describe_uff(file)}
        echo_json(d) if as_json else click.echo(_human(d))
        return
    fmt = measurement.file_format(file)
    try:
        describe = DESCRIBERS[fmt]
    except KeyError:
        raise DataFormatError(f"{file}: format {fmt!r} is not one tiremodal knows; known: "
                              f"{', '.join(DESCRIBERS)}") from None
    d = {"file": str(file), **describe(file)}
    if as_json:
        echo_json(d)
    else:
        click.echo(_human(d))


def _describe_uff(path) -> dict:
    """A UFF file: FRFs as ``run`` reads them, else its time records counted."""
    if 4 in frfuff.uff_function_types([path]):
        return frfuff.describe_frf_uff(path)
    sets = pyuff.UFF(str(path)).read_sets()
    sets = [s for s in ([sets] if isinstance(sets, dict) else sets) if s.get("type") == 58]
    if not sets:
        raise DataFormatError(f"{path}: no dataset 58 (function records) in the UFF file")
    x = np.asarray(sets[0]["x"], dtype=float)
    force = [s for s in sets if int(s.get("ordinate_spec_data_type", 0) or 0) == 13]
    return {"format": "UFF 58 records", "function_types": sorted({int(s.get("func_type", 0)) for s in sets}),
            "n_records": len(sets), "n_force_records": len(force),
            "reference_nodes": sorted({int(s["ref_node"]) for s in sets}),
            "responses": sorted({f"{int(s['rsp_node'])}:{int(s['rsp_dir'])}" for s in sets if s not in force}),
            "n_samples": int(x.size), "sample_rate": float(1 / (x[1] - x[0])) if x.size > 1 else None,
            "read_by": "tiremodal ingest (time records, with a mapping of the channels)"}
