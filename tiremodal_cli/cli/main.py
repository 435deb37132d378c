"""The ``tiremodal`` click group: error handling shared by every command.

Every :class:`~tiremodal_cli.errors.TiremodalError` and every usage error becomes one line
on stderr and exit status 2; no traceback reaches the user.
"""

from __future__ import annotations

import importlib
import logging
import sys

import click

from tiremodal_cli import __version__
from tiremodal_cli.errors import TiremodalError

_NO_ARGS = getattr(click.exceptions, "NoArgsIsHelpError", None)  # click ≥ 8.2
COMMANDS = ("run", "batch", "report", "simulate", "ingest", "info", "frf", "lsce", "mac", "predict", "identify", "diagnose",
            "sensitivity", "export")
#: Each command's one-line help, so that ``tiremodal --help`` lists them without importing
#: them (tests/test_cli.py checks that each equals its command's own first sentence).
SHORT_HELP = {
    "run": "Run frf → lsce → identify → diagnose on MEASUREMENT, writing each stage into OUTDIR.",
    "batch": "Run frf → lsce → identify → diagnose on every test under ROOTS.",
    "report": "Write report.html (figures embedded; also as PNG and SVG in figures/) for the run folder OUTDIR, "
              "or for every test of the batch folder OUTDIR plus its index.html.",
    "simulate": "Simulate a roving-hammer test of a tyre into OUTPUT (HDF5).",
    "ingest": "Convert SOURCES (UFF 58 files/folders, or one CSV folder) into a measurement file.",
    "info": "Summarise a tiremodal FILE (measurement, FRF or modal file, or a UFF file).",
    "frf": "Estimate FRFs of MEASUREMENT into OUTPUT, rejecting bad hits (reported).",
    "lsce": "Estimate modes of FRF_FILE (FRF HDF5 or UFF 58 FRFs) into OUTPUT.",
    "mac": "AutoMAC of MODAL_FILE, or cross-MAC against OTHER (a second modal file), --analytic or --model.",
    "predict": "Modes of the model: frequency of every (n, branch) up to --n-max (the cos members).",
    "identify": "Fit the model to MODES_FILE (a modal file from lsce, or a CSV with frequency_hz, n, branch).",
    "diagnose": "Find what the model fitted to MODES_FILE lacks, add it, and report the error before and after.",
    "sensitivity": "How each parameter moves the frequencies (80/100/120 % study and normalised coefficients).",
    "export": "Export the mode shapes of SOURCE (a run folder or a modal file) into the folder OUTPUT.",
}


class _LazyCommands(dict):
    """The group's commands, each imported when first asked for (start-up: ``tiremodal
    --help`` imports no command module, so neither scipy nor h5py). A command's module
    ``tiremodal_cli.cli.<name>`` registers it here through its ``@cli.command``
    decorator; iterating over all of them imports them all."""

    def _load(self, name):
        if name in COMMANDS and not dict.__contains__(self, name):
            importlib.import_module(f"{__package__}.{name}")

    def _load_all(self):
        for name in COMMANDS:
            self._load(name)

    def get(self, name, default=None):
        self._load(name)
        return dict.get(self, name, default)

    def __getitem__(self, name):
        self._load(name)
        return dict.__getitem__(self, name)

    def __contains__(self, name):
        self._load(name)
        return dict.__contains__(self, name)

    def __iter__(self):
        self._load_all()
        return dict.__iter__(self)

    def __len__(self):
        self._load_all()
        return dict.__len__(self)

    def keys(self):
        self._load_all()
        return dict.keys(self)

    def values(self):
        self._load_all()
        return dict.values(self)

    def items(self):
        self._load_all()
        return dict.items(self)


class _Stderr(logging.StreamHandler):
    """A handler writing to the ``sys.stderr`` of the moment (a test runner swaps it)."""

    @property
    def stream(self):
        return sys.stderr

    @stream.setter
    def stream(self, value):
        pass


class TiremodalGroup(click.Group):
    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self.commands = _LazyCommands(self.commands)

    def list_commands(self, ctx):
        loaded = dict.keys(self.commands)  # without importing every command
        return list(COMMANDS) + sorted(set(loaded) - set(COMMANDS))

    def format_commands(self, ctx, formatter):
        """The command list from :data:`SHORT_HELP` (no command imported to show it)."""
        names = self.list_commands(ctx)
        limit = formatter.width - 6 - max(len(n) for n in names)
        rows = []
        for name in names:
            text = SHORT_HELP.get(name)
            if text is None or dict.__contains__(self.commands, name):
                text = self.commands[name].get_short_help_str(limit)
            elif len(text) > limit:
                text = text[:limit - 3].rsplit(" ", 1)[0] + "..."
            rows.append((name, text))
        with formatter.section("Commands"):
            formatter.write_dl(rows)

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
    # -v and -vv speak for tiremodal's own loggers; other libraries (matplotlib, h5py, dask)
    # say only their warnings (errors with -q), never their info or debug chatter. One
    # handler on the root, as logging.basicConfig would add (none when the host program,
    # e.g. a test runner, has its own).
    logging.getLogger("tiremodal_cli").setLevel(level)
    root = logging.getLogger()
    root.setLevel(logging.ERROR if quiet else logging.WARNING)
    if not root.handlers:
        handler = _Stderr()
        handler.setFormatter(logging.Formatter("tiremodal: %(levelname)s: %(message)s"))
        root.addHandler(handler)
    click.get_current_context().obj = {"quiet": quiet, "verbose": verbose}
