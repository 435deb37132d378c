"""Figures, kept apart from the computations: each takes a result and returns axes.

Uses matplotlib's object API: every figure is a ``matplotlib.figure.Figure`` on its own Agg
canvas, made without pyplot, so importing this module changes no global state (a notebook
keeps its backend) and no screen is needed.
"""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter, MaxNLocator

from tiremodal_cli import names as _names
from tiremodal_cli.io.files import atomic_path

__all__ = ["plot_frf", "save_figure", "plot_stabilization", "plot_mac", "plot_shapes", "plot_synthesis",
           "plot_dispersion", "plot_convergence", "plot_sensitivity", "plot_residuals", "plot_campaign_parameters",
           "plot_campaign_frequencies", "stabilization_figure", "automac_figure", "synthesis_figure", "mode_labels",
           "stabilization_grid",
           "animate_mode", "mode_gif", "mode_gifs",
           "iter_mode_gifs"]


def _subplots(*args, figsize=None, **kw):
    """pyplot's subplots without pyplot: a Figure on its own Agg canvas, and its axes."""
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(*args, **kw)


def save_figure(fig, path, *, overwrite: bool = False) -> None:
    """Save a figure atomically (format from the suffix)."""
    fmt = str(path).rsplit(".", 1)[-1].lower()
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format=fmt, dpi=120)


def plot_frf(r, *, points=(0,), channels=None, axes=None):
    """Magnitude, phase and coherence of chosen FRFs.

    Parameters
    ----------
    r : FRFResult
    points : sequence of int       indices into ``r.point_angle``
    channels : sequence of str     channel names (default: all live channels)
    axes : three Axes, optional

    Returns
    -------
    axes : (3,) array of Axes
    """
    if axes is None:
        fig, axes = _subplots(3, 1, sharex=True, figsize=(8, 8),
                                 gridspec_kw={"height_ratios": [3, 1.5, 1]})
    channels = [c for c in (channels or r.channel_name) if c not in r.dead_channels]
    for c in channels:
        ic = r.channel_name.index(c)
        for ip in points:
            lab = f"{c} / point {int(r.point_index[ip]) + 1} ({np.rad2deg(r.point_angle[ip]):.0f}°)"
            axes[0].semilogy(r.freq_hz, np.abs(r.H[ic, ip]), lw=1, label=lab)
            axes[1].plot(r.freq_hz, np.rad2deg(np.angle(r.H[ic, ip])), lw=0.8)
            axes[2].plot(r.freq_hz, r.coherence[ic, ip], lw=0.8)
    units = {"accelerance": "m/s²/N", "mobility": "m/s/N", "receptance": "m/N"}[r.form]
    axes[0].set_ylabel(f"|{r.estimator if r.estimator != 'unknown' else 'H'}| [{units}]")
    axes[1].set_ylabel("phase [°]")
    axes[1].set_yticks([-180, -90, 0, 90, 180])
    axes[2].set_ylabel("coherence")
    axes[2].set_ylim(0, 1.05)
    axes[2].set_xlabel("frequency [Hz]")
    axes[0].legend(fontsize=7)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return axes


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
        _, ax = _subplots(figsize=(10, 6))
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
    fig, axes = _subplots(rows, ncols, figsize=(3.0 * ncols, 1.9 * rows + 0.8), sharex=True, squeeze=False)
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
        _, ax = _subplots(figsize=(size, size))
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
    fig, axes = _subplots(rows, ncols, subplot_kw={"projection": "polar"}, figsize=(2.2 * ncols, 2.4 * rows))
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
        _, ax = _subplots(figsize=(9, 5))
    for i in range(H.shape[0]):
        line, = ax.semilogy(freq_hz, np.abs(H[i]), lw=1, label=(labels[i] if i < len(labels) else None))
        ax.semilogy(freq_hz, np.abs(H_syn[i]), "--", color=line.get_color(), lw=1)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("|H| (solid: measured, dashed: modal model)")
    ax.grid(True, alpha=0.3)
    if labels:
        ax.legend(fontsize=7)
    return ax


