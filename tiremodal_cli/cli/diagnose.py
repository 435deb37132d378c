"""``tiremodal diagnose``: what the fitted model lacks, added, with the error before and after."""

from __future__ import annotations

from pathlib import Path

import click

from tiremodal_cli.diagnose.loop import DiagnoseOptions, diagnose, report
from tiremodal_cli.io.files import check_overwrite, refuse_input_as_output, write_text_atomic
from tiremodal_cli.io.modalfile import read_modal
from tiremodal_cli.modal.spatial import grid_points
from tiremodal_cli.cli.main import cli
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.tyre.measured import modes_from_rows
from tiremodal_cli.cli.options import (FiniteRange, PlotPath, Progress, dumps, echo_json, json_option, load_params, no_usable_modes,
                      overwrite_option, params_options, read_table_rows)
# Start-up: matplotlib (tiremodal_cli.plots) is imported inside the command, only when a figure is asked for.


def human(rep: dict) -> str:
    """The report as text for people."""
    lines = [rep["verdict"], ""]
    for key in ("base", "augmented"):
        b = rep[key]
        lines.append(f"{key}: RMS {b['rms_error_pct']:.3f} %, max {b['max_error_pct']:.3f} %; "
                     + ", ".join(f"{n} = {v['value']:.5g} ± {v['std_error']:.2g}" for n, v in b["parameters"].items()))
    lines += ["", f"{'round':>5} {'candidate':<18} {'ΔAICc':>8} {'F p':>8} {'RMS %':>7}  verdict"]
    for c in rep["candidates"]:
        f = lambda v, fmt: format(v, fmt) if v is not None else "–"  # noqa: E731
        lines.append(f"{c['round']:>5} {c['name']:<18} {f(c['score'], '8.1f'):>8} {f(c['f_p_value'], '8.2g'):>8} "
                     f"{f(c['rms_error_pct'], '7.3f'):>7}  {c['reason']}")
    lines += ["", f"{'n':>3} {'branch':>9} {'measured':>9} {'base':>9} {'err %':>7} {'augmented':>9} {'err %':>7}"]
    for m in rep["modes"]:
        g = lambda v, fmt: format(v, fmt) if v is not None else "–"  # noqa: E731
        lines.append(f"{m['n']:3d} {m['branch']:>9} {m['measured_hz']:9.3f} {g(m['base_hz'], '9.3f'):>9} "
                     f"{g(m['base_error_pct'], '7.3f'):>7} {g(m['augmented_hz'], '9.3f'):>9} "
                     f"{g(m['augmented_error_pct'], '7.3f'):>7}")
    if rep["unexplained_modes"]:
        lines.append("")
        lines.append("modes that fit no structural (n, branch): " + "; ".join(
            f"{u['frequency_hz']:.2f} Hz" + (f" (n = {u['n']})" if u["n"] is not None else "") for u in
            rep["unexplained_modes"]))
    return "\n".join(lines) + "\n"


@cli.command("diagnose", epilog="\b\nExample:\n  tiremodal diagnose sample_data/paper_table_a1.csv")
@click.argument("modes_file", type=click.Path(dir_okay=False, path_type=Path))
@params_options
@click.option("--free", default="k_r1,k_r2,EI", show_default=True, help="Parameters of the base fit.")
@click.option("--candidates", help="Candidates to try, comma-separated (default: every effect and parameter).")
@click.option("--noise-floor-pct", type=FiniteRange(0, 100, min_open=True), default=0.1, show_default=True,
              help="Floor of each mode's relative frequency uncertainty, %.")
@click.option("--alpha", type=FiniteRange(0, 0.5, min_open=True, max_open=True), default=0.01,
              show_default=True, help="Level of the residual χ² test and (÷ candidates) of the F-tests.")
@click.option("--max-effects", type=click.IntRange(0, 5), default=2, show_default=True)
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of the evolutionary searches.")
@click.option("--predict-n", type=click.IntRange(1, 100), default=12, show_default=True)
@click.option("--min-confidence", type=FiniteRange(0, 1), default=0.5, show_default=True,
              help="Leave out modes with lower n_confidence (0 … 1).")
@click.option("-o", "--output", type=click.Path(dir_okay=False, path_type=Path), help="Also write the JSON report here.")
@click.option("--plot", "plot_out", type=PlotPath(), help="Residual per (n, branch) before and after.")
@overwrite_option
@json_option
def diagnose_cmd(modes_file, params_file, param_items, free, candidates, noise_floor_pct, alpha, max_effects, seed,
                 predict_n, min_confidence, output, plot_out, overwrite, as_json):
    """Find what the model fitted to MODES_FILE lacks, add it, and report the error before and after.

    MODES_FILE is what identify takes: a modal file from lsce, or a CSV with frequency_hz,
    n and branch (the paper's Table A1: sample_data/paper_table_a1.csv).
    """
    refuse_input_as_output({"--output": output, "--plot": plot_out}, {"MODES_FILE": modes_file, "--params": params_file})
    for o in (output, plot_out):
        if o is not None:
            check_overwrite(o, overwrite)
    base, effects = load_params(params_file, param_items)
    if effects:
        raise click.BadParameter("a params file for diagnose holds no [effects]: diagnose finds them",
                                 param_hint="--params")
    opt = DiagnoseOptions(free=tuple(x.strip() for x in free.split(",") if x.strip()),
                          candidates=tuple(x.strip() for x in candidates.split(",")) if candidates else None,
                          noise_floor_pct=noise_floor_pct, alpha=alpha, max_effects=max_effects, seed=seed)
    rows, n_points = _rows_and_points(modes_file)
    usable, skipped = modes_from_rows(rows, min_confidence=min_confidence, split_pairs="members")
    if not usable:
        raise DataFormatError(no_usable_modes(modes_file, rows, skipped))
    bar = Progress("diagnose")
    try:
        diag = diagnose(rows, base, opt, n_points=n_points, min_confidence=min_confidence, progress=bar)
    finally:
        bar.close()
    rep = report(diag, predict_n)
    if output:
        write_text_atomic(output, dumps(rep), overwrite=overwrite)
    if plot_out:
        from tiremodal_cli.plots import plot_residuals, save_figure

        save_figure(plot_residuals(rep["modes"]), plot_out, overwrite=overwrite)
    if as_json:
        echo_json(rep)
    else:
        click.echo(human(rep), nl=False)


def _rows_and_points(path: Path):
    """Table rows, and the number of impact points when the file is a modal file."""
    rows = read_table_rows(path)
    if path.suffix.lower() == ".csv":
        return rows, None
    return rows, grid_points(read_modal(path).point_angle)
