"""``tiremodal predict``: the tyre model's modal table for given parameters."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import click
import numpy as np

from ..files import check_overwrite, write_text_atomic
from ..model import paper_damping, solve_modes
from .main import cli
from .options import echo_json, json_option, load_params, overwrite_option, params_options


@cli.command("predict")
@params_options
@click.option("--n-max", type=click.IntRange(1, 200), default=12, show_default=True, help="Highest order listed.")
@click.option("--csv", "csv_out", type=click.Path(dir_okay=False, path_type=Path), help="Write the table as CSV.")
@click.option("--plot", "plot_out", type=click.Path(dir_okay=False, path_type=Path), help="Frequency against n.")
@overwrite_option
@json_option
def predict_cmd(params_file, param_items, n_max, csv_out, plot_out, overwrite, as_json):
    """Modes of the model: frequency of every (n, branch) up to --n-max (the cos members)."""
    for o in (csv_out, plot_out):
        if o is not None:
            check_overwrite(o, overwrite)
    p, effects = load_params(params_file, param_items)
    m = solve_modes(p, n_max=max(n_max, 2), effects=effects or None)
    rows = [{"n": int(n), "branch": b, "frequency_hz": float(f), "damping_ratio_default": paper_damping(int(n), b)}
            for f, n, h, b in zip(m.freq_hz, m.n, m.harmonic, m.branch) if h in ("cos", "mixed") and n <= n_max]
    if csv_out:
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        write_text_atomic(csv_out, buf.getvalue(), overwrite=overwrite)
    if plot_out:
        from ..plots import plot_dispersion, save_figure

        ax = plot_dispersion([{"n": r["n"], "branch": r["branch"], "model_hz": r["frequency_hz"]} for r in rows])
        save_figure(ax.figure, plot_out, overwrite=overwrite)
    if as_json:
        echo_json({"parameters": p.to_dict(), "effects": effects, "modes": rows})
    else:
        click.echo(f"{'n':>3} {'branch':>9} {'f [Hz]':>10}")
        for r in rows:
            click.echo(f"{r['n']:3d} {r['branch']:>9} {r['frequency_hz']:10.3f}")
