"""``tiremodal frf``: H1/H2/Hv FRFs and coherence from a measurement file."""

from __future__ import annotations

from pathlib import Path

import click

from ..errors import DataFormatError
from ..files import check_overwrite, sha256_file
from ..frf import ESTIMATORS, FORMS, FRFOptions, compute_frf
from ..frffile import describe_frf, write_frf, write_frf_uff
from ..measurement import open_measurement
from .main import cli
from .options import Progress, echo_json, json_option, overwrite_option


@cli.command("frf")
@click.argument("measurement", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="FRF file to write (HDF5).")
@click.option("--estimator", type=click.Choice(ESTIMATORS), default="H1", show_default=True)
@click.option("--form", type=click.Choice(FORMS), default="accelerance", show_default=True)
@click.option("--band", nargs=2, type=float, metavar="LO HI", help="Keep LO ≤ f ≤ HI (Hz); default all lines.")
@click.option("--force-window/--no-force-window", default=True, show_default=True,
              help="Rectangular window over the pulse with cosine tapers.")
@click.option("--force-window-length", type=float, metavar="SECONDS", help="Flat length (default: from the pulse).")
@click.option("--exp-end", type=click.FloatRange(0, 1, min_open=True, max_open=True),
              help="Exponential window: its value at the record's end (adds known damping, corrected downstream).")
@click.option("--exp-tau", type=click.FloatRange(0, min_open=True), metavar="SECONDS",
              help="Exponential window by its time constant instead.")
@click.option("--no-hit-checks", is_flag=True, help="Keep every finite hit (no double-hit/clip/consistency checks).")
@click.option("--hit-residual-max", type=click.FloatRange(0, min_open=True), default=0.1, show_default=True,
              help="Reject a hit the other hits' H1 leaves more of its energy unexplained than this "
                   "(and 3× the hits' median; ≥ 3 hits).")
@click.option("--uff", "uff_out", type=click.Path(dir_okay=False, path_type=Path),
              help="Also write the FRFs as UFF 58 (function type 4).")
@click.option("--plot", "plot_out", type=click.Path(dir_okay=False, path_type=Path),
              help="Also draw magnitude, phase and coherence (PNG/SVG/PDF).")
@click.option("--plot-points", default="1", show_default=True, help="Points to plot, 1-based, comma-separated.")
@overwrite_option
@json_option
def frf_cmd(measurement, output, estimator, form, band, force_window, force_window_length, exp_end, exp_tau,
            no_hit_checks, hit_residual_max, uff_out, plot_out, plot_points, overwrite, as_json):
    """Estimate FRFs of MEASUREMENT into OUTPUT, rejecting bad hits (reported)."""
    for out in (output, uff_out, plot_out):
        if out is not None:
            check_overwrite(out, overwrite)
    if exp_end is not None and exp_tau is not None:
        raise click.UsageError("give --exp-end or --exp-tau, not both")
    opt = FRFOptions(estimator=estimator, form=form, band_hz=tuple(band) if band else None,
                     force_window=force_window, force_window_s=force_window_length, exp_end=exp_end,
                     exp_tau_s=exp_tau, check_hits=not no_hit_checks, hit_residual_max=hit_residual_max)
    try:
        pts = [int(x) - 1 for x in plot_points.split(",") if x.strip()]
    except ValueError:
        raise click.BadParameter(f"{plot_points!r} is not a comma-separated list of point numbers",
                                 param_hint="--plot-points") from None
    sha = sha256_file(measurement) if measurement.is_file() else ""
    bar = Progress("frf")
    with open_measurement(measurement) as m:
        try:
            r = compute_frf(m, opt, progress=bar)
        except OSError as exc:
            raise DataFormatError(f"{measurement}: cannot read the records ({exc}); the file may be truncated") from None
        finally:
            bar.close()
    write_frf(output, r, input_file=str(measurement), input_sha256=sha, overwrite=overwrite)
    if uff_out:
        write_frf_uff(uff_out, r, overwrite=overwrite)
    if plot_out:
        from ..plots import plot_frf, save_figure

        bad = [p + 1 for p in pts if not 0 <= p < r.point_angle.size]
        if bad:
            raise click.BadParameter(f"point {bad[0]} is not in 1…{r.point_angle.size}", param_hint="--plot-points")
        axes = plot_frf(r, points=pts)
        save_figure(axes[0].figure, plot_out, overwrite=overwrite)
    summary = {"output": str(output), **describe_frf(output),
               "rejections": [x.to_dict() for x in r.rejections],
               "failed_points": r.meta.get("failed_points", []),
               "exponential_window": r.meta.get("exponential_window")}
    if as_json:
        echo_json(summary)
    else:
        for x in r.rejections:
            where = "all hits" if x.hit is None else f"point {x.point + 1} hit {x.hit + 1}"
            click.echo(f"rejected {where} ({x.channel}): {x.reason}", err=True)
        click.echo(f"wrote {output}: {len(r.channel_name)} channels × {r.point_angle.size} points × "
                   f"{r.freq_hz.size} lines, {len(r.rejections)} rejection(s)", err=True)
