"""``tiremodal report``: self-contained HTML of a run folder, or of every test of a batch."""

from __future__ import annotations

from pathlib import Path

import click

from tiremodal_cli.workflow.report import report
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import Progress, echo_json, json_option


@cli.command("report", epilog="\b\nExample:\n  tiremodal report out/gl073a")
@click.argument("outdir", type=click.Path(file_okay=False, path_type=Path))
@json_option
def report_cmd(outdir, as_json):
    """Write report.html (figures embedded; also as PNG and SVG in figures/) for the run
    folder OUTDIR, or for every test of the batch folder OUTDIR plus its index.html.

    Pages and figures are replaced on each call (they are views of the outputs).
    """
    bar = Progress("report")
    try:
        pages = report(outdir, progress=lambda name, done, total: bar(done, total))
    finally:
        bar.close()
    if as_json:
        echo_json({"pages": [str(p) for p in pages]})
    else:
        for p in pages:
            click.echo(str(p))
