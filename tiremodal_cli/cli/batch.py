"""``tiremodal batch``: ``run`` over every test under some folders, in parallel, resumable."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import click

from tiremodal_cli.workflow.batch import load_config, run_batch
from tiremodal_cli.workflow.summary import SUMMARY_CSV, SUMMARY_JSONL
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import FiniteRange, band_option, echo_json, json_option, parse_key_values, say


class _BatchProgress:
    """A bar on a terminal (tests done, failed, ETA); one line per finished test otherwise
    (a log a shell batch can keep)."""

    def __init__(self):
        self.bar, self.failed, self.t0 = None, 0, time.monotonic()

    def __call__(self, rec, done, total):
        self.failed += rec["status"] == "failed"
        if sys.stderr.isatty():
            if self.bar is None:
                self.bar = click.progressbar(length=total, label="batch", file=sys.stderr, show_eta=True,
                                             show_pos=True, item_show_func=lambda s: s)
                self.bar.__enter__()
            self.bar.update(done - self.bar.pos, f"failed {self.failed}" if self.failed else "")
            if done >= total:
                self.close()
            return
        what = rec["status"] + (f": {rec['reason']}" if rec["reason"] else "")
        took = f" ({rec['seconds']:.1f} s)" if rec["status"] == "done" else ""
        say(f"batch: [{done}/{total}] {rec['test']}: {what}{took}")

    def close(self):
        if self.bar is not None:
            self.bar.__exit__(None, None, None)
            self.bar = None


@cli.command("batch", epilog="\b\nExample:\n  tiremodal batch campaign/ -o results/ --jobs 2")
@click.argument("roots", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("-o", "--output", "outdir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Batch folder: one sub-folder per test, summary.csv/.jsonl, campaign plots.")
@click.option("-j", "--jobs", type=click.IntRange(1, 256), default=None,
              help="Worker processes (default: the number of cores).")
@click.option("--scheduler", metavar="ADDRESS",
              help="Run on a Dask cluster (e.g. tcp://host:8786) instead of local processes; needs tiremodal[dask].")
@click.option("--config", "config_file", type=click.Path(dir_okay=False, path_type=Path),
              help="TOML/JSON with [run] options, [params] nominal parameters, [ingest] mapping name.")
@click.option("--force", is_flag=True, help="Redo tests whose outputs are complete and unchanged.")
@band_option("lsce band, Hz.", default=None)
@click.option("--exp-end", type=FiniteRange(0, 1, min_open=True, max_open=True), default=None,
              help="Exponential window's value at the record's end [default 0.05].")
@click.option("--no-exp-window", is_flag=True, help="No exponential window.")
@click.option("--seed", type=int, default=None, help="Seed of every search [default 0].")
@click.option("--noise-floor-pct", type=FiniteRange(0, 100, min_open=True), default=None,
              help="Frequency noise floor of the diagnosis, % [default 0.1].")
@click.option("--max-effects", type=click.IntRange(0, 5), default=None, help="Effects diagnose may add [default 2].")
@click.option("--p0-from-params", is_flag=True, default=None,
              help="Model P0 from the parameters, not each test's recorded inflation pressure.")
@click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE",
              help="A nominal model parameter (repeatable; default the paper's with m_w=1000).")
@click.option("--no-plots", is_flag=True, help="No campaign plots.")
@json_option
def batch_cmd(roots, outdir, jobs, scheduler, config_file, force, band, exp_end, no_exp_window, seed,
              noise_floor_pct, max_effects, p0_from_params, param_items, no_plots, as_json):
    """Run frf → lsce → identify → diagnose on every test under ROOTS.

    Tests are measurement files (*.h5) and UFF/CSV test folders (read as 'tiremodal ingest'
    does, with the folder's mapping.toml). Each test's outputs go to OUTDIR/NAME, complete or
    not at all; tests already complete for the same input and options are skipped, so a
    stopped batch resumes. Command-line options override the --config file.

    Exit status: 0 every test done (or skipped as complete); 1 some test failed (the
    summary gives each reason); 2 bad options or no tests found; 130 interrupted.
    """
    over = {}
    if band:
        over["band"] = list(band)
    if no_exp_window:
        over["exp_end"] = False
    elif exp_end is not None:
        over["exp_end"] = exp_end
    for k, v in (("seed", seed), ("noise_floor_pct", noise_floor_pct), ("max_effects", max_effects)):
        if v is not None:
            over[k] = v
    if p0_from_params:
        over["pressure_from_file"] = False
    config = load_config(config_file, run_overrides=over, param_overrides=parse_key_values(param_items, "--param"))
    prog = _BatchProgress()
    try:
        recs = run_batch(roots, outdir, config, jobs=jobs or os.cpu_count() or 1, scheduler=scheduler, force=force,
                         progress=prog, plots=not no_plots)
    finally:
        prog.close()
    n = {s: sum(r["status"] == s for r in recs) for s in ("done", "skipped", "failed")}
    if as_json:
        echo_json(recs)
    else:
        click.echo("test,status,modes_found,rms_before_pct,rms_after_pct,reason")
        for r in recs:
            fmt = (lambda v: "" if v is None else f"{v:.3f}")
            reason = (r["reason"] or "").replace('"', "'")
            click.echo(f"{r['test']},{r['status']},{r.get('modes_found') or ''},{fmt(r.get('rms_before_pct'))},"
                       f"{fmt(r.get('rms_after_pct'))},\"{reason}\"")
    say(f"batch: {len(recs)} tests: {n['done']} done, {n['skipped']} skipped (complete), {n['failed']} failed; "
               f"summary in {outdir / SUMMARY_CSV} and {outdir / SUMMARY_JSONL}")
    if n["failed"]:
        sys.exit(1)
