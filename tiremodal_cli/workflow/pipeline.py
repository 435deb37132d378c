"""``run``: every stage in a row — frf → lsce → identify → diagnose — into one folder.

Each stage's output is written atomically into the output folder as it completes
(``frf.h5``, ``modal.h5``, ``modes.csv``, ``identify.json``, ``diagnosis.json``,
``sensitivity.json``: ∂ln f/∂ln p of the final model at its parameters); the
manifest ``run.json`` (the input's checksum, the options, each output's checksum, the
summary) is written last, so a folder with a manifest whose checksums match is complete
and a folder without one is not.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from tiremodal_cli import __version__
from tiremodal_cli.diagnose.loop import DiagnoseOptions, base_fit, diagnose, report, usable_modes
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.io.files import _UMASK, dumps, install_dir, path_lock, refuse_input_as_output, sha256_file, write_text_atomic
from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.io.frffile import is_uff, read_frf_uff, write_frf
from tiremodal_cli.tyre.measured import modes_from_rows
from tiremodal_cli.tyre.predict import fit_report, predict_table
from tiremodal_cli.io.modalfile import no_usable_modes
from tiremodal_cli.io.measurement import open_measurement
from tiremodal_cli.io.modalfile import to_csv, to_rows, write_modal
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.modal.modes import ModalOptions, modal_table_from_frf
from tiremodal_cli.tyre.sensitivity import PAPER_STUDY, coefficients

__all__ = ["RunOptions", "run", "run_folder", "is_complete", "read_manifest", "verify_manifest", "OUTPUTS",
           "MANIFEST"]

OUTPUTS = ("frf.h5", "modal.h5", "modes.csv", "identify.json", "diagnosis.json", "sensitivity.json")
MANIFEST = "run.json"


@dataclass(frozen=True)
class RunOptions:
    """Defaults of every stage (fractions of the sample rate fs where marked).

    frf_top : FRFs up to frf_top × fs (1/2.56 = 0.390625: an analyser's usable bandwidth under its
        anti-alias filter; the lsce band then ends where the coherence and force fail)
    band : lsce band (Hz); default: where the coherence and the force spectrum support the
        estimate (:func:`tiremodal_cli.modal.modes.default_band`, its reason in the modal file)
    exp_end : exponential window's value at the record's end (its damping is corrected)
    predict_n : predictions (and sensitivities) reach at least this order, and always two
        beyond the highest measured one
    seed : seed of every evolutionary search
    pressure_from_file : the model's inflation pressure P0 is the one the measurement
        records (when it records one), not the nominal parameters' — a campaign over
        pressures is then fitted at each test's own pressure
    form : FRF form the modal stage works on: "accelerance" (what accelerometers give),
        "mobility" or "receptance" — the modes should not depend on it
    """

    frf_top: float = 1 / 2.56
    band: tuple[float, float] | None = None
    exp_end: float | None = 0.05
    seed: int = 0
    noise_floor_pct: float = 0.1
    max_effects: int = 2
    predict_n: int = 12
    pressure_from_file: bool = True
    form: str = "accelerance"

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_mapping(cls, d: dict, where: str = "options") -> "RunOptions":
        """RunOptions from a config table (``[run]`` of a campaign file); ``exp_end = false``
        means no exponential window. Unknown keys and bad values raise ParameterError."""
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(d) - set(names))
        if unknown:
            raise ParameterError(f"{where}: unknown option {unknown[0]!r}; allowed: {', '.join(names)}")
        kw = dict(d)

        def bad(k, allowed):
            return ParameterError(f"{where}: {k} = {d[k]!r} is not allowed; allowed: {allowed}")

        def number(k, ok, allowed):
            v = kw[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not ok(v):
                raise bad(k, allowed)
            return float(v)

        if kw.get("band") is not None:
            v = kw["band"]
            if (not isinstance(v, (list, tuple)) or len(v) != 2
                    or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) for x in v)
                    or not 0 <= v[0] < v[1]):
                raise bad("band", "[LO, HI] in Hz (band needs 0 ≤ LO < HI)")
            kw["band"] = (float(v[0]), float(v[1]))
        if "exp_end" in kw:
            if kw["exp_end"] is False or kw["exp_end"] is None:
                kw["exp_end"] = None
            else:
                kw["exp_end"] = number("exp_end", lambda x: 0 < x < 1, "a number in (0, 1), or false for no window")
        if "frf_top" in kw:
            kw["frf_top"] = number("frf_top", lambda x: 0 < x <= 0.5, "a fraction of the sample rate in (0, 0.5]")
        if "noise_floor_pct" in kw:
            kw["noise_floor_pct"] = number("noise_floor_pct", lambda x: 0 < x <= 100, "a percentage in (0, 100]")
        if "form" in kw and kw["form"] not in ("accelerance", "mobility", "receptance"):
            raise bad("form", "accelerance, mobility, receptance")
        if "pressure_from_file" in kw and not isinstance(kw["pressure_from_file"], bool):
            raise bad("pressure_from_file", "true or false")
        for k, lo, hi in (("seed", None, None), ("max_effects", 0, 5), ("predict_n", 1, 100)):
            if k in kw:
                v = kw[k]
                if (isinstance(v, bool) or not isinstance(v, int) or (lo is not None and not lo <= v <= hi)):
                    raise bad(k, "an integer" + (f" in {lo}…{hi}" if lo is not None else ""))
        return cls(**kw)


def _json(obj) -> str:
    return dumps(obj)


#: Rim (plus hub and fixture) mass assumed when a rim channel shows the rim moving and the
#: nominal parameters give none, kg. The paper gives none; ``diagnose`` tests m_w as a
#: parameter that may be off, so this is a starting value, not a result.
NOMINAL_RIM_KG = 1000.0


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
    measurement = paths[0]
    params = params or TyreParameters()
    say = progress or (lambda stage: None)
    if all(is_uff(p) for p in paths):
        say("read FRFs")
        r, meta = read_uff_test(paths, mapping)
        force_g = None
        sha = sha256_file(measurement) if len(paths) == 1 else files_sha256(paths)
    else:
        if len(paths) != 1:
            raise ParameterError("run takes one measurement file, or UFF files of FRFs")
        say("frf")
        r, force_g, meta = _frf_stage(measurement, opt)
        sha = sha256_file(measurement)
    nominal = params
    if opt.pressure_from_file and meta["inflation_pressure"] is not None and float(meta["inflation_pressure"]) > 0:
        params = params.replace(P0=float(meta["inflation_pressure"]))
    params, rim_how = rim_condition(r, params)
    source = source or {"path": str(measurement), "kind": "uff-frf" if meta.get("starts_at") else "measurement",
                        "sha256": sha}
    write_frf(outdir / "frf.h5", r, input_file=str(source["path"]), input_sha256=sha, overwrite=True)
    say("lsce")
    table, _ = modal_table_from_frf(r, ModalOptions(band_hz=None if opt.band is None else tuple(opt.band)),
                                    force_autospectrum=force_g)
    write_modal(outdir / "modal.h5", table, input_file="frf.h5",
                input_sha256=sha256_file(outdir / "frf.h5"), overwrite=True)
    write_text_atomic(outdir / "modes.csv", to_csv(table), overwrite=True)
    rows = to_rows(table)
    say("identify")
    # one base fit per run: the robust fit of the modes that diagnose would make, made here
    # and handed to it (identify.json, diagnosis.json, run.json and the report hold it)
    dopt = DiagnoseOptions(seed=opt.seed, noise_floor_pct=opt.noise_floor_pct, max_effects=opt.max_effects,
                           rim=rim_state(rim_how))
    measured = usable_modes(rows, dopt, source="modal.h5", on_empty=lambda: no_usable_modes(
        f"{source['path']} (its modal table)", rows, modes_from_rows(rows)[1]))
    base = base_fit(measured.modes, params, dopt)
    res = base.fit
    # predictions reach the highest measured order and two beyond ("the higher orders")
    n_pred = max([opt.predict_n] + [m["n"] + 2 for m in res.modes])
    ident = fit_report(res, list(measured.skipped), predict_table(res, n_pred, measured=res.modes))
    ident["set_aside"] = [a.to_dict() for a in base.set_aside]
    ident["outlier_rule"] = {"z_crit": base.z_crit, "scale": base.scale, "alpha": base.alpha,
                             "rule": "|z − median z| / max(1, 1.4826 MAD z) > Φ⁻¹(1 − α/2N), one mode at a time"}
    ident["model_comparison"] = _model_comparison(list(base.kept), params, res)
    write_text_atomic(outdir / "identify.json", _json(ident), overwrite=True)
    say("diagnose")
    diag = diagnose(measured, params, dopt, n_points=int(table.point_angle.size), base=base)
    rep = report(diag, n_pred)
    write_text_atomic(outdir / "diagnosis.json", _json(rep), overwrite=True)
    write_text_atomic(outdir / "sensitivity.json", _json(_sensitivity(diag.augmented, n_pred)), overwrite=True)
    summary = {
        "measurement": str(source["path"]), **meta, "rim": rim_how,
        "rejected_hits": [x.to_dict() for x in r.rejections],
        "modes_found": int(table.n_modes),
        "identified": ident["parameters"], "rms_error_pct": ident["rms_error_pct"],
        "set_aside_modes": ident["set_aside"],
        "adopted_effects": rep["adopted_effects"], "parameter_off": rep["parameter_off"],
        "rms_before_pct": rep["base"]["rms_error_pct"], "rms_after_pct": rep["augmented"]["rms_error_pct"],
        "augmented_parameters": rep["augmented"]["parameters"],
        "unexplained_modes": rep["unexplained_modes"], "verdict": rep["verdict"],
        "seconds": time.perf_counter() - t0,
    }
    names = list(OUTPUTS) + ([measurement.name] if measurement.parent.resolve() == outdir.resolve() else [])
    manifest = {"format": "tiremodal.run", "format_version": 1, **provenance(),
                "input_file": str(source["path"]), "input_sha256": sha, "source": source, "options": opt.to_dict(),
                "params": nominal.to_dict(), "model_P0": params.P0, "model_m_w": params.m_w,
                "outputs": {name: sha256_file(outdir / name) for name in names}, "summary": summary}
    write_text_atomic(outdir / MANIFEST, _json(manifest), overwrite=True)
    return summary


#: views of a run folder that ``report`` writes; a new run does not carry them over (stale)
_VIEWS = ("report.html", "figures")


def _link_or_copy(src: str, dst: str) -> None:
    import shutil

    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def run_folder(measurement, outdir, opt: RunOptions = RunOptions(), *, params: TyreParameters | None = None,
               progress=None, overwrite: bool = False, mapping=None) -> dict:
    """:func:`run` made atomic: the outputs are written into a private folder beside
    ``outdir`` (``.NAME.partial.*``) and the folder is installed whole
    (:func:`~tiremodal_cli.io.files.install_dir`), under a lock (``.NAME.lock`` beside it).

    At every instant ``outdir`` is the complete old folder, absent, or the complete new one:
    an error or a kill leaves at most debris under ``.NAME.partial.*``/``.NAME.old.*``,
    removed by the next run into ``outdir``. Files of the old folder that are not run
    outputs (the measurement itself when it lies there, notes) are carried into the new
    one (hard links where possible); the report's views (report.html, figures/) are not.
    ``measurement`` may be a UFF file of FRFs (with an optional ``mapping``: see :func:`run`).

    Parameters
    ----------
    measurement, outdir, opt, params, progress, mapping : as for :func:`run`
    overwrite : bool
        Replace the outputs of an earlier run in ``outdir``.

    Returns
    -------
    dict
        The summary, as :func:`run`.

    Raises
    ------
    OutputExistsError : outputs exist in ``outdir`` and ``overwrite`` is false
    ParameterError : ``outdir`` is the measurement, or is a file, or another run holds its lock
    """
    import shutil
    import tempfile

    from tiremodal_cli.errors import OutputExistsError

    measurement, outdir = Path(measurement), Path(outdir)
    refuse_input_as_output({"--output": outdir}, {"measurement": measurement,
                                                  **({"--mapping": Path(mapping)} if mapping else {})})
    if outdir.exists() and not outdir.is_dir():
        raise ParameterError(f"--output {str(outdir)!r} exists and is not a folder")
    if not measurement.is_file():
        raise DataFormatError(f"{measurement}: no such file")
    parent = outdir.parent
    parent.mkdir(parents=True, exist_ok=True)
    with path_lock(parent / f".{outdir.name}.lock", f"--output {str(outdir)!r}"):
        existing = [n for n in (*OUTPUTS, MANIFEST) if (outdir / n).exists()]
        if existing and not overwrite:
            raise OutputExistsError(f"output {str(outdir / existing[0])!r} exists; pass --overwrite to replace it")
        for debris in [*parent.glob(f".{outdir.name}.partial.*"), *parent.glob(f".{outdir.name}.old.*")]:
            shutil.rmtree(debris, ignore_errors=True)  # of a killed run (we hold the lock)
        tmp = Path(tempfile.mkdtemp(prefix=f".{outdir.name}.partial.", dir=parent))
        os.chmod(tmp, 0o777 & ~_UMASK)
        try:
            meas = measurement
            if outdir.is_dir():
                for entry in outdir.iterdir():
                    if entry.name in (*OUTPUTS, MANIFEST, *_VIEWS):
                        continue
                    if entry.is_dir() and not entry.is_symlink():
                        shutil.copytree(entry, tmp / entry.name, symlinks=True, copy_function=_link_or_copy)
                    else:
                        _link_or_copy(str(entry), str(tmp / entry.name))
                if measurement.resolve().parent == outdir.resolve():
                    meas = tmp / measurement.name
            sha = sha256_file(measurement)
            kind = "uff-frf" if is_uff(measurement) else "measurement"
            summary = run(meas, tmp, opt, params=params, progress=progress, mapping=mapping,
                          source={"path": str(measurement), "kind": kind, "sha256": sha})
            install_dir(tmp, outdir, aside=parent)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    return summary


def verify_manifest(folder, man: dict | None = None) -> dict:
    """The manifest of a run folder after checking every output it lists against its checksum.

    Raises
    ------
    DataFormatError
        No manifest, a manifest that does not parse, or an output missing or changed
        (named, with the expected and the found checksum).
    """
    folder = Path(folder)
    man = read_manifest(folder) if man is None else man
    if man is None:
        raise DataFormatError(f"{folder}: no readable run manifest ({MANIFEST}); run 'tiremodal run' first")
    outs = man.get("outputs") if isinstance(man, dict) else None
    if not isinstance(outs, dict) or not set(OUTPUTS) <= set(outs):
        raise DataFormatError(f"{folder / MANIFEST}: lists no checksums of {', '.join(OUTPUTS)}; "
                              "not a complete run folder")
    for name, h in outs.items():
        p = folder / name
        if not p.is_file():
            raise DataFormatError(f"{p}: missing; the folder does not match its manifest ({MANIFEST})")
        got = sha256_file(p)
        if got != h:
            raise DataFormatError(f"{p}: SHA-256 {got[:12]}… differs from the manifest's {str(h)[:12]}…; "
                                  f"the folder does not match {MANIFEST} (mixed or changed outputs)")
    return man


def _force_autospectrum(m, freq_hz):
    """Mean |F|² of every hit's force record on the FRF lines ``freq_hz`` (one point at a
    time: memory of one point's records)."""
    fs, ns = float(m.sample_rate), int(m.n_samples)
    k = np.round(np.asarray(freq_hz) * ns / fs).astype(int)
    acc = np.zeros(k.size)
    for ip in range(m.n_points):
        f = np.asarray(m.force[ip], dtype=float)
        f = np.where(np.isfinite(f), f, 0.0)
        acc += np.sum(np.abs(np.fft.rfft(f, axis=-1)[..., k]) ** 2, axis=0)
    return acc


