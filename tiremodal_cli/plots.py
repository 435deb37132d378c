"""Figures, kept apart from the computations: each takes a result and returns axes.

Uses matplotlib's object API with the Agg backend (no screen needed).
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .files import atomic_path  # noqa: E402

__all__ = ["plot_frf", "save_figure"]


def save_figure(fig, path, *, overwrite: bool = False) -> None:
    """Save a figure atomically (format from the suffix) and close it."""
    fmt = str(path).rsplit(".", 1)[-1].lower()
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format=fmt, dpi=120)
    plt.close(fig)


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
        fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 8),
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
    axes[0].set_ylabel(f"|{r.estimator}| [{units}]")
    axes[1].set_ylabel("phase [°]")
    axes[1].set_yticks([-180, -90, 0, 90, 180])
    axes[2].set_ylabel("coherence")
    axes[2].set_ylim(0, 1.05)
    axes[2].set_xlabel("frequency [Hz]")
    axes[0].legend(fontsize=7)
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return axes
