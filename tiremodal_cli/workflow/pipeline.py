"""``run``: every stage in a row — frf → lsce → identify → diagnose — into one folder.

Each stage's output is written atomically into the output folder as it completes
(``frf.h5``, ``modal.h5``, ``modes.csv``, ``identify.json``, ``diagnosis.json``,
``sensitivity.json``: ∂ln f/∂ln p of the final model at its parameters); the
manifest ``run.json`` (the input's checksum, the options, each output's checksum, the
summary) is written last, so a folder with a manifest whose checksums match is complete
and a folder without one is not.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_info

from tiremodal_cli.diagnose.loop import DiagnoseOptions, base_fit, diagnose, report, usable_modes
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.io.config import load_mapping
from tiremodal_cli.io.files import sha256_file, write_text_atomic
from tiremodal_cli.io.frffile import write_frf
from tiremodal_cli.io.frfuff import is_uff, read_frf_uff
from tiremodal_cli.io.ingest import load_channel_map
from tiremodal_cli.io.measurement import open_measurement
from tiremodal_cli.io.modalfile import no_usable_modes
from tiremodal_cli.io.modalfile import read_modal_csv, to_csv, write_modal
from tiremodal_cli.modal.table import to_rows
from tiremodal_cli.modal.modes import ModalOptions, modal_table_from_frf
from tiremodal_cli.modal.spatial import grid_points
from tiremodal_cli.tyre.flexible_tread import errors_by_branch, fit_flexible_tread
from tiremodal_cli.tyre.measured import modes_from_rows
from tiremodal_cli.tyre.model import NOMINAL_RIM_KG, TyreParameters
from tiremodal_cli.tyre.predict import fit_report, predict_table
from tiremodal_cli.tyre.sensitivity import PAPER_STUDY, coefficients
from tiremodal_cli.workflow.manifest import files_sha256, provenance
from tiremodal_cli.workflow.run_options import MANIFEST, MODES_OUTPUTS, OUTPUTS, RunOptions, json_text

__all__ = ['run', 'rim_condition', 'rim_state', 'read_uff_test', 'thread_budget', 'is_modes_table', 'MODES_OUTPUTS']


def rim_condition(r, params: TyreParameters) -> tuple[TyreParameters, str]:
    """The rim's condition from the data: the model's rim and a sentence saying why.

    A rim channel that recorded no signal (a dead channel of the FRF stage) means a rim
    clamped to a rigid fixture (m_w → ∞, ``m_w = None``); a rim channel that moves means a
    free rim, whose mass is the parameters' (or :data:`NOMINAL_RIM_KG`); without a rim
    channel the parameters decide. (The paper's model couples the rim to n = 1 only.)
    """
    rim = [n for n, loc in zip(r.channel_name, r.channel_location) if loc == "rim"]
    if not rim:
        how = "clamped" if params.m_w is None else f"free, m_w = {params.m_w:g} kg"
        return params, f"{how}: from the parameters (the test has no rim channel)"
    if all(n in r.dead_channels for n in rim):
        return params.replace(m_w=None), (f"clamped: the rim channel ({', '.join(rim)}) recorded no signal")
    m_w = params.m_w if params.m_w is not None else NOMINAL_RIM_KG
    return params.replace(m_w=m_w), (f"free: the rim channel ({', '.join(n for n in rim if n not in r.dead_channels)}) "
                                     f"moves; rim + fixture mass m_w = {m_w:g} kg to start from")


def rim_state(how: str) -> str:
    """The rim condition of :func:`rim_condition`'s sentence as ``diagnose`` takes it:
    "clamped" or "free" when the rim channel said so, else "from parameters"."""
    for state in ("clamped", "free"):
        if how.startswith(f"{state}: the rim channel"):
            return state
    return "from parameters"


def run(measurement, outdir, opt: RunOptions = RunOptions(), *, params: TyreParameters | None = None,
        progress=None, source: dict | None = None, mapping=None) -> dict:
    """Run the whole pipeline on one measurement file; return the summary.

    Parameters
    ----------
    measurement : path of a measurement file (docs/format.md), or of UFF 58 FRFs (``*.uff``,
        ``*.unv``; a list for a test in several files): such a test starts at lsce
        (:func:`read_uff_test`; its units, geometry and flipped channels in the summary)
    outdir : folder for the outputs (created; existing outputs are replaced)
    opt : RunOptions
    params : nominal model parameters (default: the paper's); P0 is replaced by the
        measurement's pressure (see RunOptions.pressure_from_file), and the rim is clamped
        or free as the rim channel shows (:func:`rim_condition`)
    progress : callable(stage: str) called as each stage starts, optional
    source : {"path", "kind", "sha256"} of what the measurement came from when it was
        ingested from a UFF/CSV folder (default: the measurement file itself); recorded in
        the manifest, whose ``source.sha256`` is what a batch compares to skip a done test.
    mapping : mapping file (TOML/JSON) for UFF FRFs: channels, point angles, ``[test]``

    Files inside ``outdir`` refer to each other by name (the folder can be moved).

    Returns
    -------
    dict
        The summary (also ``run.json``'s ``summary``): the test's facts, rejected hits,
        modes found, identified parameters with standard errors, the diagnosis' verdict,
        the RMS errors before and after; for UFF FRFs ``starts_at`` and ``frf_source``.
    """
    t0 = time.perf_counter()
    outdir = Path(outdir)
    paths = [Path(p) for p in measurement] if isinstance(measurement, (list, tuple)) else [Path(measurement)]
    say = progress or (lambda stage: None)
    if len(paths) == 1 and is_modes_table(paths[0]):
        return _run_on_modes(paths[0], outdir, opt, params or TyreParameters(), source, say, t0)
    r, meta, sha = _frf_input(paths, opt, mapping, say)
    nominal = params or TyreParameters()
    params = nominal
    if opt.pressure_from_file and meta["inflation_pressure"] is not None and float(meta["inflation_pressure"]) > 0:
        params = params.replace(P0=float(meta["inflation_pressure"]))
    params, rim_how = rim_condition(r, params)
    source = source or {"path": str(paths[0]), "kind": "uff-frf" if meta.get("starts_at") else "measurement",
                        "sha256": sha}
    write_frf(outdir / "frf.h5", r, input_file=str(source["path"]), input_sha256=sha, overwrite=True)
    say("lsce")
    try:
        table = _modal_stage(r, opt, outdir)
    except DataFormatError as exc:  # (no stable mode: say which test)
        raise DataFormatError(f"{source['path']}: {exc}") from None
    ident, rep = _model_stages(table, params, rim_how, opt, source, outdir, say)
    summary = _summary(source, meta, rim_how, r, table, ident, rep, time.perf_counter() - t0)
    _write_manifest(outdir, list(OUTPUTS) + _input_inside(paths[0], outdir), source, sha, opt, nominal, params,
                    summary)
    return summary


def _input_inside(path: Path, outdir: Path) -> list[str]:
    """The input's name when it lies in the output folder (its checksum is then kept too)."""
    return [path.name] if path.parent.resolve() == outdir.resolve() else []


def _write_manifest(outdir: Path, names, source: dict, sha: str, opt: RunOptions, nominal: TyreParameters,
                    params: TyreParameters, summary: dict) -> None:
    """run.json, last: the input and source checksums, options, nominal parameters and the
    P0 and rim used, each output's checksum (``names``), the summary."""
    manifest = {"format": "tiremodal.run", "format_version": 1, **provenance(),
                "input_file": str(source["path"]), "input_sha256": sha, "source": source, "options": opt.to_dict(),
                "params": nominal.to_dict(), "model_P0": params.P0, "model_m_w": params.m_w,
                "outputs": {name: sha256_file(outdir / name) for name in names}, "summary": summary}
    write_text_atomic(outdir / MANIFEST, json_text(manifest), overwrite=True)


def is_modes_table(path) -> bool:
    """A CSV of measured modes (``*.csv``: frequency_hz, n, branch; the paper's Table A1 layout,
    or ``lsce --csv``): ``run`` starts at identify on it."""
    return Path(path).suffix.lower() == ".csv"


def _run_on_modes(path: Path, outdir: Path, opt: RunOptions, params: TyreParameters, source, say, t0) -> dict:
    """``run`` on a table of measured modes: identify and diagnose (and the paper's model
    comparison), the modes copied as modes.csv. The rim is the parameters' (no rim channel:
    clamped unless m_w is given), the pressure the parameters'; there are no point angles,
    so no aliasing check (every n as the table gives it)."""
    rows = read_modal_csv(path)
    sha = sha256_file(path)
    source = source or {"path": str(path), "kind": "modes-table", "sha256": sha}
    how = "clamped" if params.m_w is None else f"free, m_w = {params.m_w:g} kg"
    rim_how = f"{how}: from the parameters (the input is a table of modes, with no rim channel)"
    write_text_atomic(outdir / "modes.csv", path.read_text(encoding="utf-8"), overwrite=True)
    ident, rep = _model_stages(rows, params, rim_how, opt, source, outdir, say)
    meta = {"tire": None, "inflation_pressure": None, "n_points": None, "n_hits": None, "sample_rate": None,
            "starts_at": "identify"}
    summary = {"measurement": str(source["path"]), **meta, "rim": rim_how, "rejected_hits": [],
               "modes_found": len(rows), **_model_summary(ident, rep), "seconds": time.perf_counter() - t0}
    _write_manifest(outdir, list(MODES_OUTPUTS) + _input_inside(path, outdir), source, sha, opt, params, params,
                    summary)
    return summary


def _model_stages(table, params: TyreParameters, rim_how: str, opt: RunOptions, source: dict, outdir: Path, say):
    """identify and diagnose on the modal table, writing identify.json, diagnosis.json and
    sensitivity.json; returns identify.json's and diagnosis.json's content.

    One base fit per run: the robust fit of the modes that diagnose would make, made here
    and handed to it (identify.json, diagnosis.json, run.json and the report hold it)."""
    say("identify")
    fits = model_inputs(table, params, rim_how, opt, source)
    ident, n_pred = _identify_report(fits.base, fits.measured, params, opt)
    write_text_atomic(outdir / "identify.json", json_text(ident), overwrite=True)
    say("diagnose")
    diag = fits.diagnose()
    rep = report(diag, n_pred)
    write_text_atomic(outdir / "diagnosis.json", json_text(rep), overwrite=True)
    write_text_atomic(outdir / "sensitivity.json", json_text(_sensitivity(diag.augmented, n_pred)), overwrite=True)
    return ident, rep


@dataclass(frozen=True)
class ModelInputs:
    """What ``run`` diagnoses: the usable modes, the diagnosis options, the test's grid of
    points and the base fit, as :func:`model_inputs` makes them; :meth:`diagnose` is
    ``run``'s diagnosis of them."""
    measured: object
    params: TyreParameters
    dopt: DiagnoseOptions
    n_points: int | None
    base: object

    def diagnose(self):
        return diagnose(self.measured, self.params, self.dopt, n_points=self.n_points, base=self.base)


def model_inputs(table, params: TyreParameters, rim_how: str, opt: RunOptions, source: dict, *,
                 rows: list | None = None, search: str = "local") -> ModelInputs:
    """The usable modes and base fit of ``run``'s modal table (a ModalTable, or the rows of a
    table of modes), with ``run``'s options, rim (``rim_how``: :func:`rim_condition`'s
    sentence) and grid of points. ``rows``: the table's rows when they are not ``to_rows(table)``
    (a table read back from modal.h5 lacks the modal stage's frequency uncertainties; a
    benchmark passes modes.csv's); ``search``: DiagnoseOptions.search (``run``: "local")."""
    mix = None if isinstance(table, list) else (table.meta or {}).get("orders_mix")
    dopt = DiagnoseOptions(seed=opt.seed, noise_floor_pct=opt.noise_floor_pct, max_effects=opt.max_effects,
                           rim=rim_state(rim_how), search=search, orders_mix=mix["why"] if mix else None)
    if rows is None:
        rows = table if isinstance(table, list) else to_rows(table)
    what = "modes.csv" if isinstance(table, list) else "modal.h5"
    measured = usable_modes(rows, dopt, source=what, on_empty=lambda: no_usable_modes(
        f"{source['path']} (its modal table)", rows, modes_from_rows(rows)[1]))
    n_points = None if isinstance(table, list) else grid_points(table.point_angle)  # (a table of modes: no points)
    base = base_fit(measured.modes, params, dopt, n_points)
    return ModelInputs(measured, params, dopt, n_points, base)


def _frf_input(paths, opt: RunOptions, mapping, say):
    """The test's FRFs: read from UFF 58 files, or estimated from the measurement file.
    Returns (FRFResult, the test's facts, input checksum); the FRFs estimated here carry the
    force autospectrum (the default band's evidence), UFF ones do not."""
    if all(is_uff(p) for p in paths):
        say("read FRFs")
        r, meta = read_uff_test(paths, mapping)
        return r, meta, sha256_file(paths[0]) if len(paths) == 1 else files_sha256(paths)
    if len(paths) != 1:
        raise ParameterError("run takes one measurement file, or UFF files of FRFs")
    say("frf")
    r, meta = _frf_stage(paths[0], opt)
    return r, meta, sha256_file(paths[0])


def thread_budget() -> int:
    """Threads ``run`` may use: the size of the BLAS thread pool it is given (threadpoolctl;
    a batch job runs under a limit of one, so its tests run one thread each)."""
    n = [i["num_threads"] for i in threadpool_info() if i.get("user_api") == "blas"]
    return max(1, min(n)) if n else 1


def _modal_stage(r, opt: RunOptions, outdir: Path):
    """The modal table of the FRFs, written as modal.h5 and modes.csv (the poly-reference
    sweeps' model orders solved in :func:`thread_budget` threads: the same poles)."""
    mopt = ModalOptions(band_hz=None if opt.band is None else tuple(opt.band), workers=thread_budget(),
                        order_within_band=True)  # (run has no order option: short records lower it)
    table, _ = modal_table_from_frf(r, mopt)
    write_modal(outdir / "modal.h5", table, input_file="frf.h5",
                input_sha256=sha256_file(outdir / "frf.h5"), overwrite=True)
    write_text_atomic(outdir / "modes.csv", to_csv(table), overwrite=True)
    return table


def _identify_report(base, measured, params: TyreParameters, opt: RunOptions):
    """identify.json's content from the base fit, and the highest order predicted."""
    res = base.fit
    # predictions reach the highest measured order and two beyond ("the higher orders")
    n_pred = max([opt.predict_n] + [m["n"] + 2 for m in res.modes])
    ident = fit_report(res, list(measured.skipped), predict_table(res, n_pred, measured=res.modes))
    ident["set_aside"] = [a.to_dict() for a in base.set_aside]
    ident["outlier_rule"] = {"z_crit": base.z_crit, "scale": base.scale, "alpha": base.alpha,
                             "rule": "|z − median z| / max(1, 1.4826 MAD z) > Φ⁻¹(1 − α/2N), one mode at a time"}
    ident["model_comparison"] = _model_comparison(list(base.kept), params, res)
    return ident, n_pred


def _summary(source, meta, rim_how, r, table, ident, rep, seconds) -> dict:
    """The run's summary (run.json's ``summary``, and what ``run`` returns)."""
    return {
        "measurement": str(source["path"]), **meta, "rim": rim_how,
        "rejected_hits": [x.to_dict() for x in r.rejections],
        "modes_found": int(table.n_modes), "orders_mix": (table.meta or {}).get("orders_mix"),
        **_model_summary(ident, rep), "seconds": seconds,
    }


def _model_summary(ident: dict, rep: dict) -> dict:
    """The summary's fields of identify and diagnose."""
    return {"identified": ident["parameters"], "rms_error_pct": ident["rms_error_pct"],
            "set_aside_modes": ident["set_aside"],
            "adopted_effects": rep["adopted_effects"], "parameter_off": rep["parameter_off"],
            "rms_before_pct": rep["base"]["rms_error_pct"], "rms_after_pct": rep["augmented"]["rms_error_pct"],
            "augmented_parameters": rep["augmented"]["parameters"],
            "unexplained_modes": rep["unexplained_modes"], "verdict": rep["verdict"]}


def _frf_stage(measurement: Path, opt: RunOptions):
    """The FRF stage of a measurement file: FRFs (with the force autospectrum), the test's facts."""
    with open_measurement(measurement) as m:
        fs = float(m.sample_rate)
        if opt.band is not None and not opt.band[1] <= opt.frf_top * fs:
            raise ParameterError(f"band {opt.band[0]:g} … {opt.band[1]:g} Hz: allowed: HI ≤ {opt.frf_top * fs:g} Hz "
                                 f"(the FRFs' top, {opt.frf_top:g} × the sample rate; Nyquist {fs / 2:g} Hz)")
        try:
            r = compute_frf(m, FRFOptions(band_hz=(0.0, opt.frf_top * fs), exp_end=opt.exp_end, form=opt.form))
        except OSError as exc:
            raise DataFormatError(f"{measurement}: cannot read the records ({exc}); the file may be truncated") from None
        except DataFormatError as exc:  # (every hit rejected: say which test)
            raise DataFormatError(f"{measurement}: {exc}") from None
        meta = {"tire": getattr(m, "tire", None), "inflation_pressure": getattr(m, "inflation_pressure", None),
                "n_points": int(m.n_points), "n_hits": int(m.n_hits), "sample_rate": fs}
    return r, meta


def read_uff_test(paths, mapping=None):
    """A test given as UFF 58 FRFs (another system's): the FRFs in SI and the test's facts.

    The pipeline starts at lsce for such a test: there are no time records, so no hit
    checks, no window and no force spectrum (the lsce band is every line above 0 Hz unless
    ``band`` is given, or the file's coherence with a number of averages from the mapping).
    Point angles come from the mapping's ``[points]`` or the file's dataset 15; neither is
    an error. Tyre, pressure (Pa) and the number of averages from the mapping's optional
    ``[test]`` table (``tire``, ``inflation_pressure``, ``n_averages``).

    Returns
    -------
    r : FRFResult ; meta : dict (``starts_at`` = "lsce", ``frf_source``: units, factor, geometry)
    """
    chans, points = load_channel_map(mapping) if mapping else ({}, {})
    test = dict(load_mapping(mapping).get("test", {})) if mapping else {}
    r = read_frf_uff(paths, channels=chans, points=points, require_geometry=True)
    if "tread" not in r.channel_location:
        raise DataFormatError(f"{paths[0]}: no response is on the tread (channels "
                              f"{', '.join(f'{n}: {loc}' for n, loc in zip(r.channel_name, r.channel_location))}); "
                              "allowed: a mapping's [channels] with locations, response entity names "
                              "tread/sidewall/rim, or a dataset 15 node on the points' circle")
    n_avg = test.get("n_averages")
    if n_avg is not None:
        if isinstance(n_avg, bool) or not isinstance(n_avg, int) or n_avg < 1:
            raise ParameterError(f"{mapping} [test]: n_averages = {n_avg!r}; allowed: an integer ≥ 1")
        r = replace(r, n_averages=np.full(r.point_angle.size, n_avg))
    u = {k: v for k, v in r.meta["uff"].items() if k not in ("reference_nodes", "response_dofs", "files")}
    pressure = test.get("inflation_pressure")
    meta = {"tire": None if test.get("tire") is None else str(test["tire"]),
            "inflation_pressure": None if pressure is None else float(pressure),
            "n_points": int(r.point_angle.size), "n_hits": None, "sample_rate": None, "starts_at": "lsce",
            "frf_source": {"kind": "UFF 58 FRFs", "files": [str(p) for p in paths], **u,
                           "mapping": None if mapping is None else str(mapping),
                           "options_not_used": "frf_top, exp_end and form: the FRFs are the file's, in its "
                                               "form, with whatever window it applied (no time records)"}}
    return r, meta


def _model_comparison(modes, params: TyreParameters, res) -> dict:
    """The paper's comparison on this test's modes: the coupled model's errors by branch and
    band beside the classical flexible-tread model's (:mod:`tiremodal_cli.tyre.flexible_tread`)."""
    out = {"coupled": {"rms_error_pct": res.rms_error_pct, "by_branch": errors_by_branch(res.modes)}}
    try:
        out["flexible_tread"] = fit_flexible_tread(modes, params).to_dict()
    except DataFormatError as exc:
        out["flexible_tread"] = {"skipped": str(exc)}
    return out


def _sensitivity(res, n_max: int) -> dict:
    """Normalised sensitivities ∂ln f/∂ln p of the final model (its effects included) at its
    identified parameters, for the paper's parameters and n = 1 … n_max."""
    ns, br, S = coefficients(res.parameters, PAPER_STUDY, n_max, res.effects or None)
    # a coefficient that cannot be computed is an explicit null with its reason, never NaN
    nulls = [{"n": int(ns[i]), "branch": str(br[i]), "parameter": k,
              "reason": "not finite at the final model's parameters (no such mode of the model there)"}
             for i in range(len(ns)) for j, k in enumerate(PAPER_STUDY) if not np.isfinite(S[i, j])]
    return {"parameters": res.parameters.to_dict(), "effects": res.effects, "names": list(PAPER_STUDY),
            "coefficients": [{"n": int(n), "branch": str(b),
                              **{k: float(S[i, j]) if np.isfinite(S[i, j]) else None for j, k in enumerate(PAPER_STUDY)}}
                             for i, (n, b) in enumerate(zip(ns, br))],
            "nulls": nulls}