def provenance() -> dict:
    """When and with what a result is made: UTC time, tiremodal's version and git commit (of
    the checkout the package runs from; absent when it is not one, e.g. an installed wheel),
    and the command line (``tiremodal …`` as typed)."""
    import datetime
    import shlex
    import subprocess
    import sys

    out = {"created_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
           "tiremodal_version": __version__}
    global _COMMIT
    if _COMMIT is None:
        _COMMIT = ""
        try:
            here = Path(__file__).resolve().parent
            rev = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True,
                                 timeout=5)
            # the package's own files must be tracked there: an installed copy inside some
            # other repository's tree (a virtualenv in a project) is not that commit
            tracked = subprocess.run(["git", "-C", str(here), "ls-files", "--error-unmatch", "pipeline.py"],
                                     capture_output=True, text=True, timeout=5)
            if rev.returncode == 0 and tracked.returncode == 0:
                dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
                                       capture_output=True, text=True, timeout=5)
                _COMMIT = rev.stdout.strip()[:12] + ("+changes" if dirty.stdout.strip() else "")
        except (OSError, subprocess.SubprocessError):
            pass
    if _COMMIT:
        out["tiremodal_commit"] = _COMMIT
    argv = list(sys.argv)
    prog = Path(argv[0]).name if argv else "tiremodal"
    out["command"] = shlex.join(["tiremodal" if prog in ("tiremodal", "__main__.py") else prog] + argv[1:])
    return out


