"""``tiremodal ingest``: UFF 58 time records or a CSV folder → a measurement file."""

from __future__ import annotations

from pathlib import Path

import click

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.io.files import refuse_input_as_output
from tiremodal_cli.io.ingest import read_source, source_kind
from tiremodal_cli.io.measurement import describe, write_measurement
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import FiniteRange, echo_json, json_option, overwrite_option, say


def _read_by_ingest(path: Path) -> bool:
    """Whether ingest reads a file of this name from a source folder (docs/ingest.md)."""
    name = path.name.lower()
    return path.suffix.lower() in (".uff", ".unv") or (name.startswith("point") and name.endswith(".csv"))


@cli.command("ingest", epilog="\b\nExample:\n  tiremodal ingest sample_data/uff --mapping sample_data/uff/mapping.toml -o from_uff.h5")
@click.argument("sources", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="Measurement file to write (HDF5).")
@click.option("--from", "source_kind_opt", type=click.Choice(["auto", "uff", "csv"]), default="auto",
              show_default=True, help="Source kind; auto: a folder of CSV files, else UFF.")
@click.option("--mapping", type=click.Path(exists=True, dir_okay=False),
              help="TOML/JSON with [points] (key → angle_deg) and [channels] (key → name, location, angle_deg).")
@click.option("--channel", "channel_opts", multiple=True, metavar="KEY=NAME,LOCATION,ANGLE_DEG",
              help="A channel (UFF key NODE:DIR, CSV key the column name); repeatable.")
@click.option("--pressure", type=FiniteRange(0, min_open=True), help="Inflation pressure to record, Pa (> 0).")
@click.option("--tire", help="Free text: size, model, serial.")
@overwrite_option
@json_option
def ingest_cmd(sources, output, source_kind_opt, mapping, channel_opts, pressure, tire, overwrite, as_json):
    """Convert SOURCES (UFF 58 files/folders, or one CSV folder) into a measurement file."""
    refuse_input_as_output({"--output": output}, {**{"source": s for s in sources}, "--mapping": mapping},
                           read_from_folder=_read_by_ingest)
    for s in sources:
        if not s.exists():
            raise ParameterError(f"source {str(s)!r}: no such file or folder")
    if source_kind_opt == "auto" and all(s.is_dir() for s in sources) and source_kind(sources) == "uff" \
            and not any(f.suffix.lower() in (".uff", ".unv") for s in sources for f in s.iterdir()):
        raise ParameterError(f"source {', '.join(map(str, sources))!r}: no point*.csv nor *.uff/*.unv files; "
                             "allowed: one folder of point*.csv files, or UFF 58 files/folders")
    kind = source_kind(sources) if source_kind_opt == "auto" else source_kind_opt
    attrs = dict(inflation_pressure=pressure, tire=tire, description=f"ingested from {kind}: "
                 + ", ".join(map(str, sources))[:200])
    try:
        m = read_source(sources, kind, mapping, channel_opts, **attrs)
    except ParameterError as exc:
        raise click.UsageError(str(exc)) from None
    write_measurement(output, m, overwrite=overwrite)
    d = {"output": str(output), **describe(m)}
    if as_json:
        echo_json(d)
    else:
        say(f"wrote {output}: {m.n_points} points × {m.n_hits} hits × {m.n_channels} channels, "
                   f"{m.n_samples} samples at {m.sample_rate:g} Hz")
