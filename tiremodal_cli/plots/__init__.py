"""Figures, kept apart from the computations: each takes a result and returns axes or a figure.

One module per subject: :mod:`~tiremodal_cli.plots.frf` (the FRF stage),
:mod:`~tiremodal_cli.plots.modal` (stabilization, MAC, shapes, re-synthesis),
:mod:`~tiremodal_cli.plots.tyre` (the model's fit and the diagnosis),
:mod:`~tiremodal_cli.plots.campaign` (across a batch's tests) and
:mod:`~tiremodal_cli.plots.animation` (the modes moving); every public function is
importable from here as well.

Uses matplotlib's object API: every figure is a ``matplotlib.figure.Figure`` on its own Agg
canvas (:mod:`~tiremodal_cli.plots.canvas`), made without pyplot, so importing this package
changes no global state (a notebook keeps its backend) and no screen is needed.
"""

from __future__ import annotations

from tiremodal_cli.plots.animation import animate_mode, iter_mode_gifs, mode_gif, mode_gifs
from tiremodal_cli.plots.campaign import plot_campaign_frequencies, plot_campaign_parameters
from tiremodal_cli.plots.canvas import save_figure
from tiremodal_cli.plots.frf import plot_frf
from tiremodal_cli.plots.modal import (MAC_VALUES_MAX, automac_figure, mode_labels, plot_mac, plot_shapes,
                                       plot_stabilization, plot_synthesis, stabilization_figure, stabilization_grid,
                                       synthesis_figure)
from tiremodal_cli.plots.tyre import plot_convergence, plot_dispersion, plot_residuals, plot_sensitivity

__all__ = ["plot_frf", "save_figure", "plot_stabilization", "plot_mac", "plot_shapes", "plot_synthesis",
           "plot_dispersion", "plot_convergence", "plot_sensitivity", "plot_residuals", "plot_campaign_parameters",
           "plot_campaign_frequencies", "stabilization_figure", "automac_figure", "synthesis_figure", "mode_labels",
           "stabilization_grid", "animate_mode", "mode_gif", "mode_gifs", "iter_mode_gifs", "MAC_VALUES_MAX"]
