"""Figures of the modal stage, from a ``ModalTable`` (and the ``FRFResult`` it came from):
stabilization diagrams, MAC, mode shapes, measured against re-synthesised FRFs."""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.ticker import MaxNLocator

from tiremodal_cli.modal.mac import mac_matrix
from tiremodal_cli.plots.canvas import subplots

__all__ = ["plot_stabilization", "stabilization_grid", "MAC_VALUES_MAX", "plot_mac", "plot_shapes", "plot_synthesis",
           "mode_labels", "stabilization_figure", "automac_figure", "synthesis_figure"]


_STATUS_STYLE = {0: ("o", "lightgray", "new"), 1: ("x", "tab:orange", "f"), 2: ("d", "tab:purple", "f, ζ"),
                 3: ("s", "tab:blue", "f, shape"), 4: ("+", "tab:green", "stable")}


def _stab_panel(ax, d, freqs, *, legend=False):
    for code, (marker, color, label) in _STATUS_STYLE.items():
        sel = d[:, 4] == code
        if sel.any():
            ax.plot(d[sel, 2], d[sel, 1], marker, color=color, ms=2.5, ls="none", label=label)
    for f in freqs:
        ax.axvline(f, color="k", lw=0.6, alpha=0.6)
    ax.yaxis.set_major_locator(MaxNLocator(integer=True, nbins=4))
    if legend:
        ax.legend(fontsize=7, loc="upper left")


def plot_stabilization(table, *, H_freq=None, H_mag=None, ax=None, group=None):
    """Stabilization diagram of one sweep: every candidate pole by model order, coloured by
    status; the adopted modes as vertical lines; optionally a mean FRF magnitude behind
    (right axis).

    table : ModalTable ; H_freq, H_mag : (n_freq,) arrays, optional
    group : the circumferential order group to draw (default: all poles on one axis; see
    :func:`stabilization_grid` for one panel per group)
    """
    if ax is None:
        _, ax = subplots(figsize=(10, 6))
    d = table.diagram
    freqs = table.frequency_hz
    if group is not None:
        d = d[d[:, 0] == group]
        freqs = table.frequency_hz[np.asarray(table.group) == group]
    _stab_panel(ax, d, freqs, legend=True)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order")
    if H_freq is not None:
        ax2 = ax.twinx()
        ax2.semilogy(H_freq, H_mag, color="0.4", lw=0.8)
        ax2.set_ylabel("mean |H|")
    return ax


def stabilization_grid(table, *, ncols: int = 4, band_hz=None):
    """Small multiples: one stabilization diagram per circumferential order group (the
    spatial order the FRFs were split into), the adopted modes of that group as lines.

    Returns the figure (one axes for a table without groups).
    """
    d = table.diagram
    groups = [int(g) for g in np.unique(d[:, 0])] if d.size else []
    if len(groups) <= 1:
        return plot_stabilization(table).figure
    rows = int(np.ceil(len(groups) / ncols))
    fig, axes = subplots(rows, ncols, figsize=(3.0 * ncols, 1.9 * rows + 0.8), sharex=True, squeeze=False)
    for i, (ax, g) in enumerate(zip(axes.ravel(), groups)):
        sel = d[:, 0] == g
        _stab_panel(ax, d[sel], table.frequency_hz[np.asarray(table.group) == g], legend=False)
        ax.set_title(f"spatial order {g}" if g >= 0 else "all", fontsize=9)
        ax.tick_params(labelsize=7)
        if band_hz is not None:
            ax.set_xlim(*band_hz)
    for ax in axes.ravel()[len(groups):]:
        ax.set_visible(False)
    for i, ax in enumerate(axes.ravel()[:len(groups)]):
        if i + ncols >= len(groups):  # the lowest panel of its column: frequencies shown
            ax.tick_params(labelbottom=True)
            ax.set_xlabel("frequency [Hz]", fontsize=8)
    for ax in axes[:, 0]:
        ax.set_ylabel("model order", fontsize=8)
    handles = [Line2D([], [], marker=m, color=c, ls="none", label=lab) for m, c, lab in _STATUS_STYLE.values()]
    handles.append(Line2D([], [], color="k", lw=0.6, label="adopted mode"))
    fig.legend(handles=handles, loc="upper center", ncol=len(handles), fontsize=8, frameon=False)
    w, h = fig.get_size_inches()  # fixed margins in inches (tight_layout over many panels costs a second)
    fig.subplots_adjust(left=0.6 / w, right=1 - 0.1 / w, bottom=0.5 / h, top=1 - 0.55 / h, wspace=0.25, hspace=0.45)
    return fig


#: a MAC image prints its values only up to this many modes (beyond, the numbers overlap at
#: a readable font size in a page-wide figure: colour only)
MAC_VALUES_MAX = 12


def plot_mac(M, *, labels_a=None, labels_b=None, ax=None, title="MAC"):
    """A MAC matrix as a heat map; its values printed in the cells up to
    :data:`MAC_VALUES_MAX` modes (colour only beyond)."""
    if ax is None:
        size = max(5, 0.35 * max(M.shape))
        _, ax = subplots(figsize=(size, size))
    im = ax.imshow(M, vmin=0, vmax=1, cmap="viridis", origin="upper")
    if max(M.shape) <= MAC_VALUES_MAX:
        for (i, j), v in np.ndenumerate(M):
            ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=7, color="w" if v < 0.6 else "k")
    if labels_a is not None:
        ax.set_yticks(range(len(labels_a)), labels_a, fontsize=6)
    if labels_b is not None:
        ax.set_xticks(range(len(labels_b)), labels_b, fontsize=6, rotation=90)
    ax.figure.colorbar(im, ax=ax, shrink=0.7)
    ax.set_title(title)
    return ax


