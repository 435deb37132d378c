"""issue #18: importing the package or running a computation changes no global state."""

import subprocess
import sys

import numpy as np


def test_importing_plots_keeps_the_matplotlib_backend():
    """A notebook's backend survives ``import tiremodal_cli.plots`` (it used to be forced to Agg)."""
    code = ("import matplotlib; matplotlib.use('svg'); import tiremodal_cli.plots, tiremodal_cli.workflow.report; "
            "print(matplotlib.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "svg"


def test_numpy_error_state_is_restored_after_a_point_mass_solve():
    from tiremodal_cli.tyre.frequencies import point_mass_pairs
    from tiremodal_cli.tyre.model import TyreParameters
    before = np.geterr()
    point_mass_pairs(TyreParameters(), 1.0, 6)
    assert np.geterr() == before
