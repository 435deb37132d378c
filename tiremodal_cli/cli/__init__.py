"""The ``tiremodal`` command line: one thin module per command."""