_COMMIT: str | None = None


def _frf_stage(measurement: Path, opt: RunOptions):
    """The FRF stage of a measurement file: FRFs, the force autospectrum, the test's facts."""
    with open_measurement(measurement) as m:
        fs = float(m.sample_rate)
        if opt.band is not None and not opt.band[1] <= opt.frf_top * fs:
            raise ParameterError(f"band {opt.band[0]:g} … {opt.band[1]:g} Hz: allowed: HI ≤ {opt.frf_top * fs:g} Hz "
                                 f"(the FRFs' top, {opt.frf_top:g} × the sample rate; Nyquist {fs / 2:g} Hz)")
        try:
            r = compute_frf(m, FRFOptions(band_hz=(0.0, opt.frf_top * fs), exp_end=opt.exp_end, form=opt.form))
        except OSError as exc:
            raise DataFormatError(f"{measurement}: cannot read the records ({exc}); the file may be truncated") from None
        force_g = _force_autospectrum(m, r.freq_hz)
        meta = {"tire": getattr(m, "tire", None), "inflation_pressure": getattr(m, "inflation_pressure", None),
                "n_points": int(m.n_points), "n_hits": int(m.n_hits), "sample_rate": fs}
    return r, force_g, meta


def files_sha256(paths) -> str:
    """SHA-256 of several files: of their names and checksums, sorted (any change counts)."""
    import hashlib

    h = hashlib.sha256()
    for p in sorted(Path(q) for q in paths):
        h.update(f"{p.name}\0{sha256_file(p)}\n".encode())
    return h.hexdigest()


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
    from dataclasses import replace

    from tiremodal_cli.io.config import load_mapping
    from tiremodal_cli.io.ingest import load_channel_map

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
    from tiremodal_cli.tyre.flexible_tread import errors_by_branch, fit_flexible_tread

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


