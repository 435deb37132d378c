"""Bad input over every command: exit status 2, one line on stderr naming what, where and
what is allowed, no traceback, every input byte-identical, nothing left where the output
would have gone.

Table-driven; the fixture files (a small simulated test, its FRFs and modal table, and
broken variants of each) are built once for the module. Commands run in-process through
click's runner (the group's own error handling, as the console script), which catches the
same exits the console script would; an uncaught exception fails the case."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from tiremodal_cli.cli.main import cli
from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.io.frffile import write_frf
from tiremodal_cli.io.measurement import read_measurement, write_measurement
from tiremodal_cli.io.modalfile import write_modal
from tiremodal_cli.modal.modes import ModalOptions, modal_table_from_frf
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

SAMPLE_CSV = Path(__file__).resolve().parents[1] / "sample_data" / "paper_table_a1.csv"


def _csv_with(path: Path, row: int, column: str, value: str) -> Path:
    """The paper's Table A1 with one cell replaced (``column`` added when missing)."""
    lines = SAMPLE_CSV.read_text().splitlines()
    head = lines[0].split(",")
    if column not in head:
        head.append(column)
        lines = [",".join(head)] + [ln + "," for ln in lines[1:]]
    cells = lines[row].split(",")
    cells[head.index(column)] = value
    lines[row] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def fx(tmp_path_factory):
    """Every input file of the table, in one folder (read-only for the cases)."""
    d = tmp_path_factory.mktemp("inputs")
    sim = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=1024, seed=3))
    m = write_measurement(d / "m.h5", sim.measurement)
    r = compute_frf(read_measurement(m), FRFOptions(band_hz=(0.0, 320.0), exp_end=0.05))
    write_frf(d / "f.h5", r)
    table, _ = modal_table_from_frf(r, ModalOptions(band_hz=(41.0, 300.0)))
    write_modal(d / "modal.h5", table)
    shutil.copy(SAMPLE_CSV, d / "modes.csv")
    _csv_with(d / "n_inf.csv", 1, "n", "inf")
    _csv_with(d / "n_huge.csv", 1, "n", "1e12")
    _csv_with(d / "f_inf.csv", 2, "frequency_hz", "inf")
    _csv_with(d / "zeta_text.csv", 3, "damping_ratio", "low")
    _csv_with(d / "conf_text.csv", 1, "n_confidence", "high")
    _csv_with(d / "mpc_text.csv", 1, "mpc", "x")
    _csv_with(d / "branch_typo.csv", 2, "branch", "sideways")
    (d / "a_file").write_text("not a folder\n")
    (d / "no_branch.csv").write_text("frequency_hz,n\n55.5,1\n66.0,2\n81.0,3\n")
    for name, value in (("p_text.h5", "high"), ("p_neg.h5", -2.0e5)):
        shutil.copy(m, d / name)
        with h5py.File(d / name, "r+") as h:
            h.attrs["inflation_pressure"] = value
    for name, n in (("short.h5", 2), ("s64.h5", 64)):
        shutil.copy(m, d / name)
        with h5py.File(d / name, "r+") as h:
            for k in ("force", "response"):
                data = h[k][..., :n]
                del h[k]
                h.create_dataset(k, data=data)
    shutil.copy(d / "f.h5", d / "f_force.h5")  # a force autospectrum of the wrong shape, one value < 0
    with h5py.File(d / "f_force.h5", "r+") as h:
        g = h["force_autospectrum"][()]
        del h["force_autospectrum"]
        h.create_dataset("force_autospectrum", data=-g[:, :-1])
    (d / "c_type.toml").write_text('n_points = "many"\n')
    (d / "c_float.toml").write_text("n_hits = 2.5\n")
    (d / "c_bool.toml").write_text("sample_rate = true\n")
    (d / "c_inf.json").write_text('{"noise": Infinity}\n')
    (d / "c_ok.toml").write_text("n_points = 4\n")
    (d / "b_seed.toml").write_text('[run]\nseed = "x"\n')
    (d / "b_band.toml").write_text("[run]\nband = 5\n")
    (d / "b_exp.toml").write_text('[run]\nexp_end = "big"\n')
    (d / "b_param.toml").write_text('[params]\nk_r1 = "stiff"\n')
    (d / "b_mapping.toml").write_text("[ingest]\nmapping = 3\n")
    (d / "b_table.toml").write_text("run = 3\n")
    (d / "params_text.toml").write_text('[params]\nk_r1 = "stiff"\n')
    (d / "params_neg.toml").write_text("[params]\nEI = -1.0\n")
    (d / "notjson.json").write_text("{")
    (d / "garbage.h5").write_bytes(b"not an HDF5 file at all\n" * 10)
    run_dir = d / "run_mixed"
    run_dir.mkdir()
    for name in ("frf.h5", "modal.h5", "modes.csv", "identify.json", "diagnosis.json", "sensitivity.json"):
        (run_dir / name).write_text(name)
    man = {"format": "tiremodal.run", "outputs": {n: "0" * 64 for n in
                                                  ("frf.h5", "modal.h5", "modes.csv", "identify.json",
                                                   "diagnosis.json", "sensitivity.json")}}
    (run_dir / "run.json").write_text(json.dumps(man))
    (d / "empty_dir").mkdir()
    csvdir = d / "csvtest"
    csvdir.mkdir()
    (csvdir / "point01.csv").write_text("time,force,acc\n0,1,2\n")
    return d


