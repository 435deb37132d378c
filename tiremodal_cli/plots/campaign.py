"""Figures across a batch's tests, from its records (``summary.jsonl``): identified
parameters and measured frequencies against the test condition."""

from __future__ import annotations

import matplotlib
import numpy as np

from tiremodal_cli.conventions import BRANCHES
from tiremodal_cli.names import effect_title, long_label
from tiremodal_cli.plots.canvas import subplots

__all__ = ["plot_campaign_parameters", "plot_campaign_frequencies"]


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
    fig, axes = subplots(nrows, ncols, figsize=(4 * ncols, 3.6 * nrows), squeeze=False)
    xd = _dodge(x)
    repeats = xd.size != np.unique(x).size
    for ax, k in zip(axes.ravel(), params):
        v, e = _campaign_values(ok, k)
        ax.errorbar(xd, v, yerr=np.where(np.isfinite(e), e, 0), fmt="o", ms=4, capsize=3)
        title = long_label(k)
        if "." in k:
            title = f"{effect_title(k.split('.')[0])}:\n{title}"
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
    fig, axes = subplots(1, 2, figsize=(11, 4.5), sharey=True)
    for ax, br in zip(axes, BRANCHES):
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
