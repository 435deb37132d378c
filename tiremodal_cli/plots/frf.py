"""Figures of the FRF stage: magnitude, phase and coherence of an :class:`FRFResult`."""

from __future__ import annotations

import numpy as np

from tiremodal_cli.conventions import FORM_UNITS_DISPLAY
from tiremodal_cli.plots.canvas import subplots

__all__ = ["plot_frf"]


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
        fig, axes = subplots(3, 1, sharex=True, figsize=(8, 8),
                                 gridspec_kw={"height_ratios": [3, 1.5, 1]})
    channels = [c for c in (channels or r.channel_name) if c not in r.dead_channels]
    for c in channels:
        ic = r.channel_name.index(c)
        for ip in points:
            lab = f"{c} / point {int(r.point_index[ip]) + 1} ({np.rad2deg(r.point_angle[ip]):.0f}°)"
            axes[0].semilogy(r.freq_hz, np.abs(r.H[ic, ip]), lw=1, label=lab)
            axes[1].plot(r.freq_hz, np.rad2deg(np.angle(r.H[ic, ip])), lw=0.8)
            axes[2].plot(r.freq_hz, r.coherence[ic, ip], lw=0.8)
    units = FORM_UNITS_DISPLAY[r.form]
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