# (id, args, words the message must hold). {X} is a fixture file, {out}/{out2} an output
# path in an empty folder. Every case must exit 2 with one line.
CASES = [
    # ---- input replaced by its own output
    ("frf-o-is-input", ["frf", "{m.h5}", "-o", "{m.h5}", "--overwrite"], ["--output", "is the input"]),
    ("frf-plot-is-input", ["frf", "{m.h5}", "-o", "{out}", "--plot", "{m.h5}", "--overwrite"], ["--plot", "input"]),
    ("frf-o-is-plot", ["frf", "{m.h5}", "-o", "{out}.png", "--plot", "{out}.png"], ["--plot", "--output"]),
    ("ingest-o-inside-source", ["ingest", "{csvtest}", "-o", "{csvtest}/point01.csv", "--overwrite"],
     ["inside", "csvtest"]),
    ("ingest-o-read-as-source", ["ingest", "{csvtest}", "-o", "{csvtest}/point02.csv"], ["inside", "csvtest"]),
    ("diagnose-o-is-input", ["diagnose", "{modes.csv}", "-o", "{modes.csv}", "--overwrite"], ["--output", "input"]),
    ("simulate-o-is-config", ["simulate", "{c_ok.toml}", "--config", "{c_ok.toml}", "--overwrite"],
     ["OUTPUT", "--config"]),
    ("simulate-truth-is-config", ["simulate", "{out}", "--config", "{c_ok.toml}", "--truth", "{c_ok.toml}",
                                  "--overwrite"], ["--truth", "--config"]),
    ("lsce-o-is-input", ["lsce", "{f.h5}", "-o", "{f.h5}", "--overwrite"], ["--output", "input"]),
    ("lsce-csv-is-input", ["lsce", "{f.h5}", "-o", "{out}", "--csv", "{f.h5}", "--overwrite"], ["--csv", "input"]),
    # a second output that cannot be written is refused before the first is written
    ("lsce-csv-under-a-file", ["lsce", "{f.h5}", "-o", "{out}", "--csv", "{a_file}/x.csv"],
     ["a_file", "is a file", "allowed"]),
    ("frf-o-under-a-file", ["frf", "{m.h5}", "-o", "{a_file}/f.h5"], ["a_file", "is a file", "allowed"]),
    ("run-o-under-a-file", ["run", "{m.h5}", "-o", "{a_file}/run"], ["a_file", "is a file", "allowed"]),
    ("identify-branch-typo", ["identify", "{branch_typo.csv}"],
     ["branch_typo.csv", "row 2", "branch", "sideways", "allowed", "same"]),
    ("mac-csv-is-input", ["mac", "{modal.h5}", "--csv", "{modal.h5}", "--overwrite"], ["--csv", "input"]),
    ("identify-csv-is-input", ["identify", "{modes.csv}", "--csv", "{modes.csv}", "--overwrite"], ["--csv", "input"]),
    ("predict-csv-is-params", ["predict", "--params", "{params_neg.toml}", "--csv", "{params_neg.toml}",
                               "--overwrite"], ["--csv", "--params"]),
    ("sensitivity-csv-is-params", ["sensitivity", "--params", "{params_neg.toml}", "--csv", "{params_neg.toml}",
                                   "--overwrite"], ["--csv", "--params"]),
    ("run-o-is-input", ["run", "{m.h5}", "-o", "{m.h5}", "--overwrite"], ["--output", "m.h5"]),
    # ---- modes CSV values
    ("identify-n-inf", ["identify", "{n_inf.csv}"], ["n_inf.csv", "row 1", "n", "inf", "allowed"]),
    ("identify-n-huge", ["identify", "{n_huge.csv}"], ["n_huge.csv", "n", "1e12", "allowed"]),
    ("identify-f-inf", ["identify", "{f_inf.csv}"], ["f_inf.csv", "frequency_hz", "inf", "allowed"]),
    ("identify-zeta-text", ["identify", "{zeta_text.csv}"], ["zeta_text.csv", "damping_ratio", "low"]),
    ("identify-conf-text", ["identify", "{conf_text.csv}"], ["conf_text.csv", "n_confidence", "high"]),
    ("identify-mpc-text", ["identify", "{mpc_text.csv}"], ["mpc_text.csv", "mpc", "'x'"]),
    ("identify-no-usable", ["identify", "{no_branch.csv}"], ["no_branch.csv", "no usable modes", "branch"]),
    ("diagnose-n-inf", ["diagnose", "{n_inf.csv}"], ["n_inf.csv", "n", "inf"]),
    ("diagnose-f-inf", ["diagnose", "{f_inf.csv}"], ["f_inf.csv", "frequency_hz"]),
    ("diagnose-conf-text", ["diagnose", "{conf_text.csv}"], ["conf_text.csv", "n_confidence"]),
    ("diagnose-no-usable", ["diagnose", "{no_branch.csv}"], ["no_branch.csv", "no usable modes"]),
    ("diagnose-min-conf", ["diagnose", "{modes.csv}", "--min-confidence", "2"], ["--min-confidence", "2"]),
    ("identify-min-conf", ["identify", "{modes.csv}", "--min-confidence", "nan"], ["--min-confidence"]),
    ("identify-population", ["identify", "{modes.csv}", "--population", "10000000"], ["--population", "10000000"]),
    ("identify-generations", ["identify", "{modes.csv}", "--generations", "100000000"], ["--generations"]),
    ("identify-bounds-inf", ["identify", "{modes.csv}", "--bounds", "k_r1=1:inf"], ["--bounds", "inf"]),
    ("identify-bounds-order", ["identify", "{modes.csv}", "--bounds", "k_r1=5:1"], ["--bounds"]),
    ("identify-missing", ["identify", "{out}"], ["out"]),
    ("identify-garbage", ["identify", "{garbage.h5}"], ["garbage.h5"]),
    # ---- measurement attributes and records
    ("info-pressure-text", ["info", "{p_text.h5}"], ["p_text.h5", "inflation_pressure", "high", "allowed"]),
    ("info-pressure-neg", ["info", "{p_neg.h5}"], ["p_neg.h5", "inflation_pressure", "allowed"]),
    ("run-pressure-text", ["run", "{p_text.h5}", "-o", "{out}"], ["p_text.h5", "inflation_pressure"]),
    ("run-pressure-neg", ["run", "{p_neg.h5}", "-o", "{out}"], ["p_neg.h5", "inflation_pressure"]),
    ("frf-short", ["frf", "{short.h5}", "-o", "{out}"], ["short.h5", "2 samples", "at least"]),
    ("info-short", ["info", "{short.h5}"], ["short.h5", "samples"]),
    ("info-garbage", ["info", "{garbage.h5}"], ["garbage.h5"]),
    ("info-missing", ["info", "{out}"], ["out"]),
    ("frf-plot-ext", ["frf", "{m.h5}", "-o", "{out}", "--plot", "{out2}.xyz"], ["--plot", "xyz", "png"]),
    ("frf-exp-tau", ["frf", "{m.h5}", "-o", "{out}", "--exp-tau", "1e-9"], ["--exp-tau", "1e-09"]),
    ("frf-exp-end-tiny", ["frf", "{s64.h5}", "-o", "{out}", "--exp-end", "1e-50"], ["--exp-end", "allowed", "2.19e-44"]),
    ("frf-fwl-huge", ["frf", "{m.h5}", "-o", "{out}", "--force-window-length", "1e9"],
     ["--force-window-length", "1e+09", "record"]),
    ("frf-fwl-neg", ["frf", "{m.h5}", "-o", "{out}", "--force-window-length", "-1"], ["--force-window-length"]),
    ("frf-fwl-nan", ["frf", "{m.h5}", "-o", "{out}", "--force-window-length", "nan"], ["--force-window-length"]),
    ("frf-band-inverted", ["frf", "{m.h5}", "-o", "{out}", "--band", "300", "100"], ["--band"]),
    ("frf-band-inf", ["frf", "{m.h5}", "-o", "{out}", "--band", "0", "inf"], ["--band"]),
    ("frf-residual-inf", ["frf", "{m.h5}", "-o", "{out}", "--hit-residual-max", "inf"], ["--hit-residual-max"]),
    ("frf-plot-points", ["frf", "{m.h5}", "-o", "{out}", "--plot", "{out2}.png", "--plot-points", "99"],
     ["--plot-points", "99"]),
    ("frf-garbage", ["frf", "{garbage.h5}", "-o", "{out}"], ["garbage.h5"]),
    ("frf-missing", ["frf", "{out2}", "-o", "{out}"], ["out2"]),
    ("frf-not-measurement", ["frf", "{f.h5}", "-o", "{out}"], ["f.h5"]),
    # ---- run
    ("run-param-clamped", ["run", "{m.h5}", "-o", "{out}", "--param", "k_r1=-6.7e6"], ["k_r1", "positive"]),
    ("run-param-bad", ["run", "{m.h5}", "-o", "{out}", "--param", "m_w=heavy"], ["m_w", "heavy"]),
    ("run-param-unknown", ["run", "{m.h5}", "-o", "{out}", "--param", "k_r9=1"], ["k_r9", "allowed"]),
    ("run-band-inverted", ["run", "{m.h5}", "-o", "{out}", "--band", "300", "100"], ["--band"]),
    ("run-band-high", ["run", "{m.h5}", "-o", "{out}", "--band", "10", "1e6"], ["band", "Nyquist"]),
    ("run-params-text", ["run", "{m.h5}", "-o", "{out}", "--params", "{params_text.toml}"], ["k_r1", "stiff"]),
    ("run-missing", ["run", "{out2}", "-o", "{out}"], ["out2"]),
    ("run-garbage", ["run", "{garbage.h5}", "-o", "{out}"], ["garbage.h5"]),
    ("run-short", ["run", "{short.h5}", "-o", "{out}"], ["short.h5", "samples"]),
    # ---- simulate
    ("simulate-config-type", ["simulate", "{out}", "--config", "{c_type.toml}"], ["c_type.toml", "n_points", "many"]),
    ("simulate-config-float", ["simulate", "{out}", "--config", "{c_float.toml}"], ["n_hits", "2.5", "integer"]),
    ("simulate-config-bool", ["simulate", "{out}", "--config", "{c_bool.toml}"], ["sample_rate", "True"]),
    ("simulate-config-inf", ["simulate", "{out}", "--config", "{c_inf.json}"], ["noise", "inf"]),
    ("simulate-n-max-huge", ["simulate", "{out}", "--n-max", "100000", "--points", "4", "--samples", "256"],
     ["--n-max", "100000", "GiB"]),
    ("simulate-samples-huge", ["simulate", "{out}", "--samples", "2000000000"], ["--samples", "2000000000", "GiB"]),
    ("simulate-points-huge", ["simulate", "{out}", "--points", "10000000"], ["--points", "10000000", "GiB"]),
    ("simulate-rate-inf", ["simulate", "{out}", "--sample-rate", "inf"], ["--sample-rate"]),
    ("simulate-noise-nan", ["simulate", "{out}", "--noise", "nan"], ["--noise"]),
    ("simulate-param-text", ["simulate", "{out}", "--param", "EI=soft"], ["EI", "soft"]),
    ("simulate-effect-unknown", ["simulate", "{out}", "--effect", "magic"], ["--effect", "magic", "allowed"]),
    ("simulate-double-hit-range", ["simulate", "{out}", "--double-hit", "99:0"], ["99"]),
    ("simulate-config-notjson", ["simulate", "{out}", "--config", "{notjson.json}"], ["notjson.json"]),
    # ---- lsce
    ("lsce-tol-freq-neg", ["lsce", "{f.h5}", "-o", "{out}", "--tol-freq", "-1"], ["--tol-freq", "-1"]),
    ("lsce-tol-mac-big", ["lsce", "{f.h5}", "-o", "{out}", "--tol-mac", "2"], ["--tol-mac", "2"]),
    ("lsce-tol-damp-nan", ["lsce", "{f.h5}", "-o", "{out}", "--tol-damping", "nan"], ["--tol-damping"]),
    ("lsce-signif", ["lsce", "{f.h5}", "-o", "{out}", "--min-significance", "-0.5"], ["--min-significance"]),
    ("lsce-band-inverted", ["lsce", "{f.h5}", "-o", "{out}", "--band", "300", "100"], ["--band"]),
    ("lsce-not-frf", ["lsce", "{m.h5}", "-o", "{out}"], ["m.h5"]),
    ("lsce-garbage", ["lsce", "{garbage.h5}", "-o", "{out}"], ["garbage.h5"]),
    ("lsce-force-spectrum", ["lsce", "{f_force.h5}", "-o", "{out}"], ["f_force.h5", "force_autospectrum", "≥ 0"]),
    ("lsce-max-order", ["lsce", "{f.h5}", "-o", "{out}", "--max-order", "100000"], ["--max-order"]),
    # ---- mac, predict, sensitivity, ingest
    ("mac-not-modal", ["mac", "{f.h5}"], ["f.h5"]),
    ("mac-channel", ["mac", "{modal.h5}", "--channels", "nope"], ["nope"]),
    ("mac-analytic-neg", ["mac", "{modal.h5}", "--analytic", "-1"], ["--analytic"]),
    ("mac-model-text", ["mac", "{modal.h5}", "--model", "{params_text.toml}"], ["k_r1", "stiff"]),
    ("predict-n-max", ["predict", "--n-max", "100000"], ["--n-max"]),
    ("predict-params-neg", ["predict", "--params", "{params_neg.toml}"], ["EI", "positive"]),
    ("predict-param-nan", ["predict", "--param", "k_r2=nan"], ["k_r2", "nan"]),
    ("predict-compare-alone", ["predict", "--compare-frf", "{f.h5}"], ["--plot-frf"]),
    ("sensitivity-factors", ["sensitivity", "--factors", "a,b"], ["--factors"]),
    ("sensitivity-factors-neg", ["sensitivity", "--factors", "-1,1"], ["--factors", "-1"]),
    ("sensitivity-n-max", ["sensitivity", "--n-max", "5000"], ["--n-max"]),
    ("ingest-missing", ["ingest", "{out2}", "-o", "{out}"], ["out2"]),
    ("ingest-pressure-neg", ["ingest", "{csvtest}", "-o", "{out}", "--pressure", "-3"], ["--pressure", "-3"]),
    ("ingest-pressure-inf", ["ingest", "{csvtest}", "-o", "{out}", "--pressure", "inf"], ["--pressure"]),
    ("ingest-empty", ["ingest", "{empty_dir}", "-o", "{out}"], ["empty_dir"]),
    # ---- export
    ("export-o-is-source", ["export", "{modal.h5}", "-o", "{modal.h5}"], ["--output", "modal.h5"]),
    ("export-o-inside-source", ["export", "{run_mixed}", "-o", "{run_mixed}/shapes"], ["--output", "inside"]),
    ("export-not-modal", ["export", "{f.h5}", "-o", "{out}"], ["f.h5"]),
    ("export-radius-nan", ["export", "{modal.h5}", "-o", "{out}", "--radius", "tread=nan"], ["--radius", "nan"]),
    ("export-radius-ring", ["export", "{modal.h5}", "-o", "{out}", "--radius", "hub=0.3"], ["--radius", "hub"]),
    # ---- report
    ("report-mixed", ["report", "{run_mixed}"], ["run_mixed", "does not match"]),
    ("report-empty", ["report", "{empty_dir}"], ["empty_dir"]),
    ("report-missing", ["report", "{out}"], ["out"]),
    # ---- batch
    ("batch-config-seed", ["batch", "{m.h5}", "-o", "{out}", "--config", "{b_seed.toml}"],
     ["b_seed.toml", "seed", "'x'", "integer"]),
    ("batch-config-band", ["batch", "{m.h5}", "-o", "{out}", "--config", "{b_band.toml}"],
     ["b_band.toml", "band", "5", "LO"]),
    ("batch-config-exp", ["batch", "{m.h5}", "-o", "{out}", "--config", "{b_exp.toml}"],
     ["b_exp.toml", "exp_end", "big"]),
    ("batch-config-param", ["batch", "{m.h5}", "-o", "{out}", "--config", "{b_param.toml}"], ["k_r1", "stiff"]),
    ("batch-config-mapping", ["batch", "{m.h5}", "-o", "{out}", "--config", "{b_mapping.toml}"],
     ["mapping", "3"]),
    ("batch-config-table", ["batch", "{m.h5}", "-o", "{out}", "--config", "{b_table.toml}"], ["[run]", "table"]),
    ("batch-missing-root", ["batch", "{out2}", "-o", "{out}"], ["out2"]),
    ("batch-no-tests", ["batch", "{empty_dir}", "-o", "{out}"], ["no tests"]),
    ("batch-o-is-file", ["batch", "{m.h5}", "-o", "{m.h5}"], ["m.h5"]),
    ("batch-jobs", ["batch", "{m.h5}", "-o", "{out}", "--jobs", "0"], ["--jobs"]),
]


