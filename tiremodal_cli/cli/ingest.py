"""``tiremodal ingest``: UFF 58 time records or a CSV folder → a measurement file."""

from __future__ import annotations

from pathlib import Path

import click

from ..ingest import load_channel_map
from ..ingest.csv import read_csv_folder
from ..ingest.uff import read_uff_time
from ..measurement import describe, write_measurement
from .main import cli
from .options import echo_json, json_option, overwrite_option


@cli.command("ingest")
@click.argument("sources", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="Measurement file to write (HDF5).")
@click.option("--from", "source_kind", type=click.Choice(["auto", "uff", "csv"]), default="auto",
              show_default=True, help="Source kind; auto: a folder of CSV files, else UFF.")
@click.option("--mapping", type=click.Path(exists=True, dir_okay=False),
              help="TOML/JSON with [points] (key → angle_deg) and [channels] (key → name, location, angle_deg).")
@click.option("--channel", "channel_opts", multiple=True, metavar="KEY=NAME,LOCATION,ANGLE_DEG",
              help="A channel (UFF key NODE:DIR, CSV key the column name); repeatable.")
@click.option("--pressure", type=float, help="Inflation pressure to record, Pa.")
@click.option("--tire", help="Free text: size, model, serial.")
@overwrite_option
@json_option
def ingest_cmd(sources, output, source_kind, mapping, channel_opts, pressure, tire, overwrite, as_json):
    """Convert SOURCES (UFF 58 files/folders, or one CSV folder) into a measurement file."""
    chans, points = load_channel_map(mapping, channel_opts)
    kind = source_kind
    if kind == "auto":
        csvs = len(sources) == 1 and sources[0].is_dir() and any(sources[0].glob("point*.csv"))
        kind = "csv" if csvs else "uff"
    attrs = dict(inflation_pressure=pressure, tire=tire, description=f"ingested from {kind}: "
                 + ", ".join(map(str, sources))[:200])
    if kind == "csv":
        if len(sources) != 1:
            raise click.UsageError("CSV ingest takes one folder")
        m = read_csv_folder(sources[0], chans, points, **attrs)
    else:
        if not chans:
            raise click.UsageError("UFF ingest needs the channels: --mapping FILE or --channel NODE:DIR=NAME,LOCATION,ANGLE_DEG")
        m = read_uff_time(sources, chans, points, **attrs)
    write_measurement(output, m, overwrite=overwrite)
    d = {"output": str(output), **describe(m)}
    if as_json:
        echo_json(d)
    else:
        click.echo(f"wrote {output}: {m.n_points} points × {m.n_hits} hits × {m.n_channels} channels, "
                   f"{m.n_samples} samples at {m.sample_rate:g} Hz", err=True)
