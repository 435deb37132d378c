"""``tiremodal sensitivity``: the paper's single-variable study and ∂ln f/∂ln p."""

from __future__ import annotations

from pathlib import Path

import math

import click

from tiremodal_cli.io.files import check_overwrite, refuse_input_as_output, write_text_atomic
from tiremodal_cli.tyre.sensitivity import PAPER_STUDY, coefficients, single_variable
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import PlotPath, echo_json, json_option, load_params, overwrite_option, params_options
from tiremodal_cli.workflow.summary import rows_to_csv
# Start-up: matplotlib (tiremodal_cli.plots) is imported inside the command, only when a figure is asked for.


@cli.command("sensitivity", epilog="\b\nExample:\n  tiremodal sensitivity --n-max 10")
@params_options
@click.option("--parameters", default=",".join(PAPER_STUDY), show_default=True, help="Parameters to vary.")
@click.option("--factors", default="0.8,1.0,1.2", show_default=True, help="Scale factors of the single-variable study.")
@click.option("--n-max", type=click.IntRange(1, 100), default=10, show_default=True)
@click.option("--csv", "csv_out", type=click.Path(dir_okay=False, path_type=Path), help="Study table as CSV.")
@click.option("--plot", "plot_out", type=PlotPath(), help="∂ln f/∂ln p against n.")
@overwrite_option
@json_option
def sensitivity_cmd(params_file, param_items, parameters, factors, n_max, csv_out, plot_out, overwrite, as_json):
    """How each parameter moves the frequencies (80/100/120 % study and normalised coefficients)."""
    refuse_input_as_output({"--csv": csv_out, "--plot": plot_out}, {"--params": params_file})
    for o in (csv_out, plot_out):
        if o is not None:
            check_overwrite(o, overwrite)
    p, effects = load_params(params_file, param_items)
    names = tuple(x.strip() for x in parameters.split(",") if x.strip())
    try:
        facs = tuple(float(x) for x in factors.split(","))
    except ValueError:
        raise click.BadParameter(f"{factors!r} is not a list of numbers", param_hint="--factors") from None
    bad = [x for x in facs if not (math.isfinite(x) and x > 0)]
    if bad or not facs:
        raise click.BadParameter(f"{factors!r}: factor {bad[0] if bad else None!r}; allowed: positive finite scale factors",
                                 param_hint="--factors")
    study = single_variable(p, names, facs, n_max, effects or None)
    ns, br, S = coefficients(p, names, n_max, effects or None)
    if csv_out:
        write_text_atomic(csv_out, rows_to_csv(study), overwrite=overwrite)
    if plot_out:
        from tiremodal_cli.plots import plot_sensitivity, save_figure

        ax = plot_sensitivity(ns, br, S, names)
        save_figure(ax[0].figure, plot_out, overwrite=overwrite)
    coef = [{"n": int(n), "branch": b, **{name: float(S[i, j]) for j, name in enumerate(names)}}
            for i, (n, b) in enumerate(zip(ns, br))]
    if as_json:
        echo_json({"parameters": p.to_dict(), "study": study, "coefficients": coef})
        return
    click.echo(f"∂ln f/∂ln p{'':>6}" + "".join(f"{n:>9}" for n in names))
    for c in coef:
        click.echo(f"n={c['n']:<3d}{c['branch']:>9}   " + "".join(f"{c[n]:9.3f}" for n in names))
