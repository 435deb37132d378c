"""Figures of the tyre model's fit and the diagnosis: frequencies against n, the search's
convergence, sensitivities, errors before and after."""

from __future__ import annotations

import numpy as np
from matplotlib.ticker import FuncFormatter, MaxNLocator

from tiremodal_cli.conventions import BRANCHES
from tiremodal_cli.names import long_label
from tiremodal_cli.plots.canvas import subplots

__all__ = ["plot_dispersion", "plot_convergence", "plot_sensitivity", "plot_residuals"]


def plot_dispersion(rows, *, measured=(), ax=None):
    """Frequency against circumferential order for both branches (the paper's Fig. 12).

    rows : dicts with n, branch, model_hz (and optionally std_hz);
    measured : dicts with n, branch, measured_hz.
    """
    if ax is None:
        _, ax = subplots(figsize=(7, 5))
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
        _, ax = subplots(figsize=(6, 4))
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
        _, ax = subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for k, br in enumerate(BRANCHES):
        sel = np.asarray(branches) == br
        for j, name in enumerate(names):
            ax[k].plot(np.asarray(ns)[sel], S[sel, j], "o-", ms=3, label=long_label(name))
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
        fig, axes = subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, br in zip(axes, BRANCHES):
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
