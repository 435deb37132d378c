"""``tiremodal info``: what a tiremodal file holds."""

from __future__ import annotations

from pathlib import Path

import click

from .. import frffile, measurement, modalfile
from ..errors import DataFormatError
from .main import cli
from .options import echo_json, json_option

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
    """Summarise a tiremodal FILE (measurement, FRF or modal file)."""
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
