"""``tiremodal export``: mode shapes for other programs (UFF 15/82/55 or CSV, GIFs)."""

from __future__ import annotations

from pathlib import Path

import click

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import refuse_input_as_output
from tiremodal_cli.io.export import DEFAULT_RADII_M, FORMATS, export_folder
from tiremodal_cli.io.modalfile import read_modal
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import Progress, echo_json, json_option, overwrite_option, parse_key_values, say


def _modal_path(source: Path) -> Path:
    if source.is_dir():
        p = source / "modal.h5"
        if not p.is_file():
            raise DataFormatError(f"{source}: not a run folder (no modal.h5); give a run folder or a modal file")
        return p
    return source


@cli.command("export", epilog="\b\nExample:\n  tiremodal export out/gl073a -o out/gl073a-shapes --format uff --gif")
@click.argument("source", type=click.Path(exists=True, path_type=Path))
@click.option("-o", "--output", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Folder to write (created whole, or not at all).")
@click.option("--format", "fmt", type=click.Choice(FORMATS), default="uff", show_default=True,
              help="uff: shapes.uff (UFF 15 nodes, 82 trace lines, 55 complex shapes); csv: nodes.csv, shapes.csv.")
@click.option("--radius", "radii", multiple=True, metavar="RING=METRES",
              help="Radius of a ring of nodes: tread, sidewall or rim (defaults "
                   + ", ".join(f"{k} {v} m" for k, v in DEFAULT_RADII_M.items()) + ").")
@click.option("--gif", is_flag=True, help="Also modes/mode_NN.gif: each mode shape moving.")
@overwrite_option
@json_option
def export_cmd(source, output, fmt, radii, gif, overwrite, as_json):
    """Export the mode shapes of SOURCE (a run folder or a modal file) into the folder OUTPUT.

    One ring of nodes per measured location (tread, sidewall, rim) at the impact points'
    angles; each mode's radial shape, scaled to a largest tread value of 1.
    """
    values = parse_key_values(radii, "--radius")
    radii_m = {}
    for k, v in values.items():
        if k not in DEFAULT_RADII_M:
            raise click.BadParameter(f"ring {k!r}; allowed: {', '.join(DEFAULT_RADII_M)}", param_hint="--radius")
        try:
            radii_m[k] = float(v)
        except ValueError:
            raise click.BadParameter(f"{k}={v!r} is not a number of metres", param_hint="--radius") from None
        if not 0 < radii_m[k] < 10:
            raise click.BadParameter(f"{k}={v} m; allowed: 0 < radius < 10 m", param_hint="--radius")
    src = _modal_path(source)
    refuse_input_as_output({"--output": output}, {"SOURCE": source})
    table = read_modal(src)
    bar = Progress("export") if gif else None
    try:
        summary = export_folder(table, output, fmt=fmt, radii_m=radii_m, gif=gif, overwrite=overwrite,
                                name=src.stem, progress=bar)
    finally:
        if bar is not None:
            bar.close()
    if as_json:
        echo_json(summary)
    else:
        say(f"wrote {output}/ ({', '.join(summary['files'][:3])}{' …' if len(summary['files']) > 3 else ''}): "
                   f"{summary['modes']} modes on {summary['nodes']} nodes")
        for item in summary["left_out"]:
            say(f"left out: {item}")
