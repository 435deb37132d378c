"""``tiremodal run``: the whole pipeline on one measurement (frf → lsce → identify → diagnose)."""

from __future__ import annotations

from pathlib import Path

import click

from tiremodal_cli.errors import OutputExistsError
from tiremodal_cli.io.files import refuse_input_as_output
from tiremodal_cli.io.frfuff import is_uff
from tiremodal_cli.tyre.model import NOMINAL_RIM_KG
from tiremodal_cli.workflow.pipeline import MODES_OUTPUTS, is_modes_table
from tiremodal_cli.workflow.run_folder import run_folder
from tiremodal_cli.workflow.run_options import MANIFEST, OUTPUTS, RunOptions
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import FiniteRange, StageProgress, band_option, echo_json, json_option, load_params, params_options, say


@cli.command("run", epilog="\b\nExample:\n  tiremodal run sample_data/gl073a_sim.h5 -o out/gl073a --overwrite")
@click.argument("measurement", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", "outdir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Folder for every stage's output.")
@params_options
@band_option("lsce band, Hz (default: from the coherence and force spectrum).")
@click.option("--exp-end", type=FiniteRange(0, 1, min_open=True, max_open=True), default=0.05,
              show_default=True, help="Exponential window's value at the record's end (corrected in lsce).")
@click.option("--no-exp-window", is_flag=True, help="No exponential window.")
@click.option("--seed", type=int, default=0, show_default=True)
@click.option("--noise-floor-pct", type=FiniteRange(0, 100, min_open=True), default=0.1, show_default=True)
@click.option("--max-effects", type=click.IntRange(0, 5), default=2, show_default=True)
@click.option("--p0-from-params", is_flag=True,
              help="Model P0 from the parameters, not the inflation pressure the measurement records.")
@click.option("--mapping", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="For UFF FRFs: channels, point angles, [test] (as for ingest; default: the file's geometry).")
@click.option("--overwrite", is_flag=True, help="Replace the outputs of an earlier run in OUTDIR.")
@json_option
def run_cmd(measurement, outdir, params_file, param_items, band, exp_end, no_exp_window, seed, noise_floor_pct,
            max_effects, p0_from_params, mapping, overwrite, as_json):
    """Run frf → lsce → identify → diagnose on MEASUREMENT, writing each stage into OUTDIR.

    MEASUREMENT is a measurement file, or a UFF file of FRFs (dataset 58, function type 4,
    from another system): such a test starts at lsce, in SI from the file's units, its
    points placed by the file's geometry (dataset 15) or by --mapping; or a CSV of measured
    modes (*.csv: frequency_hz, n, branch — the paper's Table A1, or lsce --csv): it starts
    at identify, the rim and pressure from the parameters (writes modes.csv, identify.json,
    diagnosis.json, sensitivity.json, run.json).

    Writes frf.h5, modal.h5, modes.csv, identify.json, diagnosis.json, sensitivity.json and,
    last, run.json (checksums and summary) into a private folder beside OUTDIR, installed
    whole when complete: OUTDIR is always the old complete run, absent, or the new one.
    Prints the summary on stdout (JSON with --json); what it wrote on stderr.
    """
    existing = [n for n in (*OUTPUTS, MANIFEST) if (outdir / n).exists()]
    if existing and not overwrite:  # checked again under the lock; here to refuse before any work
        raise OutputExistsError(f"output {str(outdir / existing[0])!r} exists; pass --overwrite to replace it")
    refuse_input_as_output({"--output": outdir}, {"MEASUREMENT": measurement, "--mapping": mapping})
    base, effects = load_params(params_file, param_items)
    if effects:
        raise click.BadParameter("run finds the effects itself: a params file holds no [effects] here",
                                 param_hint="--params")
    modes_table = is_modes_table(measurement)
    if "m_w" not in {p.split("=", 1)[0].strip() for p in param_items if "=" in p} and not params_file \
            and not modes_table:  # (a table of modes has no rim channel: the parameters' rim, as in diagnose)
        base = base.replace(m_w=NOMINAL_RIM_KG)
    opt = RunOptions(band=tuple(band) if band else None, exp_end=None if no_exp_window else exp_end, seed=seed,
                     noise_floor_pct=noise_floor_pct, max_effects=max_effects, pressure_from_file=not p0_from_params)
    bar = StageProgress("run", ["identify", "diagnose"] if modes_table else
                        ["read FRFs" if is_uff(measurement) else "frf", "lsce", "identify", "diagnose"])
    try:
        summary = run_folder(measurement, outdir, opt, params=base, overwrite=overwrite, progress=bar,
                             mapping=mapping)
    finally:
        bar.close()
    if as_json:
        echo_json(summary)
        return
    src = summary.get("frf_source")
    if src:
        click.echo(f"{summary['measurement']}: UFF FRFs ({src['form']}, {src['unit_in_file']} × {src['to_si']:.6g} "
                   f"to SI, from {src['from']}; points from {src['geometry']}); started at lsce: "
                   f"{summary['modes_found']} modes")
    elif summary.get("starts_at") == "identify":
        click.echo(f"{summary['measurement']}: a table of {summary['modes_found']} modes; started at identify")
    else:
        rej = summary["rejected_hits"]  # (a channel without signal is listed with hit None: not a hit)
        dead = sorted({x["channel"] for x in rej if x["hit"] is None})
        click.echo(f"{summary['measurement']}: {summary['modes_found']} modes, "
                   f"{sum(x['hit'] is not None for x in rej)} rejected hit(s)"
                   + (f", no signal on {', '.join(dead)}" if dead else ""))
    click.echo("identified: " + ", ".join(f"{k} = {v['value']:.5g} ± {v['std_error']:.2g}"
                                          for k, v in summary["identified"].items()))
    click.echo(f"diagnosis: {summary['verdict']}")
    if summary.get("orders_mix"):
        say(f"modes: {summary['orders_mix']['statement']}")
    say(f"wrote {outdir}/: {', '.join(MODES_OUTPUTS if modes_table else OUTPUTS)}, {MANIFEST}")
