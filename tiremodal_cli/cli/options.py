"""Options and helpers shared by the commands."""

from __future__ import annotations

import json
import logging
import math
import sys
from pathlib import Path

import click

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.config import load_mapping
from tiremodal_cli.io.files import dumps  # noqa: F401  (re-exported for the commands)
from tiremodal_cli.io.measurement import file_format
from tiremodal_cli.io.modalfile import FORMAT_NAME, read_modal, read_modal_csv
from tiremodal_cli.modal.table import to_rows
from tiremodal_cli.io.modalfile import no_usable_modes  # noqa: F401  (re-exported for the commands

# Start-up: every command imports this module, so what only some need is imported inside the
# function that needs it (the tyre model and scipy, matplotlib).

overwrite_option = click.option("--overwrite", is_flag=True,
                                help="Replace existing outputs (refused otherwise).")
json_option = click.option("--json", "as_json", is_flag=True, help="Print JSON on stdout.")


def echo_json(obj) -> None:
    click.echo(dumps(obj), nl=False)


def _tty() -> bool:
    return sys.stderr.isatty()


def quiet() -> bool:
    """True when ``tiremodal -q`` was given: nothing but errors on stderr."""
    ctx = click.get_current_context(silent=True)
    return bool(ctx is not None and (ctx.find_root().obj or {}).get("quiet"))


def say(text: str) -> None:
    """A message for the person (stderr), not data: nothing with ``tiremodal -q``."""
    if not quiet():
        click.echo(text, err=True)


def show_progress() -> bool:
    """Bars and stage messages only for a person: stderr a terminal, and no ``-q``."""
    return _tty() and not quiet()


class Progress:
    """A progress callback that draws a bar on stderr (nothing when stderr is not a TTY, or
    with ``-q``)."""

    def __init__(self, label: str):
        self.label = label
        self.bar = None

    def __call__(self, done: int, total: int) -> None:
        if not show_progress():
            return
        if self.bar is None:
            self.bar = click.progressbar(length=total, label=self.label, file=sys.stderr)
            self.bar.__enter__()
        self.bar.update(done - self.bar.pos)
        if done >= total:
            self.close()

    def close(self):
        if self.bar is not None:
            self.bar.__exit__(None, None, None)
            self.bar = None


class StageProgress:
    """A bar over a long command's stages on stderr, the current stage beside it (on a
    terminal, without ``-q``); each stage also logged at INFO (``-v``: the stages in a log).

    Call it with each stage's name as it starts; :meth:`close` when done.
    """

    def __init__(self, label: str, stages):
        self.label, self.stages, self.bar = label, list(stages), None
        self._log = logging.getLogger("tiremodal_cli.progress")

    def __call__(self, stage: str) -> None:
        self._log.info("%s: %s", self.label, stage)
        if not show_progress():
            return
        if self.bar is None:
            self.bar = click.progressbar(length=len(self.stages), label=self.label, file=sys.stderr, show_pos=True,
                                         show_eta=False, item_show_func=lambda s: s or "")
            self.bar.__enter__()
        k = self.stages.index(stage) if stage in self.stages else self.bar.pos
        self.bar.update(max(k - self.bar.pos, 0), current_item=stage)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.update(len(self.stages) - self.bar.pos, current_item="done")
            self.bar.__exit__(None, None, None)
            self.bar = None


def parse_key_values(items, what: str) -> dict:
    """``("a=1", "b=2")`` → ``{"a": "1", "b": "2"}``; a malformed item is a usage error."""
    out = {}
    for it in items:
        if "=" not in it:
            raise click.BadParameter(f"{it!r} is not NAME=VALUE", param_hint=what)
        k, v = it.split("=", 1)
        out[k.strip()] = v.strip()
    return out


def params_options(f):
    """--params FILE and --param NAME=VALUE: the tyre model's parameters."""
    f = click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE",
                     help="A model parameter, e.g. k_r1=6.7e6, m_w=clamped (repeatable; default: the paper's).")(f)
    f = click.option("--params", "params_file", type=click.Path(exists=True, dir_okay=False),
                     help="TOML/JSON with the model parameters (a [params] table, or flat).")(f)
    return f


def load_params(params_file, param_items):
    """TyreParameters from a file (its [params] table, or the top level) and NAME=VALUE items."""
    from tiremodal_cli.tyre.model import TyreParameters

    base = {}
    effects = {}
    if params_file:
        data = load_mapping(params_file)
        base = dict(data.get("params", {k: v for k, v in data.items() if not isinstance(v, dict)}))
        effects = {k: dict(v) for k, v in data.get("effects", {}).items()}
    base.update(parse_key_values(param_items, "--param"))
    return TyreParameters.from_mapping(base), effects


def read_table_rows(path: Path):
    """Modal-table rows from a modal file (``lsce``) or a CSV with frequency_hz, n, branch."""
    path = Path(path)
    if path.suffix.lower() == ".csv":
        return read_modal_csv(path)
    fmt = file_format(path, "a modal file (HDF5, written by lsce) or a CSV named *.csv with frequency_hz, n, branch")
    if fmt != FORMAT_NAME:
        raise DataFormatError(f"{path}: format {fmt!r} is not a modal file or CSV; run 'tiremodal lsce' first")
    return to_rows(read_modal(path))


class FiniteRange(click.FloatRange):
    """A float option in a range that is also finite (click's FloatRange lets nan and inf by)."""

    name = "float"

    def convert(self, value, param, ctx):
        rv = super().convert(value, param, ctx)
        if not math.isfinite(rv):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return rv


def _plot_formats() -> dict:
    from matplotlib.backend_bases import FigureCanvasBase

    return FigureCanvasBase.get_supported_filetypes()


class PlotPath(click.Path):
    """An output figure's path whose suffix names a format matplotlib writes (checked
    before any work is done)."""

    def __init__(self):
        super().__init__(dir_okay=False, path_type=Path)

    def convert(self, value, param, ctx):
        rv = super().convert(value, param, ctx)
        fmt = Path(rv).suffix.lower().lstrip(".")
        allowed = _plot_formats()
        if fmt not in allowed:
            self.fail(f"{str(value)!r}: format {fmt or '(no suffix)'!r} is not one a figure can be written in; "
                      f"allowed: {', '.join(sorted(allowed))}", param, ctx)
        return rv


def band_option(help_text: str, **kw):
    """--band LO HI (Hz): finite, 0 ≤ LO < HI."""

    def check(ctx, param, value):
        if not value:
            return value
        lo, hi = value
        if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
            raise click.BadParameter(f"{lo:g} {hi:g}: allowed: finite 0 ≤ LO < HI (Hz)", ctx, param)
        return value

    return click.option("--band", nargs=2, type=float, metavar="LO HI", callback=check, help=help_text, **kw)

