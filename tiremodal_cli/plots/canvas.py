"""The figure canvas of every plot: a ``Figure`` on its own Agg canvas, made without pyplot.

Importing this changes no global state (a notebook keeps its backend) and needs no screen.
"""

from __future__ import annotations

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from tiremodal_cli.io.files import atomic_path

__all__ = ["subplots", "save_figure"]


def subplots(*args, figsize=None, **kw):
    """pyplot's subplots without pyplot: a Figure on its own Agg canvas, and its axes."""
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(*args, **kw)


def save_figure(fig, path, *, overwrite: bool = False) -> None:
    """Save a figure atomically (format from the suffix)."""
    fmt = str(path).rsplit(".", 1)[-1].lower()
    with atomic_path(path, overwrite=overwrite) as tmp:
        fig.savefig(tmp, format=fmt, dpi=120)
