"""``tiremodal lsce``: modal parameters from FRFs (LSCE, stabilization, LSFD, tyre classes)."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from tiremodal_cli.io.files import check_overwrite, refuse_input_as_output, sha256_file, write_text_atomic
from tiremodal_cli.io.frffile import read_frf
from tiremodal_cli.io.frfuff import read_frf_uff
from tiremodal_cli.io.ingest import load_channel_map
from tiremodal_cli.io.modalfile import to_csv, write_modal
from tiremodal_cli.modal.table import to_rows
from tiremodal_cli.modal.modes import GROUP_MAX_ORDER, ModalOptions, modal_table_from_frf
from tiremodal_cli.modal.stabilization import StabilizationOptions
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import FiniteRange, PlotPath, Progress, band_option, echo_json, json_option, overwrite_option, say
# Start-up: matplotlib (tiremodal_cli.plots) is imported inside the command, only when a figure is asked for.


def read_any_frf(path: Path, mapping=None):
    """An FRF file (HDF5 from ``tiremodal frf``) or UFF 58 FRFs (function type 4)."""
    if path.suffix.lower() in (".uff", ".unv"):
        chans, points = load_channel_map(mapping) if mapping else ({}, {})
        r = read_frf_uff(path, channels=chans, points=points)
        if not np.isfinite(r.point_angle).any():
            say(f"lsce: warning: {path}: no point angles (no dataset 15 in the file, no --mapping): the modes "
                       "are estimated as any structure's, without order n or branch")
        return r
    return read_frf(path)


@cli.command("lsce", epilog="\b\nExample:\n  tiremodal lsce frf.h5 -o modal.h5 --csv modes.csv")
@click.argument("frf_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="Modal file to write (HDF5).")
@band_option("Analysis band, Hz (default: where the coherence supports the estimate).")
@click.option("--max-order", type=click.IntRange(2, 400), default=120, show_default=True,
              help=f"Highest model order of the sweep (per circumferential order: at most {GROUP_MAX_ORDER}).")
@click.option("--spatial", type=click.Choice(["auto", "on", "off"]), default="auto", show_default=True,
              help="Split tyre FRFs into circumferential orders before the sweep.")
@click.option("--method", type=click.Choice(["lsce", "plscf", "both"]), default="lsce", show_default=True,
              help="Pole estimator; both: run LSCE and pLSCF, mark the modes they agree on as confirmed.")
@click.option("--tol-freq", type=FiniteRange(0, 1, min_open=True), default=0.01, show_default=True,
              help="Stability: relative frequency (0 < TOL ≤ 1).")
@click.option("--tol-damping", type=FiniteRange(0, 1, min_open=True), default=0.05, show_default=True,
              help="Stability: relative damping (0 < TOL ≤ 1).")
@click.option("--tol-mac", type=FiniteRange(0, 1, min_open=True), default=0.98, show_default=True,
              help="Stability: shape MAC (0 < MAC ≤ 1).")
@click.option("--min-significance", type=FiniteRange(0, 1, max_open=True), default=0.05, show_default=True,
              help="Reject modes explaining less of the response at their frequency.")
@click.option("--mapping", type=click.Path(exists=True, dir_okay=False),
              help="For UFF input: channel names/locations/angles and point angles (as for ingest).")
@click.option("--csv", "csv_out", type=click.Path(dir_okay=False, path_type=Path), help="Also write the table as CSV.")
@click.option("--plot-stabilization", type=PlotPath())
@click.option("--plot-mac", type=PlotPath())
@click.option("--plot-shapes", type=PlotPath())
@click.option("--plot-synthesis", type=PlotPath())
@overwrite_option
@json_option
def lsce_cmd(frf_file, output, band, max_order, spatial, method, tol_freq, tol_damping, tol_mac, min_significance, mapping,
             csv_out, plot_stabilization, plot_mac, plot_shapes, plot_synthesis, overwrite, as_json):
    """Estimate modes of FRF_FILE (FRF HDF5 or UFF 58 FRFs) into OUTPUT.

    Prints the modal table (text; --json: an object with the modes, the clusters of the
    stabilization and the rejected candidates).
    """
    refuse_input_as_output({"--output": output, "--csv": csv_out, "--plot-stabilization": plot_stabilization,
                            "--plot-mac": plot_mac, "--plot-shapes": plot_shapes, "--plot-synthesis": plot_synthesis},
                           {"FRF_FILE": frf_file, "--mapping": mapping})
    outs = [output, csv_out, plot_stabilization, plot_mac, plot_shapes, plot_synthesis]
    for o in outs:
        if o is not None:
            check_overwrite(o, overwrite)
    r = read_any_frf(frf_file, mapping)
    opt = ModalOptions(band_hz=tuple(band) if band else None, max_order=max_order, spatial=spatial, method=method,
                       min_significance=min_significance,
                       stabilization=StabilizationOptions(tol_freq=tol_freq, tol_damping=tol_damping, tol_mac=tol_mac))
    bar = Progress("lsce")
    try:
        table, res = modal_table_from_frf(r, opt, progress=bar)
    finally:
        bar.close()
    write_modal(output, table, input_file=str(frf_file), input_sha256=sha256_file(frf_file), overwrite=overwrite)
    if csv_out:
        write_text_atomic(csv_out, to_csv(table), overwrite=overwrite)
    _plots(table, r, plot_stabilization, plot_mac, plot_shapes, plot_synthesis, overwrite)
    rows = to_rows(table)
    if as_json:
        echo_json({"modes": rows, "clusters": table.clusters, "rejected_modes": table.rejected,
                   "band_hz": table.meta["band_hz"], "band_reason": table.meta.get("band_reason"),
                   "spatial": table.meta["spatial"], "crowds": table.meta.get("crowds", []),
                   "orders_mix": table.meta.get("orders_mix"),
                   "exp_tau_s": table.meta["exp_tau_s"],
                   "fit_error_median": float(np.nanmedian(table.fit_error)), "output": str(output)})
    else:
        head = f"{'mode':>4} {'f [Hz]':>9} {'zeta [%]':>8} {'MPC':>5} {'n':>3} {'branch':>8} {'conf':>5}"
        click.echo(head)
        for row in rows:
            click.echo(f"{row['mode']:4d} {row['frequency_hz']:9.3f} {100 * row['damping_ratio']:8.3f} "
                       f"{row['mpc']:5.2f} {row.get('n', ''):>3} {row.get('branch') or '':>8} "
                       + (f"{row['n_confidence']:5.2f}" if 'n_confidence' in row else f"{'':>5}")
                       + (f"  crowd: n in {row['n_candidates']}" if row.get('crowd') else ""))
    if table.meta.get("orders_mix"):
        say(f"modes: {table.meta['orders_mix']['statement']}")


def _plots(table, r, stab, macp, shapes, synth, overwrite):
    from tiremodal_cli.plots import automac_figure, plot_shapes, save_figure, stabilization_figure, synthesis_figure

    for path, make in ((stab, lambda: stabilization_figure(table, r)), (macp, lambda: automac_figure(table)),
                       (shapes, lambda: plot_shapes(table)), (synth, lambda: synthesis_figure(table, r))):
        if path:
            save_figure(make(), path, overwrite=overwrite)
