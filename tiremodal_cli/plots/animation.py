"""The modes moving: a :class:`tiremodal_cli.io.export.ShapeSet`'s rings in the tyre's
plane, as a matplotlib animation or as looping GIFs (the report's)."""

from __future__ import annotations

import io

import numpy as np
from matplotlib.animation import FuncAnimation
from PIL import Image

from tiremodal_cli.plots.canvas import subplots

__all__ = ["animate_mode", "iter_mode_gifs", "mode_gifs", "mode_gif"]


class _ModeFigure:
    """The figure of one moving mode: the rings' still outlines and their moving lines.

    :meth:`set_mode` turns the same figure to another mode (data, scale and title);
    :meth:`draw` sets the moving lines at frame ``i`` of one period and returns them.
    """

    def __init__(self, shapes, k: int, frames: int, exaggeration: float, size_in: float):
        self.shapes, self.frames, self.exaggeration = shapes, frames, exaggeration
        self.fig, ax = subplots(figsize=(size_in, size_in))
        self.r_max = float(np.max(np.hypot(shapes.xyz_m[:, 0], shapes.xyz_m[:, 1])))
        self.lines, self.geo = self._rings(ax)
        lim = 1.25 * self.r_max
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.axis("off")
        self.title = ax.set_title("", fontsize=8)
        ax.legend(fontsize=6, loc="lower right", frameon=False)
        self.fig.subplots_adjust(left=0.02, right=0.98, bottom=0.02, top=0.9)  # (tight_layout: 4x slower, same look)
        self.set_mode(k)

    def _rings(self, ax):
        """Each ring's undeformed outline drawn, and its (empty) moving line with its nodes'
        angles, radii and indices in angle order, closed."""
        shapes = self.shapes
        colors = {"tread": "tab:blue", "sidewall": "tab:red", "rim": "0.3"}
        lines, geo = [], []
        for ring in dict.fromkeys(shapes.ring):
            sel = np.flatnonzero(np.array(shapes.ring) == ring)
            order = sel[np.argsort(np.mod(shapes.angle_rad[sel], 2 * np.pi))]
            th = np.mod(shapes.angle_rad[order], 2 * np.pi)
            rad = np.hypot(shapes.xyz_m[order, 0], shapes.xyz_m[order, 1])
            th_c, rad_c = np.append(th, th[0]), np.append(rad, rad[0])
            ax.plot(rad_c * np.cos(th_c), rad_c * np.sin(th_c), color="0.85", lw=0.8)
            (ln,) = ax.plot([], [], color=colors.get(ring, "k"), lw=1.5, marker=".", ms=3, label=ring)
            lines.append(ln)
            geo.append((th_c, rad_c, np.append(order, order[0])))
        return lines, geo

    def set_mode(self, k: int) -> None:
        """Show mode ``k``: its radial shape on each ring, the scale and the title."""
        self.phis = [self.shapes.radial[k, idx] for _, _, idx in self.geo]
        peak = max(np.max(np.abs(p)) for p in self.phis) or 1.0
        self.scale = self.exaggeration * self.r_max / peak
        self.title.set_text(f"{self.shapes.frequency_hz[k]:.1f} Hz  {self.shapes.label[k]}")

    def draw(self, i: int) -> list:
        """The moving lines at frame ``i`` of one period."""
        rot = np.exp(2j * np.pi * i / self.frames)
        for ln, (th, rad, _), phi in zip(self.lines, self.geo, self.phis):
            rr = rad + self.scale * np.real(phi * rot)
            ln.set_data(rr * np.cos(th), rr * np.sin(th))
        return self.lines


def animate_mode(shapes, k: int, *, frames: int = 16, exaggeration: float = 0.2, size_in: float = 2.4):
    """One mode shape moving, for interactive use: the rings of an
    :class:`tiremodal_cli.io.export.ShapeSet` in the tyre's plane, each node displaced
    radially by Re(φ e^{iωt}) over one period (the largest displacement ``exaggeration`` ×
    the tread radius). Returns a ``matplotlib.animation.FuncAnimation``; for a file or a
    report use :func:`mode_gif`."""
    mf = _ModeFigure(shapes, k, frames, exaggeration, size_in)
    return FuncAnimation(mf.fig, mf.draw, frames=frames, blit=True)


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
    modes = range(shapes.radial.shape[0]) if modes is None else list(modes)
    if not len(modes):
        return
    mf = _ModeFigure(shapes, modes[0], frames, exaggeration, size_in)
    mf.fig.set_dpi(dpi)
    try:
        for k in modes:
            yield _gif(mf, k, fps)
    finally:
        mf.fig.clear()


def _gif(mf: _ModeFigure, k: int, fps: int) -> bytes:
    """Mode ``k`` on the figure ``mf`` over one period, as a looping GIF's bytes: the still
    parts drawn once, each frame redrawing only the moving rings (blitting)."""
    fig, canvas = mf.fig, mf.fig.canvas
    ax = fig.axes[0]
    mf.set_mode(k)
    for ln in mf.draw(0):
        ln.set_visible(False)
    canvas.draw()  # the still parts and the title (the moving rings hidden)
    background = canvas.copy_from_bbox(fig.bbox)
    images = []
    for i in range(mf.frames):
        canvas.restore_region(background)
        for ln in mf.draw(i):
            ln.set_visible(True)
            ax.draw_artist(ln)
        rgba = np.asarray(canvas.buffer_rgba())
        images.append(Image.fromarray(rgba[..., :3]).convert("P", palette=Image.Palette.ADAPTIVE, colors=32))
    buf = io.BytesIO()
    images[0].save(buf, format="GIF", save_all=True, append_images=images[1:], duration=int(1000 / fps), loop=0)
    return buf.getvalue()


def mode_gifs(shapes, modes=None, **kw) -> list[bytes]:
    """Every mode's GIF as a list (:func:`iter_mode_gifs`, same parameters)."""
    return list(iter_mode_gifs(shapes, modes, **kw))


def mode_gif(shapes, k: int, **kw) -> bytes:
    """One mode shape moving as the bytes of a looping GIF (:func:`mode_gifs` for one mode)."""
    return mode_gifs(shapes, [k], **kw)[0]
