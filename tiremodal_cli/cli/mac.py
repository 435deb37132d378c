"""``tiremodal mac``: AutoMAC of a modal table, or cross-MAC against another table, the
analytic cos nθ shapes, or the tyre model's shapes."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import click
import numpy as np

from tiremodal_cli.io.config import load_mapping
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import check_overwrite, refuse_input_as_output, write_text_atomic
from tiremodal_cli.modal.mac import analytic_bases, mac_matrix, model_bases, shape_labels, subspace_mac
from tiremodal_cli.io.modalfile import read_modal
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.solve import observation, solve_modes
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import PlotPath, echo_json, json_option, overwrite_option


def _flat(t, channels):
    idx = [t.channel_name.index(c) for c in channels]
    return t.shapes[:, idx].reshape(t.n_modes, -1)


@cli.command("mac", epilog="\b\nExample:\n  tiremodal mac out/gl073a/modal.h5 --analytic 12")
@click.argument("modal_file", type=click.Path(dir_okay=False, path_type=Path))
@click.argument("other", required=False, type=click.Path(dir_okay=False, path_type=Path))
@click.option("--analytic", "analytic", type=click.IntRange(0, 200), metavar="N_MAX",
              help="Against the analytic shapes cos nθ, sin nθ, n = 0 … N_MAX (tread channel over the points).")
@click.option("--model", "model_file", type=click.Path(exists=True, dir_okay=False),
              help="Against the tyre model's shapes; TOML/JSON of parameters (as for simulate's [params]).")
@click.option("--channels", help="Channels to compare, comma-separated (default: all live in both).")
@click.option("--csv", "csv_out", type=click.Path(dir_okay=False, path_type=Path), help="Write the matrix as CSV.")
@click.option("--plot", "plot_out", type=PlotPath(), help="Heat map (PNG/SVG).")
@overwrite_option
@json_option
def mac_cmd(modal_file, other, analytic, model_file, channels, csv_out, plot_out, overwrite, as_json):
    """AutoMAC of MODAL_FILE, or cross-MAC against OTHER (a second modal file), --analytic or --model."""
    if sum(x is not None for x in (other, analytic, model_file)) > 1:
        raise click.UsageError("compare against one of OTHER, --analytic, --model")
    refuse_input_as_output({"--csv": csv_out, "--plot": plot_out},
                           {"MODAL_FILE": modal_file, "OTHER": other, "--model": model_file})
    for o in (csv_out, plot_out):
        if o is not None:
            check_overwrite(o, overwrite)
    a = read_modal(modal_file)
    live = [c for i, c in enumerate(a.channel_name) if np.all(np.isfinite(a.shapes[:, i]))]
    chans = [c.strip() for c in channels.split(",")] if channels else live
    unknown = [c for c in chans if c not in a.channel_name]
    if unknown:
        raise DataFormatError(f"channel {unknown[0]!r} is not in {modal_file}; channels: {', '.join(a.channel_name)}")
    la = shape_labels(a)
    M, lb, kind = _compare(a, modal_file, chans, other=other, analytic=analytic, model_file=model_file)
    if csv_out:
        _write_csv(csv_out, M, la, lb, overwrite)
    if plot_out:
        from tiremodal_cli.plots import plot_mac, save_figure  # matplotlib: loaded only for --plot (start-up time)

        ax = plot_mac(M, labels_a=la, labels_b=lb, title={"auto": "AutoMAC", "cross": "cross-MAC",
                                                           "analytic": "MAC with cos nθ", "model": "MAC with the model"}[kind])
        save_figure(ax.figure, plot_out, overwrite=overwrite)
    if as_json:
        echo_json({"kind": kind, "rows": la, "columns": lb, "mac": M.round(6).tolist()})
    else:
        _echo(kind, M, la, lb)


def _compare(a, modal_file, chans, *, other, analytic, model_file):
    """The MAC matrix of table ``a`` against what was asked, its column labels and its kind."""
    if other is not None:
        b = read_modal(other)
        if b.point_angle.size != a.point_angle.size or any(c not in b.channel_name for c in chans):
            raise DataFormatError(f"{other}: geometry differs ({b.point_angle.size} points, channels "
                                  f"{', '.join(b.channel_name)}); cross-MAC needs the same points and channels")
        return mac_matrix(_flat(a, chans), _flat(b, chans)), shape_labels(b), "cross"
    if analytic is not None:
        if "tread" not in a.channel_location:
            raise DataFormatError(f"{modal_file}: no tread channel for the analytic shapes")
        if not np.all(np.isfinite(a.point_angle)):
            raise DataFormatError(f"{modal_file}: point angles unknown; analytic shapes need them")
        tread = a.shapes[:, a.channel_location.index("tread")]
        return (subspace_mac(tread, analytic_bases(a.point_angle, analytic)),
                [f"n={n}" for n in range(analytic + 1)], "analytic")
    if model_file is not None:
        params = TyreParameters.from_mapping(load_mapping(model_file).get("params", load_mapping(model_file)))
        lb, bases = model_bases(solve_modes(params, n_max=30), a, f_max=1.2 * float(a.frequency_hz.max()),
                                observe=observation)
        return subspace_mac(np.nan_to_num(a.shapes.reshape(a.n_modes, -1)), bases), lb, "model"
    return mac_matrix(_flat(a, chans)), shape_labels(a), "auto"


def _write_csv(path, M, la, lb, overwrite):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["mode"] + lb)
    for lab, row in zip(la, M):
        w.writerow([lab] + [f"{v:.4f}" for v in row])
    write_text_atomic(path, buf.getvalue(), overwrite=overwrite)


def _echo(kind, M, la, lb):
    """The matrix's size and each mode's best match, for people (stdout, without --json);
    for an AutoMAC the best match among the other modes (the diagonal is 1 by definition)
    and the pair holding the largest off-diagonal value."""
    off = M.copy()
    if kind == "auto":
        np.fill_diagonal(off, -np.inf)
        i, j = np.unravel_index(int(np.argmax(off)), off.shape) if M.shape[0] > 1 else (0, 0)
        top = f"{off[i, j]:.3f} ({la[i]} with {lb[j]})" if M.shape[0] > 1 else "none (one mode)"
        click.echo(f"{kind} MAC {M.shape[0]} × {M.shape[1]}; largest off-diagonal {top}")
    else:
        click.echo(f"{kind} MAC {M.shape[0]} × {M.shape[1]}")
    if kind == "auto" and M.shape[0] < 2:
        return
    for lab, row in zip(la, off if kind == "auto" else M):
        j = int(np.argmax(row))
        click.echo(f"{lab:>28}  {'closest other' if kind == 'auto' else 'best'} {lb[j]} ({row[j]:.3f})")