def _digest(folder: Path) -> dict:
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else "dir"
            for p in sorted(folder.rglob("*"))}


def test_the_table_covers_every_command():
    covered = {args[0] for _, args, _ in CASES}
    assert covered == set(cli.commands)  # every registered command, not only the listed ones
    assert len(CASES) >= 60


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_input(fx, tmp_path, case, monkeypatch):
    name, args, words = case
    outdir = tmp_path / "outputs"
    outdir.mkdir()
    monkeypatch.chdir(outdir)  # anything written relative to the working folder shows up here
    subs = {"out": str(outdir / "out"), "out2": str(outdir / "out2")}
    subs.update({p.name: str(p) for p in fx.iterdir()})
    argv = []
    for a in args:
        for k, v in subs.items():
            a = a.replace("{" + k + "}", v)
        argv.append(a)
    before = _digest(fx)
    res = CliRunner().invoke(cli, argv, catch_exceptions=False)
    err = res.stderr.strip()
    assert res.exit_code == 2, (name, res.exit_code, res.output)
    assert "Traceback" not in res.output
    assert err and "\n" not in err, f"{name}: not one line: {err!r}"
    for w in words:
        w = w.replace("{", "").replace("}", "")
        assert w.lower() in err.lower(), f"{name}: {w!r} not in {err!r}"
    assert _digest(fx) == before, f"{name}: an input changed"
    assert os.listdir(outdir) == [], f"{name}: left {os.listdir(outdir)}"
