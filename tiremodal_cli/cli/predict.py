"""``tiremodal predict``: the tyre model's modal table for given parameters."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from tiremodal_cli.io.files import check_overwrite, refuse_input_as_output, write_text_atomic
from tiremodal_cli.io.frffile import read_frf
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.tyre.model import paper_damping
from tiremodal_cli.tyre.solve import frf as model_frf
from tiremodal_cli.tyre.solve import solve_modes
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import FiniteRange, PlotPath, echo_json, json_option, load_params, overwrite_option, params_options
from tiremodal_cli.workflow.summary import rows_to_csv
# Start-up: matplotlib (tiremodal_cli.plots) is imported inside the functions, only when a figure is asked for.


@cli.command("predict", epilog="\b\nExample:\n  tiremodal predict --n-max 12 --csv predicted.csv")
@params_options
@click.option("--n-max", type=click.IntRange(1, 200), default=12, show_default=True, help="Highest order listed.")
@click.option("--csv", "csv_out", type=click.Path(dir_okay=False, path_type=Path), help="Write the table as CSV.")
@click.option("--plot", "plot_out", type=PlotPath(), help="Frequency against n.")
@click.option("--compare-frf", type=click.Path(dir_okay=False, path_type=Path),
              help="An FRF file: draw the model's FRFs over the measured ones (the paper's Fig. 9).")
@click.option("--plot-frf", type=PlotPath(), help="Where to draw that comparison.")
@click.option("--point", type=click.IntRange(1), default=1, show_default=True, help="Impact point of the comparison.")
@click.option("--damping", type=FiniteRange(0, 1, min_open=True, max_open=True),
              help="Modal damping for the model's FRFs (default: the paper's by n and branch).")
@overwrite_option
@json_option
def predict_cmd(params_file, param_items, n_max, csv_out, plot_out, compare_frf, plot_frf, point, damping, overwrite,
                as_json):
    """Modes of the model: frequency of every (n, branch) up to --n-max (the cos members)."""
    refuse_input_as_output({"--csv": csv_out, "--plot": plot_out, "--plot-frf": plot_frf},
                           {"--params": params_file, "--compare-frf": compare_frf})
    for o in (csv_out, plot_out, plot_frf):
        if o is not None:
            check_overwrite(o, overwrite)
    if (compare_frf is None) != (plot_frf is None):
        raise click.UsageError("--compare-frf and --plot-frf go together")
    p, effects = load_params(params_file, param_items)
    m = solve_modes(p, n_max=max(n_max, 2), effects=effects or None)
    if compare_frf is not None:
        _compare(p, effects, compare_frf, plot_frf, point, damping, overwrite)
    rows = [{"n": int(n), "branch": b, "frequency_hz": float(f), "damping_ratio_default": paper_damping(int(n), b)}
            for f, n, h, b in zip(m.freq_hz, m.n, m.harmonic, m.branch) if h in ("cos", "mixed") and n <= n_max]
    if csv_out:
        write_text_atomic(csv_out, rows_to_csv(rows), overwrite=overwrite)
    if plot_out:
        from tiremodal_cli.plots import plot_dispersion, save_figure

        ax = plot_dispersion([{"n": r["n"], "branch": r["branch"], "model_hz": r["frequency_hz"]} for r in rows])
        save_figure(ax.figure, plot_out, overwrite=overwrite)
    if as_json:
        echo_json({"parameters": p.to_dict(), "effects": effects, "modes": rows})
    else:
        click.echo(f"{'n':>3} {'branch':>9} {'f [Hz]':>10}")
        for r in rows:
            click.echo(f"{r['n']:3d} {r['branch']:>9} {r['frequency_hz']:10.3f}")


def _compare(p, effects, frf_path, out, point, damping, overwrite):
    """Model FRFs at the test's geometry over the measured ones, for every live channel."""
    from tiremodal_cli.plots import plot_synthesis, save_figure

    r = read_frf(frf_path)
    if not 1 <= point <= r.point_angle.size:
        raise DataFormatError(f"--point {point} is not in 1…{r.point_angle.size}")
    if not np.all(np.isfinite(r.point_angle)):
        raise DataFormatError(f"{frf_path}: point angles unknown; the model needs them")
    m = solve_modes(p, n_max=30, effects=effects or None)
    zeta = np.array([damping if damping else paper_damping(int(n), b) for n, b in zip(m.n, m.branch)])
    live = [i for i, n in enumerate(r.channel_name) if n not in r.dead_channels
            and r.channel_location[i] in ("tread", "sidewall", "rim")]
    H = model_frf(m, r.freq_hz, zeta, [r.channel_location[i] for i in live], r.channel_angle[live],
                  r.point_angle[[point - 1]], form=r.form)[:, 0]
    ax = plot_synthesis(r.freq_hz, r.H[live, point - 1], H,
                        labels=[f"{r.channel_name[i]} / point {point}" for i in live])
    ax.set_ylabel("|H| (solid: measured, dashed: model)")
    save_figure(ax.figure, out, overwrite=overwrite)
