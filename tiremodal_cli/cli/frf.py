"""``tiremodal frf``: H1/H2/Hv FRFs and coherence from a measurement file."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import check_overwrite, refuse_input_as_output, sha256_file
from tiremodal_cli.frf.estimate import ESTIMATORS, FORMS, FRFOptions, compute_frf
from tiremodal_cli.io.frffile import describe_frf, write_frf
from tiremodal_cli.io.frfuff import write_frf_uff
from tiremodal_cli.io.measurement import open_measurement
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import FiniteRange, PlotPath, Progress, band_option, echo_json, json_option, overwrite_option, say
# Start-up: matplotlib (tiremodal_cli.plots) is imported inside the command, only when a figure is asked for.


def _check_windows(m, force_window_s, exp_tau_s, exp_end=None) -> None:
    """Window lengths against the record: the force window's flat part must be shorter than
    the record; the exponential window's time constant τ at least 2/(π fs) — it widens every
    line by 1/(π τ) Hz (its Lorentzian's half-power bandwidth), which must stay below the
    Nyquist frequency fs/2 or no line is resolved at all."""
    T, fs = m.n_samples / m.sample_rate, m.sample_rate
    if force_window_s is not None and not force_window_s < T:
        raise click.BadParameter(f"{force_window_s:g} s is not shorter than the record ({T:g} s); "
                                 f"allowed: 0 < SECONDS < {T:g}", param_hint="--force-window-length")
    tau_min = 2.0 / (np.pi * fs)
    if exp_end is not None and T / -np.log(exp_end) < tau_min:
        raise click.BadParameter(f"{exp_end:g} at the record's end is a time constant of {T / -np.log(exp_end):.3g} s, "
                                 f"widening every line beyond the Nyquist frequency ({fs / 2:g} Hz); allowed: ≥ "
                                 f"{np.exp(-T / tau_min):.3g} (τ ≥ 2/(π fs) = {tau_min:.3g} s)", param_hint="--exp-end")
    if exp_tau_s is not None and exp_tau_s < tau_min:
        raise click.BadParameter(f"{exp_tau_s:g} s widens every line by {1 / (np.pi * exp_tau_s):.3g} Hz, beyond "
                                 f"the Nyquist frequency ({fs / 2:g} Hz); allowed: ≥ 2/(π fs) = {tau_min:.3g} s",
                                 param_hint="--exp-tau")


@cli.command("frf", epilog="\b\nExample:\n  tiremodal frf sample_data/gl073a_sim.h5 -o frf.h5 --uff frf.uff")
@click.argument("measurement", type=click.Path(dir_okay=False, path_type=Path))
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="FRF file to write (HDF5).")
@click.option("--estimator", type=click.Choice(ESTIMATORS), default="H1", show_default=True)
@click.option("--form", type=click.Choice(FORMS), default="accelerance", show_default=True)
@band_option("Keep LO ≤ f ≤ HI (Hz); default all lines.")
@click.option("--force-window/--no-force-window", default=True, show_default=True,
              help="Rectangular window over the pulse with cosine tapers.")
@click.option("--force-window-length", type=FiniteRange(0, min_open=True), metavar="SECONDS",
              help="Flat length (default: from the pulse); shorter than the record.")
@click.option("--exp-end", type=FiniteRange(0, 1, min_open=True, max_open=True),
              help="Exponential window: its value at the record's end (adds known damping, corrected downstream).")
@click.option("--exp-tau", type=FiniteRange(0, min_open=True), metavar="SECONDS",
              help="Exponential window by its time constant instead (at least 2/(π fs): see docs/frf.md).")
@click.option("--no-hit-checks", is_flag=True, help="Keep every finite hit (no double-hit/clip/consistency checks).")
@click.option("--hit-residual-max", type=FiniteRange(0, 1, min_open=True), default=0.1, show_default=True,
              help="Reject a hit the other hits' H1 leaves more of its energy unexplained than this "
                   "(and 3× the hits' median; ≥ 3 hits).")
@click.option("--uff", "uff_out", type=click.Path(dir_okay=False, path_type=Path),
              help="Also write the FRFs as UFF 58 (function type 4).")
@click.option("--plot", "plot_out", type=PlotPath(),
              help="Also draw magnitude, phase and coherence (PNG/SVG/PDF).")
@click.option("--plot-points", default="1", show_default=True, help="Points to plot, 1-based, comma-separated.")
@overwrite_option
@json_option
def frf_cmd(measurement, output, estimator, form, band, force_window, force_window_length, exp_end, exp_tau,
            no_hit_checks, hit_residual_max, uff_out, plot_out, plot_points, overwrite, as_json):
    """Estimate FRFs of MEASUREMENT into OUTPUT, rejecting bad hits (reported)."""
    refuse_input_as_output({"--output": output, "--uff": uff_out, "--plot": plot_out}, {"MEASUREMENT": measurement})
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
        _check_windows(m, force_window_length, exp_tau, exp_end)
        bad = [p + 1 for p in pts if not 0 <= p < m.n_points]
        if plot_out and bad:
            raise click.BadParameter(f"point {bad[0]} is not in 1…{m.n_points}", param_hint="--plot-points")
        try:
            r = compute_frf(m, opt, progress=bar)
        except OSError as exc:
            raise DataFormatError(f"{measurement}: cannot read the records ({exc}); the file may be truncated") from None
        except DataFormatError as exc:  # (every hit rejected: say which test)
            raise DataFormatError(f"{measurement}: {exc}") from None
        finally:
            bar.close()
    if not np.isfinite(r.H).any():
        raise DataFormatError(f"{measurement}: every FRF line is non-finite with these options (windows "
                              f"--exp-end {exp_end}, --exp-tau {exp_tau}, --force-window-length {force_window_length}); "
                              "allowed: windows that leave the records a finite spectrum")
    write_frf(output, r, input_file=str(measurement), input_sha256=sha, overwrite=overwrite)
    if uff_out:
        write_frf_uff(uff_out, r, overwrite=overwrite)
    if plot_out:
        from tiremodal_cli.plots import plot_frf, save_figure

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
            say(f"rejected {where} ({x.channel}): {x.reason}")
        say(f"wrote {output}: {len(r.channel_name)} channels × {r.point_angle.size} points × "
                   f"{r.freq_hz.size} lines, {len(r.rejections)} rejection(s)")