def plot_shapes(table, *, modes=None, ncols=6):
    """Mode shapes as polar plots of the tread and sidewall (the paper's Figs. A1/A2).

    The residues seen by the tread (and sidewall) sensor over the point angles, made real
    along their principal direction, drawn as a deformed circle around the unit circle.
    Returns the figure.
    """
    modes = list(range(table.n_modes)) if modes is None else list(modes)
    rows = int(np.ceil(len(modes) / ncols)) or 1
    fig, axes = subplots(rows, ncols, subplot_kw={"projection": "polar"}, figsize=(2.2 * ncols, 2.4 * rows))
    axes = np.atleast_1d(axes).ravel()
    locs = list(table.channel_location)
    order = np.argsort(np.mod(table.point_angle, 2 * np.pi))
    th = np.mod(table.point_angle, 2 * np.pi)[order]
    th_c = np.append(th, th[0] + 2 * np.pi)
    for ax, r in zip(axes, modes):
        ax.plot(np.linspace(0, 2 * np.pi, 100), np.ones(100), color="0.8", lw=0.6)
        for loc, color in (("tread", "tab:blue"), ("sidewall", "tab:red")):
            if loc not in locs:
                continue
            v = table.shapes[r, locs.index(loc)]
            if not np.all(np.isfinite(v)):
                continue
            phi = 0.5 * np.angle(np.sum(table.shapes[r, locs.index("tread")] ** 2))
            x = np.real(v * np.exp(-1j * phi))[order]
            scale = np.max(np.abs(table.shapes[r][np.isfinite(table.shapes[r])])) or 1
            rad = 1 + 0.35 * x / scale
            ax.plot(th_c, np.append(rad, rad[0]), color=color, lw=1, label=loc)
        lab = f"{table.frequency_hz[r]:.1f} Hz"
        if table.n[r] >= 0:
            lab += f"\nn={table.n[r]} {table.branch[r]}"
        ax.set_title(lab, fontsize=7)
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_ylim(0, 1.5)
    for ax in axes[len(modes):]:
        ax.set_visible(False)
    if modes:
        axes[0].legend(fontsize=6, loc="lower left", bbox_to_anchor=(-0.3, -0.3))
    fig.tight_layout()
    return fig


def plot_synthesis(freq_hz, H, H_syn, *, labels=(), ax=None):
    """Measured against synthesised FRF magnitudes. H, H_syn : (k, n_freq) arrays."""
    if ax is None:
        _, ax = subplots(figsize=(9, 5))
    for i in range(H.shape[0]):
        line, = ax.semilogy(freq_hz, np.abs(H[i]), lw=1, label=(labels[i] if i < len(labels) else None))
        ax.semilogy(freq_hz, np.abs(H_syn[i]), "--", color=line.get_color(), lw=1)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("|H| (solid: measured, dashed: modal model)")
    ax.grid(True, alpha=0.3)
    if labels:
        ax.legend(fontsize=7)
    return ax


def mode_labels(table) -> list[str]:
    """``"63.2 n3s"``: frequency, and order and branch where classified."""
    return [f"{f:.1f}" + (f" n{n}{b[:1]}" if n >= 0 else "") for f, n, b in
            zip(table.frequency_hz, table.n, table.branch)]


def _band_lines(table, r):
    if table.synthesis_freq_hz is not None:
        lo, hi = table.synthesis_freq_hz[0], table.synthesis_freq_hz[-1]
    else:
        lo, hi = (table.meta or {}).get("band_hz", (r.freq_hz[0], r.freq_hz[-1]))
    return (r.freq_hz >= lo - 1e-9) & (r.freq_hz <= hi + 1e-9)


def stabilization_figure(table, r):
    """The stabilization diagram of the lsce band: one panel per circumferential order group
    when the FRFs were split into orders (:func:`stabilization_grid`), else one diagram over
    the mean FRF magnitude.

    table : ModalTable ; r : FRFResult it came from. Returns the figure.
    """
    lines = _band_lines(table, r)
    d = table.diagram
    if d.size and np.unique(d[:, 0]).size > 1:  # split into circumferential orders: one panel each
        return stabilization_grid(table, band_hz=(r.freq_hz[lines][0], r.freq_hz[lines][-1]))
    mag = np.nanmean(np.abs(r.H[..., lines]).reshape(-1, lines.sum()), axis=0)
    return plot_stabilization(table, H_freq=r.freq_hz[lines], H_mag=mag).figure


def automac_figure(table):
    """AutoMAC of the modes' shapes (all channels and points stacked). Returns the figure."""
    flat = np.nan_to_num(table.shapes.reshape(table.n_modes, -1))
    labels = mode_labels(table)
    return plot_mac(mac_matrix(flat), labels_a=labels, labels_b=labels, title="AutoMAC").figure


def synthesis_figure(table, r, *, points=None, n_channels: int = 2):
    """Measured FRFs against the modal model's re-synthesis (the table's ``synthesis``).

    points : point indices (default the first and the one a quarter round). Returns the figure.
    Raises ValueError when the table holds no synthesis (a modal file from before it did).
    """
    if table.synthesis is None:
        raise ValueError("the modal file holds no re-synthesised FRFs; re-run lsce")
    lines = _band_lines(table, r)
    n_p = r.H.shape[1]
    points = sorted({0, n_p // 4}) if points is None else list(points)
    live = [i for i, n in enumerate(r.channel_name) if n not in r.dead_channels][:n_channels]
    H = np.array([r.H[c, p][lines] for c in live for p in points])
    S = np.array([table.synthesis[c, p] for c in live for p in points])
    labels = [f"{r.channel_name[c]} / point {p + 1}" for c in live for p in points]
    return plot_synthesis(r.freq_hz[lines], H, S, labels=labels).figure
