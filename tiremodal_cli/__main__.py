"""``python -m tiremodal_cli``: the ``tiremodal`` command."""

from .cli.main import cli

if __name__ == "__main__":
    cli()
