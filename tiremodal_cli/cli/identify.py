"""``tiremodal identify``: structural parameters of the tyre model from a modal table."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import click
import numpy as np

from tiremodal_cli.io.files import check_overwrite, refuse_input_as_output, write_text_atomic
from tiremodal_cli.tyre.fit import fit
from tiremodal_cli.tyre.fit_types import PAPER_GA, FitOptions
from tiremodal_cli.tyre.measured import modes_from_rows
from tiremodal_cli.tyre.predict import fit_report, predict_table
from tiremodal_cli.tyre.robust import robust_fit, with_sigma
from tiremodal_cli.cli.main import cli
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.cli.options import (FiniteRange, PlotPath, Progress, echo_json, json_option, load_params, no_usable_modes,
                      overwrite_option, params_options, read_table_rows)
from tiremodal_cli.workflow.summary import rows_to_csv
# Start-up: matplotlib (tiremodal_cli.plots) is imported inside the command, only when a figure is asked for.

#: Floor of a measured frequency's relative uncertainty for the screen, % (diagnose's:
#: the repeatability of an impact test's frequencies)
NOISE_FLOOR_PCT = 0.1


#: Upper bounds of the search's size. Each member of each generation is one model solve
#: (about 1 ms for the default orders), so 10,000 members × 100,000 generations is 10⁹
#: solves — weeks on one core: the bounds keep a typo from running for ever, while 500×
#: the paper's population (20) and 300× its generations (300) stay allowed. Memory is
#: no limit here (a population of 10,000 × 7 parameters is 0.5 MB).
POPULATION_MAX = 10_000
GENERATIONS_MAX = 100_000


def fit_options(free, bounds, weights, seed, paper_ga, population, generations):
    b = {}
    for item in bounds:
        try:
            name, rng = item.split("=", 1)
            lo, hi = (float(x) for x in rng.split(":"))
        except ValueError:
            raise click.BadParameter(f"{item!r} must be NAME=LO:HI", param_hint="--bounds") from None
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
            raise click.BadParameter(f"{item!r}: bounds must be positive and finite with LO < HI (SI units)",
                                     param_hint="--bounds")
        b[name.strip()] = (lo, hi)
    kw = dict(free=tuple(x.strip() for x in free.split(",") if x.strip()), bounds=b, weights=weights, seed=seed)
    if paper_ga:
        kw.update(population=PAPER_GA["population"], generations=PAPER_GA["generations"],
                  crossover=PAPER_GA["crossover"], mutation=PAPER_GA["mutation"])
    if population:
        kw["population"] = population
    if generations:
        kw["generations"] = generations
    return FitOptions(**kw)


def common_fit_options(f):
    for opt in reversed([
        click.option("--free", default="k_r1,k_r2,EI", show_default=True,
                     help="Parameters to fit (of k_r1, k_r2, EI, rhoA, m_s, m_w, b)."),
        click.option("--bounds", multiple=True, metavar="NAME=LO:HI", help="Search bounds (SI; positive)."),
        click.option("--weights", type=click.Choice(["relative", "uncertainty"]), default="relative",
                     show_default=True, help="RMS of relative errors, or weighted by each frequency's uncertainty."),
        click.option("--seed", type=int, default=0, show_default=True, help="Seed of the evolutionary search."),
        click.option("--paper-ga", is_flag=True, help="The paper's settings: population 20, 300 generations, "
                                                      "crossover 0.7, mutation 0.1."),
        click.option("--population", type=click.IntRange(4, POPULATION_MAX),
                     help=f"Members of the population (at most {POPULATION_MAX:,})."),
        click.option("--generations", type=click.IntRange(1, GENERATIONS_MAX),
                     help=f"Generations of the search (at most {GENERATIONS_MAX:,})."),
    ]):
        f = opt(f)
    return f


@cli.command("identify", epilog="\b\nExample:\n  tiremodal identify sample_data/paper_table_a1.csv --json")
@click.argument("modes_file", type=click.Path(dir_okay=False, path_type=Path))
@params_options
@common_fit_options
@click.option("--predict-n", type=click.IntRange(1, 100), default=12, show_default=True,
              help="Predict every (n, branch) up to this order.")
@click.option("--min-confidence", type=FiniteRange(0, 1), default=0.5, show_default=True,
              help="Leave out modes with lower n_confidence (0 … 1).")
@click.option("--csv", "csv_out", type=click.Path(dir_okay=False, path_type=Path), help="Per-mode table as CSV.")
@click.option("--plot-fit", type=PlotPath(), help="Measured and model against n.")
@click.option("--plot-convergence", type=PlotPath())
@click.option("--alpha", type=FiniteRange(0, 0.5, min_open=True, max_open=True), default=0.01, show_default=True,
              help="False-rejection rate per fit of the screen that sets aside modes the model cannot represent.")
@click.option("--keep-all", is_flag=True, help="Fit every mode (no screen): the paper's plain least squares.")
@overwrite_option
@json_option
def identify_cmd(modes_file, params_file, param_items, free, bounds, weights, seed, paper_ga, population, generations,
                 predict_n, min_confidence, csv_out, plot_fit, plot_convergence, alpha, keep_all, overwrite, as_json):
    """Fit the model to MODES_FILE (a modal file from lsce, or a CSV with frequency_hz, n, branch)."""
    refuse_input_as_output({"--csv": csv_out, "--plot-fit": plot_fit, "--plot-convergence": plot_convergence},
                           {"MODES_FILE": modes_file, "--params": params_file})
    for o in (csv_out, plot_fit, plot_convergence):
        if o is not None:
            check_overwrite(o, overwrite)
    base, effects = load_params(params_file, param_items)
    opt = fit_options(free, bounds, weights, seed, paper_ga, population, generations)
    if effects:
        opt = replace(opt, effects=effects)
    rows = read_table_rows(modes_file)
    modes, skipped = modes_from_rows(rows, min_confidence=min_confidence, source=str(modes_file))
    if not modes:
        raise DataFormatError(no_usable_modes(modes_file, rows, skipped))
    bar = Progress("identify")
    try:
        if keep_all:
            res, aside = fit(modes, base, opt, progress=bar), None
        else:  # modes the model cannot represent set aside before they move it (tiremodal_cli.tyre.robust)
            rf = robust_fit(with_sigma(modes, NOISE_FLOOR_PCT), base, opt, alpha=alpha)
            res, aside = rf.fit, rf
    finally:
        bar.close()
    preds = predict_table(res, predict_n, measured=res.modes)
    report = fit_report(res, skipped, preds)
    if aside is not None:
        report["set_aside"] = [a.to_dict() for a in aside.set_aside]
        report["outlier_rule"] = {"z_crit": aside.z_crit, "scale": aside.scale, "alpha": aside.alpha}
    if csv_out:
        write_text_atomic(csv_out, rows_to_csv(res.modes), overwrite=overwrite)
    if plot_fit or plot_convergence:
        from tiremodal_cli.plots import plot_convergence as pc, plot_dispersion, save_figure

        if plot_fit:
            save_figure(plot_dispersion(preds, measured=res.modes).figure, plot_fit, overwrite=overwrite)
        if plot_convergence:
            save_figure(pc(res.history).figure, plot_convergence, overwrite=overwrite)
    if as_json:
        echo_json(report)
        return
    for n, v in report["parameters"].items():
        click.echo(f"{n:>8} = {v['value']:.6g} ± {v['std_error']:.2g} ({v['relative_std_error_pct']:.1f} %)"
                   + (f"  [undetermined: {res.undetermined[n]}]" if n in res.undetermined else ""))
    click.echo(f"RMS error {res.rms_error_pct:.3f} %, max {res.max_error_pct:.3f} %")
    click.echo(f"{'n':>3} {'branch':>9} {'measured':>10} {'model':>10} {'error %':>8}")
    for m in res.modes:
        click.echo(f"{m['n']:3d} {m['branch']:>9} {m['measured_hz']:10.3f} {m['model_hz']:10.3f} {m['error_pct']:8.3f}")
    for a in report.get("set_aside", []):
        click.echo(f"set aside: n={a['n']} {a['branch']} at {a['frequency_hz']:.3f} Hz — {a['reason']}")
    if report["not_followed"]:
        click.echo("the model does not follow: " + ", ".join(f"n={m['n']} {m['branch']} ({m['error_pct']:+.1f} %)"
                                                             for m in report["not_followed"]))
