"""The command group: help, version, error handling shared by every command."""

import re

from tiremodal_cli import __version__
from tiremodal_cli.cli.main import cli

from conftest import run_cli


def test_help_lists_every_command_with_one_line():
    res = run_cli(["--help"])
    assert res.exit_code == 0
    listed = re.findall(r"^  (\w[\w-]*)\s{2,}\S", res.stdout.split("Commands:")[1], flags=re.M)
    assert set(listed) == set(cli.commands)


def test_version():
    res = run_cli(["--version"])
    assert res.exit_code == 0 and __version__ in res.stdout


def test_usage_errors_are_one_line_exit_2(tmp_path):
    for args in (["frobnicate"], ["frf"], ["frf", tmp_path / "x.h5", "-o", tmp_path / "y.h5", "--estimator", "H9"]):
        res = run_cli(args)
        assert res.exit_code == 2
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("Error: "), lines
