"""``run``: every stage in a row — frf → lsce → identify → diagnose — into one folder.

Each stage's output is written atomically into the output folder as it completes
(``frf.h5``, ``modal.h5``, ``modes.csv``, ``identify.json``, ``diagnosis.json``); the
manifest ``run.json`` (the input's checksum, the options, each output's checksum, the
summary) is written last, so a folder with a manifest whose checksums match is complete
and a folder without one is not.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

from . import __version__
from .diagnose import DiagnoseOptions, diagnose, report
from .errors import DataFormatError
from .files import sha256_file, write_text_atomic
from .frf import FRFOptions, compute_frf
from .frffile import write_frf
from .identify import FitOptions, fit, fit_report, modes_from_rows, predict_table
from .measurement import open_measurement
from .modalfile import to_csv, to_rows, write_modal
from .model import TyreParameters
from .modes import ModalOptions, modal_table_from_frf

__all__ = ["RunOptions", "run", "OUTPUTS", "MANIFEST"]

OUTPUTS = ("frf.h5", "modal.h5", "modes.csv", "identify.json", "diagnosis.json")
MANIFEST = "run.json"


@dataclass(frozen=True)
class RunOptions:
    """Defaults of every stage (fractions of the sample rate fs where marked).

    frf_top : FRFs up to frf_top × fs (0.3125: inside a front end's anti-alias corner at 0.4 fs)
    band : lsce band (Hz); default (0.04 fs, 0.293 fs): above the rim and rigid-body region,
        below the FRF band's top
    exp_end : exponential window's value at the record's end (its damping is corrected)
    seed : seed of every evolutionary search
    """

    frf_top: float = 0.3125
    band: tuple[float, float] | None = None
    exp_end: float | None = 0.05
    seed: int = 0
    noise_floor_pct: float = 0.1
    max_effects: int = 2
    predict_n: int = 12

    def to_dict(self) -> dict:
        return asdict(self)


def _json(obj) -> str:
    from .cli.options import dumps  # one JSON encoder for numpy values

    return dumps(obj)


def run(measurement, outdir, opt: RunOptions = RunOptions(), *, params: TyreParameters | None = None,
        progress=None) -> dict:
    """Run the whole pipeline on one measurement file; return the summary.

    Parameters
    ----------
    measurement : path of a measurement file (docs/format.md)
    outdir : folder for the outputs (created; existing outputs are replaced)
    opt : RunOptions
    params : nominal model parameters (default: the paper's, with a 1,000 kg rim + fixture)
    progress : callable(stage: str) called as each stage starts, optional
    """
    measurement, outdir = Path(measurement), Path(outdir)
    params = params or TyreParameters(m_w=1000.0)
    say = progress or (lambda stage: None)
    say("frf")
    with open_measurement(measurement) as m:
        fs = float(m.sample_rate)
        try:
            r = compute_frf(m, FRFOptions(band_hz=(0.0, opt.frf_top * fs), exp_end=opt.exp_end))
        except OSError as exc:
            raise DataFormatError(f"{measurement}: cannot read the records ({exc}); the file may be truncated") from None
        meta = {"tire": getattr(m, "tire", None), "inflation_pressure": getattr(m, "inflation_pressure", None),
                "n_points": int(m.n_points), "n_hits": int(m.n_hits), "sample_rate": fs}
    sha = sha256_file(measurement)
    write_frf(outdir / "frf.h5", r, input_file=str(measurement), input_sha256=sha, overwrite=True)
    say("lsce")
    band = opt.band or (0.04 * fs, 0.293 * fs)
    table, _ = modal_table_from_frf(r, ModalOptions(band_hz=tuple(band)))
    write_modal(outdir / "modal.h5", table, input_file=str(outdir / "frf.h5"),
                input_sha256=sha256_file(outdir / "frf.h5"), overwrite=True)
    write_text_atomic(outdir / "modes.csv", to_csv(table), overwrite=True)
    rows = to_rows(table)
    say("identify")
    modes, skipped = modes_from_rows(rows, source="modal.h5")
    res = fit(modes, params, FitOptions(seed=opt.seed))
    ident = fit_report(res, skipped, predict_table(res, opt.predict_n, measured=res.modes))
    write_text_atomic(outdir / "identify.json", _json(ident), overwrite=True)
    say("diagnose")
    diag = diagnose(rows, params, DiagnoseOptions(seed=opt.seed, noise_floor_pct=opt.noise_floor_pct,
                                                  max_effects=opt.max_effects), n_points=int(table.point_angle.size))
    rep = report(diag, opt.predict_n)
    write_text_atomic(outdir / "diagnosis.json", _json(rep), overwrite=True)
    summary = {
        "measurement": str(measurement), **meta,
        "rejected_hits": [x.to_dict() for x in r.rejections],
        "modes_found": int(table.n_modes),
        "identified": ident["parameters"], "rms_error_pct": ident["rms_error_pct"],
        "adopted_effects": rep["adopted_effects"], "parameter_off": rep["parameter_off"],
        "rms_before_pct": rep["base"]["rms_error_pct"], "rms_after_pct": rep["augmented"]["rms_error_pct"],
        "augmented_parameters": rep["augmented"]["parameters"],
        "unexplained_modes": rep["unexplained_modes"], "verdict": rep["verdict"],
    }
    manifest = {"format": "tiremodal.run", "format_version": 1, "tiremodal_version": __version__,
                "input_file": str(measurement), "input_sha256": sha, "options": opt.to_dict(),
                "params": params.to_dict(),
                "outputs": {name: sha256_file(outdir / name) for name in OUTPUTS}, "summary": summary}
    write_text_atomic(outdir / MANIFEST, _json(manifest), overwrite=True)
    return summary


def is_complete(outdir, measurement=None, opt: RunOptions | None = None) -> bool:
    """True when ``outdir`` holds a manifest whose outputs exist with their checksums (and,
    if given, whose input checksum and options match)."""
    outdir = Path(outdir)
    try:
        man = json.loads((outdir / MANIFEST).read_text(encoding="utf-8"))
        if any(sha256_file(outdir / n) != h for n, h in man["outputs"].items()):
            return False
        if measurement is not None and man["input_sha256"] != sha256_file(measurement):
            return False
        if opt is not None and man["options"] != json.loads(_json(opt.to_dict())):
            return False
        return True
    except (OSError, ValueError, KeyError):
        return False
