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
object as ``tiremodal_cli.<module>.<name>``. Three functions carry names other than their
own, because a module of the package has theirs (and the import system sets
``tiremodal_cli.<module>`` to the module): ``simulate_test`` (``simulate.simulate``),
``diagnose_modes`` (``diagnose.diagnose``), ``write_report`` (``report.report``). Array and unit conventions are written down
once, in ``docs/conventions.md``.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

#: the public surface: name → (module, attribute) — documented in docs/api.md
_API = {
    # measurements in and simulated
    "Measurement": ("measurement", "Measurement"),
    "open_measurement": ("measurement", "open_measurement"),
    "read_measurement": ("measurement", "read_measurement"),
    "write_measurement": ("measurement", "write_measurement"),
    "read_source": ("ingest", "read_source"),
    "simulate_test": ("simulate", "simulate"),
    "SimulationConfig": ("simulate", "SimulationConfig"),
    # FRFs
    "FRFOptions": ("frf", "FRFOptions"),
    "FRFResult": ("frf", "FRFResult"),
    "compute_frf": ("frf", "compute_frf"),
    "read_frf": ("frffile", "read_frf"),
    "write_frf": ("frffile", "write_frf"),
    "read_frf_uff": ("frffile", "read_frf_uff"),
    "write_frf_uff": ("frffile", "write_frf_uff"),
    # modes
    "ModalOptions": ("modes", "ModalOptions"),
    "modal_table_from_frf": ("modes", "modal_table_from_frf"),
    "ModalTable": ("modalfile", "ModalTable"),
    "read_modal": ("modalfile", "read_modal"),
    "write_modal": ("modalfile", "write_modal"),
    "to_rows": ("modalfile", "to_rows"),
    "mac_matrix": ("mac", "mac_matrix"),
    # the tyre model and its fit
    "TyreParameters": ("model", "TyreParameters"),
    "FitOptions": ("identify", "FitOptions"),
    "fit": ("identify", "fit"),
    "modes_from_rows": ("identify", "modes_from_rows"),
    "predict_table": ("identify", "predict_table"),
    # the diagnosis
    "DiagnoseOptions": ("diagnose", "DiagnoseOptions"),
    "diagnose_modes": ("diagnose", "diagnose"),
    "diagnosis_report": ("diagnose", "report"),
    # the whole loop, pages and shapes out
    "RunOptions": ("pipeline", "RunOptions"),
    "run": ("pipeline", "run"),
    "run_folder": ("pipeline", "run_folder"),
    "run_batch": ("batch", "run_batch"),
    "write_report": ("report", "report"),
    "shape_set": ("export", "shape_set"),
    "export_folder": ("export", "export_folder"),
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
