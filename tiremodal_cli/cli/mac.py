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
from tiremodal_cli.modal.mac import mac_matrix, subspace_mac
from tiremodal_cli.io.modalfile import read_modal
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.solve import observation, solve_modes
from tiremodal_cli.cli.main import cli
from tiremodal_cli.cli.options import PlotPath, echo_json, json_option, overwrite_option


def _labels(t):
    return [f"{f:.1f} Hz" + (f" n={n} {b}" if n >= 0 else "") for f, n, b in zip(t.frequency_hz, t.n, t.branch)]


def _flat(t, channels):
    idx = [t.channel_name.index(c) for c in channels]
    return t.shapes[:, idx].reshape(t.n_modes, -1)


def model_bases(params: TyreParameters, t, f_max, n_max=30):
    """Residue shapes of the model's modes as the test sees them: sensor × point.

    Members of one (n, branch) (cos and sin) form one subspace. Returns (labels, bases).
    """
    m = solve_modes(params, n_max=n_max)
    groups = {}
    for r in np.flatnonzero(m.freq_hz <= f_max):
        key = (int(m.n[r]), m.branch[r])
        rows = []
        for loc, ang in zip(t.channel_location, t.channel_angle):
            c_out = observation(m.dofs, loc, ang) @ m.shapes[r] if loc in ("tread", "sidewall", "rim") else 0.0
            c_in = np.array([observation(m.dofs, "tread", a) @ m.shapes[r] for a in t.point_angle])
            rows.append(c_out * c_in)
        groups.setdefault(key, []).append((m.freq_hz[r], np.concatenate(rows)))
    labels, bases = [], []
    for (n, b), members in sorted(groups.items(), key=lambda kv: kv[1][0][0]):
        vecs = [v for _, v in members if np.linalg.norm(v) > 0]
        if vecs:
            labels.append(f"model {members[0][0]:.1f} Hz n={n} {b}")
            bases.append(np.array(vecs))
    return labels, bases


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
    la = _labels(a)
    if other is not None:
        b = read_modal(other)
        if b.point_angle.size != a.point_angle.size or any(c not in b.channel_name for c in chans):
            raise DataFormatError(f"{other}: geometry differs ({b.point_angle.size} points, channels "
                                  f"{', '.join(b.channel_name)}); cross-MAC needs the same points and channels")
        M, lb, kind = mac_matrix(_flat(a, chans), _flat(b, chans)), _labels(b), "cross"
    elif analytic is not None:
        if "tread" not in a.channel_location:
            raise DataFormatError(f"{modal_file}: no tread channel for the analytic shapes")
        th = a.point_angle
        if not np.all(np.isfinite(th)):
            raise DataFormatError(f"{modal_file}: point angles unknown; analytic shapes need them")
        tread = a.shapes[:, a.channel_location.index("tread")]
        bases = [np.ones((1, th.size))] + [np.vstack([np.cos(n * th), np.sin(n * th)]) for n in range(1, analytic + 1)]
        M, lb, kind = subspace_mac(tread, bases), [f"n={n}" for n in range(analytic + 1)], "analytic"
    elif model_file is not None:
        params = TyreParameters.from_mapping(load_mapping(model_file).get("params", load_mapping(model_file)))
        lb, bases = model_bases(params, a, f_max=1.2 * float(a.frequency_hz.max()))
        M, kind = subspace_mac(np.nan_to_num(a.shapes.reshape(a.n_modes, -1)), bases), "model"
    else:
        M, lb, kind = mac_matrix(_flat(a, chans)), la, "auto"
    if csv_out:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["mode"] + lb)
        for lab, row in zip(la, M):
            w.writerow([lab] + [f"{v:.4f}" for v in row])
        write_text_atomic(csv_out, buf.getvalue(), overwrite=overwrite)
    if plot_out:
        from tiremodal_cli.plots import plot_mac, save_figure

        ax = plot_mac(M, labels_a=la, labels_b=lb, title={"auto": "AutoMAC", "cross": "cross-MAC",
                                                           "analytic": "MAC with cos nθ", "model": "MAC with the model"}[kind])
        save_figure(ax.figure, plot_out, overwrite=overwrite)
    if as_json:
        echo_json({"kind": kind, "rows": la, "columns": lb, "mac": M.round(6).tolist()})
    else:
        off = M.copy()
        if kind == "auto":
            np.fill_diagonal(off, 0)
        click.echo(f"{kind} MAC {M.shape[0]} × {M.shape[1]}; largest off-diagonal {off.max():.3f}" if kind == "auto"
                   else f"{kind} MAC {M.shape[0]} × {M.shape[1]}")
        for lab, row in zip(la, M):
            j = int(np.argmax(row))
            click.echo(f"{lab:>28}  best {lb[j]} ({row[j]:.3f})")
