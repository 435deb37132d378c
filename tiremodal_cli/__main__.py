"""``python -m tiremodal_cli``: the ``tiremodal`` command."""

from tiremodal_cli.cli.main import cli

if __name__ == "__main__":
    cli()
