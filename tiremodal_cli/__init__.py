"""tiremodal: roving-hammer tests of tyres turned into validated physical models.

The Python API (``docs/api.md``)::

    import tiremodal_cli as tm

    with tm.open_measurement("sample_data/gl073a_sim.h5") as m:
        frf = tm.compute_frf(m)                                  # FRFs, coherence, hit checks
    table, _ = tm.modal_table_from_frf(frf)                      # modes, n and branch
    modes, _ = tm.modes_from_rows(tm.to_rows(table))
    res = tm.fit(modes, tm.TyreParameters(m_w=1000.0))           # k_r1, k_r2, EI
    diag = tm.diagnose_modes(tm.to_rows(table), tm.TyreParameters(m_w=1000.0))

Every name of :data:`__all__` is imported from its module when first used (so that
``tiremodal --help`` starts without numpy, scipy or h5py); ``tm.<name>`` is the same
object as ``tiremodal_cli.<stage>.<module>.<name>`` (the table below; the stages in
``docs/architecture.md``). Three functions carry names other than their own, because a
module or package of the package has theirs: ``simulate_test`` (``tyre.simulate.simulate``),
``diagnose_modes`` (``diagnose.diagnose``), ``write_report`` (``workflow.report.report``).
Array and unit conventions are written down
once, in ``docs/conventions.md``.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: the public surface: name → (module, attribute) — documented in docs/api.md
_API = {
    # measurements in and simulated
    "Measurement": ("io.measurement", "Measurement"),
    "open_measurement": ("io.measurement", "open_measurement"),
    "read_measurement": ("io.measurement", "read_measurement"),
    "write_measurement": ("io.measurement", "write_measurement"),
    "read_source": ("io.ingest", "read_source"),
    "simulate_test": ("tyre.simulate", "simulate"),
    "SimulationConfig": ("tyre.simulate", "SimulationConfig"),
    # FRFs
    "FRFOptions": ("frf.estimate", "FRFOptions"),
    "FRFResult": ("frf.estimate", "FRFResult"),
    "compute_frf": ("frf.estimate", "compute_frf"),
    "read_frf": ("io.frffile", "read_frf"),
    "write_frf": ("io.frffile", "write_frf"),
    "read_frf_uff": ("io.frfuff", "read_frf_uff"),
    "write_frf_uff": ("io.frfuff", "write_frf_uff"),
    # modes
    "ModalOptions": ("modal.modes", "ModalOptions"),
    "modal_table_from_frf": ("modal.modes", "modal_table_from_frf"),
    "ModalTable": ("modal.table", "ModalTable"),
    "read_modal": ("io.modalfile", "read_modal"),
    "write_modal": ("io.modalfile", "write_modal"),
    "to_rows": ("modal.table", "to_rows"),
    "mac_matrix": ("modal.mac", "mac_matrix"),
    # the tyre model and its fit
    "TyreParameters": ("tyre.model", "TyreParameters"),
    "FitOptions": ("tyre.fit_types", "FitOptions"),
    "fit": ("tyre.fit", "fit"),
    "modes_from_rows": ("tyre.measured", "modes_from_rows"),
    "predict_table": ("tyre.predict", "predict_table"),
    # the diagnosis
    "DiagnoseOptions": ("diagnose", "DiagnoseOptions"),
    "diagnose_modes": ("diagnose", "diagnose"),
    "diagnosis_report": ("diagnose", "report"),
    # the whole loop, pages and shapes out
    "RunOptions": ("workflow.run_options", "RunOptions"),
    "run": ("workflow.pipeline", "run"),
    "run_folder": ("workflow.run_folder", "run_folder"),
    "run_batch": ("workflow.batch", "run_batch"),
    "write_report": ("workflow.report", "report"),
    "shape_set": ("io.export", "shape_set"),
    "export_folder": ("io.export", "export_folder"),
    # names and units of every parameter
    "names": ("names", None),
}

__all__ = ["__version__", *_API]


def __getattr__(name: str):
    try:
        module, attr = _API[name]
    except KeyError:
        raise AttributeError(f"module 'tiremodal_cli' has no attribute {name!r}") from None
    mod = importlib.import_module(f"{__name__}.{module}")
    value = mod if attr is None else getattr(mod, attr)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(_API))
