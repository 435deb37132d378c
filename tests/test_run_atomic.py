"""``run`` is atomic: killed at any moment, its output folder is the complete old run, the
complete new one, or absent; two runs into one folder never race; ``report`` refuses a
folder that does not match its manifest."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tiremodal_cli.io.measurement import write_measurement
from tiremodal_cli.workflow.manifest import verify_manifest
from tiremodal_cli.workflow.run_folder import run_folder
from tiremodal_cli.workflow.run_options import MANIFEST, OUTPUTS, RunOptions
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

from conftest import run_cli

FAST = RunOptions(max_effects=0)  # the pipeline whole, without the (slow) diagnosis rounds


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    """A small simulated test and one complete run of it (the 'old' folder)."""
    d = tmp_path_factory.mktemp("atomic")
    sim = simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=1024, seed=3))  # rim clamped: dead rim channel
    meas = write_measurement(d / "m.h5", sim.measurement)
    old = d / "old"
    run_folder(meas, old, FAST)
    return meas, old


def _state(folder: Path, old_manifest: dict) -> str:
    """'absent', 'old' or 'new' — or the assertion fails (a half-written or mixed folder)."""
    if not folder.exists():
        return "absent"
    man = verify_manifest(folder)  # raises on a missing or mixed output
    assert set(OUTPUTS) <= set(man["outputs"])
    return "old" if man == old_manifest else "new"


def _copy_old(old: Path, dest: Path) -> None:
    import shutil

    shutil.copytree(old, dest)


def _spawn(meas, out, *extra):
    return subprocess.Popen([sys.executable, "-m", "tiremodal_cli", "run", str(meas), "-o", str(out),
                             "--max-effects", "0", *extra], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


def _private(out: Path) -> list[Path]:
    return sorted(out.parent.glob(f".{out.name}.partial.*"))


def _wait(cond, proc, timeout=60.0):
    t0 = time.monotonic()
    while not cond():
        if proc.poll() is not None or time.monotonic() - t0 > timeout:
            return False
        time.sleep(0.005)
    return True


MOMENTS = {
    "at start": lambda out: True,
    "private folder made": lambda out: bool(_private(out)),
    "frf.h5 written": lambda out: any((p / "frf.h5").exists() for p in _private(out)),
    "modal.h5 written": lambda out: any((p / "modal.h5").exists() for p in _private(out)),
    "identify.json written": lambda out: any((p / "identify.json").exists() for p in _private(out)),
}


def test_run_killed_at_any_moment_leaves_old_new_or_nothing(measured, tmp_path):
    """SIGKILL at several moments of ``run --overwrite`` over a complete folder (→ the old
    folder) and of ``run`` into a fresh one (→ nothing); then a run completes (→ the new one),
    keeping the measurement that lies inside the folder byte-identical, and clears the debris."""
    meas, old = measured
    old_manifest = json.loads((old / MANIFEST).read_text())
    cases = [(m, True) for m in MOMENTS] + [(m, False) for m in ("private folder made", "modal.h5 written")]
    for i, (moment, overwrite) in enumerate(cases):
        out = tmp_path / f"out{i}"
        if overwrite:
            _copy_old(old, out)
        proc = _spawn(meas, out, *(["--overwrite"] if overwrite else []))
        reached = _wait(lambda: MOMENTS[moment](out), proc)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        proc.stderr.close()
        state = _state(out, old_manifest)
        assert reached, (moment, proc.returncode)
        assert state == ("old" if overwrite else "absent"), (moment, overwrite, state)
    # the next run into a killed folder clears the debris and installs a complete new folder;
    # the measurement inside it and the user's other files are carried over, the stale report is not
    out = tmp_path / "out1"
    assert _private(out)
    inside = out / "m.h5"
    inside.write_bytes(meas.read_bytes())
    (out / "notes.txt").write_text("kept")
    (out / "report.html").write_text("stale view")
    before = inside.read_bytes()
    # the help's own examples of --param (a traceback before: run.py built a dict of names)
    res = run_cli(["run", inside, "-o", out, "--max-effects", "0", "--overwrite",
                   "--param", "k_r1=6.7e6", "--param", "m_w=clamped"])
    assert res.exit_code == 0, res.output
    assert _state(out, old_manifest) == "new"
    man = verify_manifest(out)
    assert man["params"]["k_r1"] == 6.7e6 and man["params"]["m_w"] is None
    assert inside.read_bytes() == before and (out / "notes.txt").read_text() == "kept"
    assert not (out / "report.html").exists()
    assert "m.h5" in verify_manifest(out)["outputs"]
    assert not _private(out) and not list(tmp_path.glob(".out1.old.*")) and not list(tmp_path.glob(".out1.lock"))


def test_two_runs_into_one_folder_do_not_race(measured, tmp_path):
    meas, _ = measured
    out = tmp_path / "r"
    first = _spawn(meas, out, "--overwrite")
    assert _wait(lambda: bool(_private(out)), first)
    res = run_cli(["run", meas, "-o", out, "--max-effects", "0", "--overwrite"])
    first.kill()
    first.wait()
    first.stderr.close()
    assert res.exit_code == 2
    assert "another process is writing there" in res.output and "--output" in res.output


def test_run_error_leaves_nothing(measured, tmp_path):
    """A run that fails (here: a band with no modes) leaves no folder and no debris."""
    meas, _ = measured
    out = tmp_path / "r"
    res = run_cli(["run", meas, "-o", out, "--band", "1", "2"])
    assert res.exit_code == 2
    assert os.listdir(tmp_path) == []


def test_report_refuses_a_mixed_folder(measured, tmp_path):
    """A folder whose outputs do not match run.json's checksums (two runs mixed) is refused."""
    meas, old = measured
    out = tmp_path / "r"
    _copy_old(old, out)
    ident = json.loads((out / "identify.json").read_text())
    ident["rms_error_pct"] = 0.0  # as if from another run
    (out / "identify.json").write_text(json.dumps(ident))
    res = run_cli(["report", out])
    assert res.exit_code == 2
    assert "identify.json" in res.output and "does not match" in res.output
    assert not (out / "report.html").exists() and not (out / "figures").exists()