def plot_dispersion(rows, *, measured=(), ax=None):
    """Frequency against circumferential order for both branches (the paper's Fig. 12).

    rows : dicts with n, branch, model_hz (and optionally std_hz);
    measured : dicts with n, branch, measured_hz.
    """
    if ax is None:
        _, ax = _subplots(figsize=(7, 5))
    for br, color in (("same", "tab:blue"), ("opposite", "tab:red")):
        r = sorted((x for x in rows if x["branch"] == br), key=lambda x: x["n"])
        if r:
            n = np.array([x["n"] for x in r])
            f = np.array([x["model_hz"] for x in r])
            ax.plot(n, f, "-", color=color, label=f"model, {br}")
            if "std_hz" in r[0]:
                sd = np.array([np.nan if x["std_hz"] is None else x["std_hz"] for x in r], dtype=float)
                ax.fill_between(n, f - 2 * sd, f + 2 * sd, color=color, alpha=0.2)
        m = [x for x in measured if x["branch"] == br]
        if m:
            ax.plot([x["n"] for x in m], [x["measured_hz"] for x in m], "o", color=color, mfc="none",
                    label=f"measured, {br}")
    ax.set_xlabel("circumferential order n")
    ax.set_ylabel("frequency [Hz]")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_convergence(history, *, ax=None):
    """Best objective per generation of the evolutionary search (the paper's Fig. 11)."""
    if ax is None:
        _, ax = _subplots(figsize=(6, 4))
    g = [h[0] for h in history]
    v = [100 * h[1] for h in history]
    ax.plot(g, v, "-")
    ax.set_xlabel("generation")
    ax.set_ylabel("best RMS frequency error [%]")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    vv = np.asarray(v, float)
    vv = vv[np.isfinite(vv) & (vv > 0)]
    if vv.size and vv.max() / vv.min() > 10:  # over a decade: log, numbers written out in full
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(FuncFormatter(lambda y, _: f"{y:g}"))
        ax.yaxis.set_minor_formatter(FuncFormatter(lambda y, _: f"{y:g}" if f"{y:g}"[0] in "25" else ""))
        ax.tick_params(axis="y", which="minor", labelsize=7)
    ax.grid(True, which="both", alpha=0.3)
    ax.figure.tight_layout()
    return ax


def plot_sensitivity(ns, branches, S, names, *, ax=None):
    """Normalised sensitivities ∂ln f/∂ln p against n, one line per parameter and branch."""
    if ax is None:
        _, ax = _subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for k, br in enumerate(("same", "opposite")):
        sel = np.asarray(branches) == br
        for j, name in enumerate(names):
            ax[k].plot(np.asarray(ns)[sel], S[sel, j], "o-", ms=3, label=_names.long_label(name))
        ax[k].set_title(f"{br} direction")
        ax[k].set_xlabel("circumferential order n")
        ax[k].xaxis.set_major_locator(MaxNLocator(integer=True))
        ax[k].grid(True, alpha=0.3)
    ax[0].set_ylabel("∂ln f / ∂ln p")
    ax[1].legend(fontsize=8)
    return ax


def plot_residuals(modes, *, axes=None):
    """Frequency error against n per branch, before (base) and after (augmented) a diagnosis.

    modes : dicts with n, branch, base_error_pct, augmented_error_pct (``diagnose`` report).
    Returns the figure.
    """
    if axes is None:
        fig, axes = _subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, br in zip(axes, ("same", "opposite")):
        m = sorted((x for x in modes if x["branch"] == br), key=lambda x: x["n"])
        n = [x["n"] for x in m]
        ax.axhline(0, color="k", lw=0.8)
        ax.plot(n, [x["base_error_pct"] for x in m], "o", mfc="none", color="tab:red", label="base model")
        ax.plot(n, [x["augmented_error_pct"] for x in m], "x", color="tab:blue", label="augmented model")
        ax.set_title(f"{br} direction")
        ax.set_xlabel("circumferential order n")
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("model − measured [%]")
    axes[1].legend(fontsize=8)
    return axes[0].figure


def _campaign_axis(records):
    """x values of a campaign's done tests: inflation pressure (kPa) when it varies, else
    the test's position, labelled by name."""
    ok = [r for r in records if r.get("status") in ("done", "skipped")]
    p = [r.get("inflation_pressure") for r in ok]
    if all(v is not None for v in p) and len(set(p)) > 1:
        return ok, np.array(p, float) / 1e3, "inflation pressure [kPa]", None
    return ok, np.arange(len(ok), dtype=float), "test", [r["test"] for r in ok]


def _dodge(x) -> np.ndarray:
    """Repeats (tests at the same x) spread side by side over a quarter of the smallest gap
    between distinct x values (± 1/8), so none hides another and each stays by its condition."""
    x = np.asarray(x, float)
    u = np.unique(x)
    width = (np.diff(u).min() if u.size > 1 else 1.0) / 4
    out = x.copy()
    for v in u:
        idx = np.flatnonzero(x == v)
        if idx.size > 1:
            out[idx] = v + (np.arange(idx.size) - (idx.size - 1) / 2) * width / idx.size
    return out


