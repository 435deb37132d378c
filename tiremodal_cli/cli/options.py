"""Options and helpers shared by the commands."""

from __future__ import annotations

import json
import sys

import click
import numpy as np

overwrite_option = click.option("--overwrite", is_flag=True,
                                help="Replace existing outputs (refused otherwise).")
json_option = click.option("--json", "as_json", is_flag=True, help="Print JSON on stdout.")


def _default(o):
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (set, tuple)):
        return list(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def dumps(obj) -> str:
    """JSON text of ``obj`` (numpy scalars and arrays allowed)."""
    return json.dumps(obj, indent=2, default=_default, allow_nan=False) + "\n"


def echo_json(obj) -> None:
    click.echo(dumps(obj), nl=False)


class Progress:
    """A progress callback that draws a bar on stderr (nothing when stderr is not a TTY)."""

    def __init__(self, label: str):
        self.label = label
        self.bar = None

    def __call__(self, done: int, total: int) -> None:
        if not sys.stderr.isatty():
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


def parse_key_values(items, what: str) -> dict:
    """``("a=1", "b=2")`` → ``{"a": "1", "b": "2"}``; a malformed item is a usage error."""
    out = {}
    for it in items:
        if "=" not in it:
            raise click.BadParameter(f"{it!r} is not NAME=VALUE", param_hint=what)
        k, v = it.split("=", 1)
        out[k.strip()] = v.strip()
    return out
