"""The ``tiremodal`` click group: error handling shared by every command.

Every :class:`~tiremodal_cli.errors.TiremodalError` and every usage error becomes one line
on stderr and exit status 2; no traceback reaches the user.
"""

from __future__ import annotations

import logging
import sys

import click

from .. import __version__
from ..errors import TiremodalError

_NO_ARGS = getattr(click.exceptions, "NoArgsIsHelpError", None)  # click ≥ 8.2
COMMANDS = ("run", "batch", "report", "simulate", "ingest", "info", "frf", "lsce", "mac", "predict", "identify", "diagnose",
            "sensitivity")


class TiremodalGroup(click.Group):
    def list_commands(self, ctx):
        return [c for c in COMMANDS if c in self.commands] + sorted(set(self.commands) - set(COMMANDS))

    def main(self, args=None, prog_name=None, **extra):
        extra.pop("standalone_mode", None)  # this group always handles its own exits
        try:
            rv = super().main(args=args, prog_name=prog_name or "tiremodal", standalone_mode=False, **extra)
        except click.UsageError as exc:
            if _NO_ARGS is not None and isinstance(exc, _NO_ARGS):
                click.echo(exc.ctx.get_help(), err=True)
                sys.exit(2)
            hint = f" (see '{exc.ctx.command_path} --help')" if exc.ctx is not None else ""
            click.echo(f"Error: {exc.format_message()}{hint}", err=True)
            sys.exit(2)
        except click.exceptions.Exit as exc:
            sys.exit(exc.exit_code)
        except click.Abort as exc:
            if isinstance(exc.__context__, KeyboardInterrupt):  # click turns Ctrl-C into Abort
                click.echo("Interrupted.", err=True)
                sys.exit(130)
            click.echo("Aborted.", err=True)
            sys.exit(1)
        except click.ClickException as exc:
            click.echo(f"Error: {exc.format_message()}", err=True)
            sys.exit(exc.exit_code)
        except TiremodalError as exc:
            click.echo(f"Error: {exc}", err=True)
            sys.exit(2)
        except KeyboardInterrupt:
            click.echo("Interrupted.", err=True)
            sys.exit(130)
        except OSError as exc:
            click.echo(f"Error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "), err=True)
            sys.exit(1)
        sys.exit(rv if isinstance(rv, int) else 0)


@click.group(cls=TiremodalGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="tiremodal")
@click.option("-v", "--verbose", count=True, help="More messages on stderr (-vv for debug).")
@click.option("-q", "--quiet", is_flag=True, help="Only errors on stderr.")
def cli(verbose, quiet):
    """Roving-hammer tests of tyres turned into validated physical models.

    Pipeline: ingest → frf → lsce → identify → diagnose. stdout carries data (JSON or
    CSV), stderr carries messages and progress bars. Exit status 2 means bad input.
    """
    level = logging.ERROR if quiet else {0: logging.WARNING, 1: logging.INFO}.get(verbose, logging.DEBUG)
    logging.basicConfig(level=level, format="tiremodal: %(levelname)s: %(message)s", stream=sys.stderr)


def _register():
    from . import (batch, diagnose, export, frf, identify, info, ingest, lsce, mac, predict, report,  # noqa: F401
                   run, sensitivity, simulate)


_register()