def _campaign_values(ok, key):
    """(value, std_error) of a parameter across the tests: the base fit's ``identified``,
    or for an effect's parameter (``effect.param``) the final model's ``augmented_parameters``."""
    src = "augmented_parameters" if "." in key else "identified"
    v, e = [], []
    for r in ok:
        d = (r.get(src) or {}).get(key)
        d = d if isinstance(d, dict) else {"value": d}
        v.append(np.nan if d.get("value") is None else d["value"])
        e.append(np.nan if d.get("std_error") is None else d["std_error"])
    return np.array(v, float), np.array(e, float)


def plot_campaign_parameters(records):
    """Identified parameters (± 1 standard error) across a batch's tests, with the
    parameters of the effects the diagnosis adopted (final model); repeats at one
    condition drawn side by side. Names and units from :mod:`tiremodal_cli.names`.

    records : batch records (``summary.jsonl``) with ``identified`` {name: {value, std_error}}
    and ``augmented_parameters`` (effect parameters as ``effect.param``). Returns the figure.
    """
    ok, x, xlabel, names = _campaign_axis(records)
    params = []
    for r in ok:
        params += [k for k in (r.get("identified") or {}) if k not in params]
    for r in ok:
        params += [k for k in (r.get("augmented_parameters") or {}) if "." in k and k not in params]
    ncols = min(max(len(params), 1), 4)
    nrows = int(np.ceil(max(len(params), 1) / ncols))
    fig, axes = _subplots(nrows, ncols, figsize=(4 * ncols, 3.6 * nrows), squeeze=False)
    xd = _dodge(x)
    repeats = xd.size != np.unique(x).size
    for ax, k in zip(axes.ravel(), params):
        v, e = _campaign_values(ok, k)
        ax.errorbar(xd, v, yerr=np.where(np.isfinite(e), e, 0), fmt="o", ms=4, capsize=3)
        title = _names.long_label(k)
        if "." in k:
            title = f"{_names.effect_title(k.split('.')[0])}:\n{title}"
        ax.set_title(title, fontsize=8)
        ax.set_xlabel(xlabel)
        ax.grid(True, alpha=0.3)
        if names is not None:
            ax.set_xticks(x, names, rotation=60, ha="right", fontsize=7)
        elif repeats:
            ax.set_xticks(np.unique(x))  # the conditions themselves, the repeats around them
    for ax in axes.ravel()[len(params):]:
        ax.set_visible(False)
    fig.suptitle("identified parameters across the tests (± 1 standard error)"
                 + ("; repeats side by side" if repeats else ""))
    fig.tight_layout()
    return fig


def plot_campaign_frequencies(records):
    """Measured frequency of each (n, branch) across a batch's tests, one line per mode.

    records : batch records with ``modes`` [{n, branch, frequency_hz}]. Returns the figure.
    """
    ok, x, xlabel, names = _campaign_axis(records)
    fig, axes = _subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, br in zip(axes, ("same", "opposite")):
        keys = sorted({m["n"] for r in ok for m in (r.get("modes") or []) if m["branch"] == br})
        cmap = matplotlib.colormaps["viridis"].resampled(max(len(keys), 2))
        for i, n in enumerate(keys):
            f = np.array([next((m["frequency_hz"] for m in (r.get("modes") or []) if m["n"] == n
                                and m["branch"] == br), np.nan) for r in ok], float)
            order = np.argsort(x, kind="stable")
            ax.plot(_dodge(x)[order], f[order], "o-", ms=3, color=cmap(i), label=f"n = {n}")
        ax.set_title(f"{br} direction")
        ax.set_xlabel(xlabel)
        ax.grid(True, alpha=0.3)
        if names is not None:
            ax.set_xticks(x, names, rotation=60, ha="right", fontsize=7)
    axes[0].set_ylabel("measured frequency [Hz]")
    axes[1].legend(fontsize=6, ncol=2)
    fig.tight_layout()
    return fig


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
    from tiremodal_cli.modal.mac import mac_matrix

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



