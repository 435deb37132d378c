"""The diagnosis: the residual, the candidate effects, the loop and its verdict (-> Diagnosis).

Modules, in the order they build on one another: ``options`` (DiagnoseOptions, the fit
options of every refit), ``statistics`` (χ², AICc, F-test, the residual's pattern),
``result`` (Candidate, Diagnosis, the verdict's prose and JSON), ``refit`` (refits and the
judgement of a candidate), ``cavity`` and ``aliases`` (the air cavity's evidence; spatial
aliases relabelled), ``candidates`` (every candidate tried and the round's choice), ``loop``
(usable modes, the base fit, :func:`diagnose`).
"""

from tiremodal_cli.diagnose.loop import MeasuredModes, base_fit, diagnose, usable_modes
from tiremodal_cli.diagnose.options import PARAMETER_CANDIDATES, DiagnoseOptions, cavity_band_hz
from tiremodal_cli.diagnose.result import Candidate, Diagnosis, mode_table, predictions, report
from tiremodal_cli.diagnose.statistics import residual_analysis

__all__ = ["DiagnoseOptions", "PARAMETER_CANDIDATES", "cavity_band_hz", "MeasuredModes", "usable_modes", "base_fit",
           "diagnose", "Candidate", "Diagnosis", "report", "mode_table", "predictions", "residual_analysis"]