def read_manifest(outdir) -> dict | None:
    """The manifest of a run folder, or None when there is none or it does not parse."""
    try:
        return json.loads((Path(outdir) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def is_complete(outdir, measurement=None, opt: RunOptions | None = None, *, input_sha256: str | None = None,
                params: TyreParameters | None = None) -> bool:
    """True when ``outdir`` holds a manifest whose outputs (all of :data:`OUTPUTS`) exist with
    their checksums and, where given, whose input checksum (of ``measurement``, or
    ``input_sha256``), options and nominal parameters match."""
    outdir = Path(outdir)
    man = read_manifest(outdir)
    try:
        if man is None or not set(OUTPUTS) <= set(man["outputs"]):
            return False
        if any(sha256_file(outdir / n) != h for n, h in man["outputs"].items()):
            return False
        if measurement is not None and input_sha256 is None:
            input_sha256 = sha256_file(measurement)
        if input_sha256 is not None and input_sha256 not in (man["input_sha256"], man.get("source", {}).get("sha256")):
            return False
        if opt is not None and man["options"] != json.loads(_json(opt.to_dict())):
            return False
        if params is not None and man["params"] != json.loads(_json(params.to_dict())):
            return False
        return True
    except (OSError, ValueError, KeyError, TypeError):
        return False