def _mode_figure(shapes, k, frames, exaggeration, size_in):
    """The figure of one moving mode, its frame-drawing function (``draw(i)``) and a function
    that turns the same figure to another mode (``set_mode(k)``: data, scale and title)."""
    fig, ax = _subplots(figsize=(size_in, size_in))
    rings = list(dict.fromkeys(shapes.ring))
    r_max = float(np.max(np.hypot(shapes.xyz_m[:, 0], shapes.xyz_m[:, 1])))
    colors = {"tread": "tab:blue", "sidewall": "tab:red", "rim": "0.3"}
    lines, geo = [], []
    for ring in rings:
        sel = np.flatnonzero(np.array(shapes.ring) == ring)
        order = sel[np.argsort(np.mod(shapes.angle_rad[sel], 2 * np.pi))]
        th = np.mod(shapes.angle_rad[order], 2 * np.pi)
        rad = np.hypot(shapes.xyz_m[order, 0], shapes.xyz_m[order, 1])
        th_c, rad_c = np.append(th, th[0]), np.append(rad, rad[0])
        ax.plot(rad_c * np.cos(th_c), rad_c * np.sin(th_c), color="0.85", lw=0.8)
        (ln,) = ax.plot([], [], color=colors.get(ring, "k"), lw=1.5, marker=".", ms=3, label=ring)
        lines.append(ln)
        geo.append((th_c, rad_c, np.append(order, order[0])))
    lim = 1.25 * r_max
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_aspect("equal")
    ax.axis("off")
    title = ax.set_title("", fontsize=8)
    ax.legend(fontsize=6, loc="lower right", frameon=False)
    fig.subplots_adjust(left=0.02, right=0.98, bottom=0.02, top=0.9)  # (tight_layout: 4x slower, same look)
    state = {}

    def set_mode(k):
        phis = [shapes.radial[k, idx] for _, _, idx in geo]
        peak = max(np.max(np.abs(p)) for p in phis) or 1.0
        state.update(phis=phis, scale=exaggeration * r_max / peak)
        title.set_text(f"{shapes.frequency_hz[k]:.1f} Hz  {shapes.label[k]}")

    def draw(i):
        rot = np.exp(2j * np.pi * i / frames)
        for ln, (th, rad, _), phi in zip(lines, geo, state["phis"]):
            rr = rad + state["scale"] * np.real(phi * rot)
            ln.set_data(rr * np.cos(th), rr * np.sin(th))
        return lines

    set_mode(k)
    return fig, draw, set_mode


def animate_mode(shapes, k: int, *, frames: int = 16, exaggeration: float = 0.2, size_in: float = 2.4):
    """One mode shape moving, for interactive use: the rings of an
    :class:`tiremodal_cli.io.export.ShapeSet` in the tyre's plane, each node displaced
    radially by Re(φ e^{iωt}) over one period (the largest displacement ``exaggeration`` ×
    the tread radius). Returns a ``matplotlib.animation.FuncAnimation``; for a file or a
    report use :func:`mode_gif`."""
    from matplotlib.animation import FuncAnimation

    fig, draw, _ = _mode_figure(shapes, k, frames, exaggeration, size_in)
    return FuncAnimation(fig, draw, frames=frames, blit=True)


def iter_mode_gifs(shapes, modes=None, *, frames: int = 12, exaggeration: float = 0.2, size_in: float = 2.4,
                   dpi: int = 60, fps: int = 12):
    """Each mode shape moving (as :func:`animate_mode`) as the bytes of a looping GIF
    (Pillow, an adaptive palette: a few tens of kB a mode at the defaults).

    Parameters
    ----------
    shapes : tiremodal_cli.io.export.ShapeSet
    modes : sequence of int, optional — which modes (default: all)
    frames : frames over one period ; exaggeration : largest displacement / tread radius
    size_in, dpi : figure size (inches) and resolution ; fps : frames per second

    Yields
    ------
    bytes, one GIF per mode, in order. One figure is drawn for all of them and each frame
    redraws only the moving rings (blitting): about 0.06 s a mode.
    """
    import io

    from PIL import Image

    modes = range(shapes.radial.shape[0]) if modes is None else list(modes)
    if not len(modes):
        return
    fig, draw, set_mode = _mode_figure(shapes, modes[0], frames, exaggeration, size_in)
    fig.set_dpi(dpi)
    ax, canvas = fig.axes[0], fig.canvas
    try:
        for k in modes:
            set_mode(k)
            for ln in draw(0):
                ln.set_visible(False)
            canvas.draw()  # the still parts and the title (the moving rings hidden)
            background = canvas.copy_from_bbox(fig.bbox)
            images = []
            for i in range(frames):
                canvas.restore_region(background)
                for ln in draw(i):
                    ln.set_visible(True)
                    ax.draw_artist(ln)
                rgba = np.asarray(canvas.buffer_rgba())
                images.append(Image.fromarray(rgba[..., :3]).convert("P", palette=Image.Palette.ADAPTIVE, colors=32))
            buf = io.BytesIO()
            images[0].save(buf, format="GIF", save_all=True, append_images=images[1:], duration=int(1000 / fps),
                           loop=0)
            yield buf.getvalue()
    finally:
        fig.clear()


def mode_gifs(shapes, modes=None, **kw) -> list[bytes]:
    """Every mode's GIF as a list (:func:`iter_mode_gifs`, same parameters)."""
    return list(iter_mode_gifs(shapes, modes, **kw))


def mode_gif(shapes, k: int, **kw) -> bytes:
    """One mode shape moving as the bytes of a looping GIF (:func:`mode_gifs` for one mode)."""
    return mode_gifs(shapes, [k], **kw)[0]
