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
import time
from dataclasses import asdict, dataclass, fields
from pathlib import Path

from . import __version__
from .diagnose import DiagnoseOptions, diagnose, report
from .errors import DataFormatError, ParameterError
from .files import dumps, sha256_file, write_text_atomic
from .frf import FRFOptions, compute_frf
from .frffile import write_frf
from .identify import FitOptions, fit, fit_report, modes_from_rows, predict_table
from .measurement import open_measurement
from .modalfile import to_csv, to_rows, write_modal
from .model import TyreParameters
from .modes import ModalOptions, modal_table_from_frf
from .sensitivity import PAPER_STUDY, coefficients

__all__ = ["RunOptions", "run", "is_complete", "read_manifest", "OUTPUTS", "MANIFEST"]

OUTPUTS = ("frf.h5", "modal.h5", "modes.csv", "identify.json", "diagnosis.json", "sensitivity.json")
MANIFEST = "run.json"


@dataclass(frozen=True)
class RunOptions:
    """Defaults of every stage (fractions of the sample rate fs where marked).

    frf_top : FRFs up to frf_top × fs (0.3125: inside a front end's anti-alias corner at 0.4 fs)
    band : lsce band (Hz); default (0.04 fs, 0.293 fs): above the rim and rigid-body region,
        below the FRF band's top
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

    frf_top: float = 0.3125
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
        try:
            if kw.get("band") is not None:
                lo, hi = (float(x) for x in kw["band"])
                if not 0 <= lo < hi:
                    raise ValueError("band needs 0 ≤ LO < HI")
                kw["band"] = (lo, hi)
            if "exp_end" in kw:
                v = kw["exp_end"]
                kw["exp_end"] = None if v is False or v is None else float(v)
                if kw["exp_end"] is not None and not 0 < kw["exp_end"] < 1:
                    raise ValueError("exp_end must be in (0, 1), or false for no window")
            for k in ("frf_top", "noise_floor_pct"):
                if k in kw:
                    kw[k] = float(kw[k])
                    if kw[k] <= 0:
                        raise ValueError(f"{k} must be > 0")
            if "frf_top" in kw and kw["frf_top"] > 0.5:
                raise ValueError("frf_top must be ≤ 0.5 (a fraction of the sample rate)")
            if kw.get("form", "accelerance") not in ("accelerance", "mobility", "receptance"):
                raise ValueError(f"form={kw['form']!r}; allowed: accelerance, mobility, receptance")
            if "pressure_from_file" in kw and not isinstance(kw["pressure_from_file"], bool):
                raise ValueError("pressure_from_file must be true or false")
            for k in ("seed", "max_effects", "predict_n"):
                if k in kw:
                    if isinstance(kw[k], bool) or int(kw[k]) != kw[k]:
                        raise ValueError(f"{k} must be an integer")
                    kw[k] = int(kw[k])
            if not 0 <= kw.get("max_effects", 0) <= 5:
                raise ValueError("max_effects must be in 0…5")
            if not 1 <= kw.get("predict_n", 1) <= 100:
                raise ValueError("predict_n must be in 1…100")
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"{where}: {exc}") from None
        return cls(**kw)


def _json(obj) -> str:
    return dumps(obj)


def run(measurement, outdir, opt: RunOptions = RunOptions(), *, params: TyreParameters | None = None,
        progress=None, source: dict | None = None) -> dict:
    """Run the whole pipeline on one measurement file; return the summary.

    Parameters
    ----------
    measurement : path of a measurement file (docs/format.md)
    outdir : folder for the outputs (created; existing outputs are replaced)
    opt : RunOptions
    params : nominal model parameters (default: the paper's, with a 1,000 kg rim + fixture);
        P0 is replaced by the measurement's pressure (see RunOptions.pressure_from_file)
    progress : callable(stage: str) called as each stage starts, optional
    source : {"path", "kind", "sha256"} of what the measurement came from when it was
        ingested from a UFF/CSV folder (default: the measurement file itself); recorded in
        the manifest, whose ``source.sha256`` is what a batch compares to skip a done test.

    Files inside ``outdir`` refer to each other by name (the folder can be moved).
    """
    t0 = time.perf_counter()
    measurement, outdir = Path(measurement), Path(outdir)
    params = params or TyreParameters(m_w=1000.0)
    say = progress or (lambda stage: None)
    say("frf")
    with open_measurement(measurement) as m:
        fs = float(m.sample_rate)
        try:
            r = compute_frf(m, FRFOptions(band_hz=(0.0, opt.frf_top * fs), exp_end=opt.exp_end, form=opt.form))
        except OSError as exc:
            raise DataFormatError(f"{measurement}: cannot read the records ({exc}); the file may be truncated") from None
        meta = {"tire": getattr(m, "tire", None), "inflation_pressure": getattr(m, "inflation_pressure", None),
                "n_points": int(m.n_points), "n_hits": int(m.n_hits), "sample_rate": fs}
    nominal = params
    if opt.pressure_from_file and meta["inflation_pressure"] is not None and float(meta["inflation_pressure"]) > 0:
        params = params.replace(P0=float(meta["inflation_pressure"]))
    sha = sha256_file(measurement)
    source = source or {"path": str(measurement), "kind": "measurement", "sha256": sha}
    write_frf(outdir / "frf.h5", r, input_file=str(source["path"]), input_sha256=sha, overwrite=True)
    say("lsce")
    band = opt.band or (0.04 * fs, 0.293 * fs)
    table, _ = modal_table_from_frf(r, ModalOptions(band_hz=tuple(band)))
    write_modal(outdir / "modal.h5", table, input_file="frf.h5",
                input_sha256=sha256_file(outdir / "frf.h5"), overwrite=True)
    write_text_atomic(outdir / "modes.csv", to_csv(table), overwrite=True)
    rows = to_rows(table)
    say("identify")
    modes, skipped = modes_from_rows(rows, source="modal.h5")
    res = fit(modes, params, FitOptions(seed=opt.seed))
    # predictions reach the highest measured order and two beyond ("the higher orders")
    n_pred = max([opt.predict_n] + [m["n"] + 2 for m in res.modes])
    ident = fit_report(res, skipped, predict_table(res, n_pred, measured=res.modes))
    write_text_atomic(outdir / "identify.json", _json(ident), overwrite=True)
    say("diagnose")
    diag = diagnose(rows, params, DiagnoseOptions(seed=opt.seed, noise_floor_pct=opt.noise_floor_pct,
                                                  max_effects=opt.max_effects), n_points=int(table.point_angle.size))
    rep = report(diag, n_pred)
    write_text_atomic(outdir / "diagnosis.json", _json(rep), overwrite=True)
    write_text_atomic(outdir / "sensitivity.json", _json(_sensitivity(diag.augmented, n_pred)), overwrite=True)
    summary = {
        "measurement": str(source["path"]), **meta,
        "rejected_hits": [x.to_dict() for x in r.rejections],
        "modes_found": int(table.n_modes),
        "identified": ident["parameters"], "rms_error_pct": ident["rms_error_pct"],
        "adopted_effects": rep["adopted_effects"], "parameter_off": rep["parameter_off"],
        "rms_before_pct": rep["base"]["rms_error_pct"], "rms_after_pct": rep["augmented"]["rms_error_pct"],
        "augmented_parameters": rep["augmented"]["parameters"],
        "unexplained_modes": rep["unexplained_modes"], "verdict": rep["verdict"],
        "seconds": time.perf_counter() - t0,
    }
    names = list(OUTPUTS) + ([measurement.name] if measurement.parent.resolve() == outdir.resolve() else [])
    manifest = {"format": "tiremodal.run", "format_version": 1, "tiremodal_version": __version__,
                "input_file": str(source["path"]), "input_sha256": sha, "source": source, "options": opt.to_dict(),
                "params": nominal.to_dict(), "model_P0": params.P0,
                "outputs": {name: sha256_file(outdir / name) for name in names}, "summary": summary}
    write_text_atomic(outdir / MANIFEST, _json(manifest), overwrite=True)
    return summary


def _sensitivity(res, n_max: int) -> dict:
    """Normalised sensitivities ∂ln f/∂ln p of the final model (its effects included) at its
    identified parameters, for the paper's parameters and n = 1 … n_max."""
    ns, br, S = coefficients(res.parameters, PAPER_STUDY, n_max, res.effects or None)
    return {"parameters": res.parameters.to_dict(), "effects": res.effects, "names": list(PAPER_STUDY),
            "coefficients": [{"n": int(n), "branch": str(b), **{k: float(S[i, j]) for j, k in enumerate(PAPER_STUDY)}}
                             for i, (n, b) in enumerate(zip(ns, br))]}


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