def test_report_of_a_run_with_a_dead_channel(measured):
    """Every default simulated test has a dead rim channel: its rejection has no point/hit;
    the report's rejection table shows it as 'all' (it raised TypeError before)."""
    from tiremodal_cli.workflow.run_page import FIGURES, run_body

    meas, old = measured
    man = json.loads((old / MANIFEST).read_text())
    assert any(x["point"] is None for x in man["summary"]["rejected_hits"])
    body = run_body(old, man, json.loads((old / "identify.json").read_text()),
                    json.loads((old / "diagnosis.json").read_text()), {stem: b"" for stem, _ in FIGURES})
    assert ">all<" in body


def test_modal_file_stores_no_nan_for_a_dead_channel(measured):
    """The dead rim channel's shapes, fit errors and synthesis are an explicit null in the
    modal file (fill value 0, ``channel_live`` false, the reason in attributes), never a
    stored NaN; read_modal gives them back as NaN, the live channels unchanged."""
    import h5py
    import numpy as np

    from tiremodal_cli.io.modalfile import read_modal

    _, old = measured
    with h5py.File(old / "modal.h5", "r") as h:
        live = h["channel_live"][()]
        names = [x.decode() if isinstance(x, bytes) else x for x in h["channel_name"][()]]
        assert not live[names.index("rim")] and live[names.index("tread")]
        for name in ("shapes", "fit_error", "synthesis"):
            arr = h[name][()]
            assert np.all(np.isfinite(arr)), name
            assert "dead channel" in h[name].attrs["null_reason"] and h[name].attrs["null_fill"] == 0
        assert "not a member of a split pair" in h["splitting_hz"].attrs["null_reason"]
        tread_err = h["fit_error"][names.index("tread")]
    t = read_modal(old / "modal.h5")
    rim = names.index("rim")
    assert np.all(np.isnan(t.fit_error[rim])) and np.all(np.isnan(t.shapes[:, rim]))
    assert np.all(np.isnan(t.synthesis[rim]))
    assert np.array_equal(t.fit_error[names.index("tread")], tread_err)
