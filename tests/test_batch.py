"""``tiremodal batch``: a campaign tree with good and bad tests, resume after a kill, Dask.

The tree: six good tests — three measurement files at 700/800/900 kPa, one more in a
sub-folder, a UFF 58 folder and a CSV folder — and three bad ones: a truncated file, a file
of the wrong layout (its force records missing), and a test whose every hit is clipped.
Stages run with ``max_effects = 0`` (diagnose reports the residual, adds nothing) to keep
the suite quick; the batch machinery is the same.
"""

from __future__ import annotations

import concurrent.futures as cf
import csv
import dataclasses
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from tiremodal_cli.workflow.batch import BatchConfig, load_config, run_batch
from tiremodal_cli.workflow.executors import as_completed
from tiremodal_cli.workflow.discovery import BatchTest, discover, source_sha256
from tiremodal_cli.workflow.summary import read_summary
from tiremodal_cli.cli.simulate import mapping_toml
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.io.ingest.uff import write_uff_time
from tiremodal_cli.io.measurement import write_measurement
from tiremodal_cli.workflow.manifest import is_complete
from tiremodal_cli.workflow.run_options import MANIFEST, RunOptions
from tiremodal_cli.tyre.simulate import CAMPAIGN_CONFIG, Faults, simulate, simulate_campaign

from conftest import run_cli

FAST = "[run]\nmax_effects = 0\n"
GOOD = ("p0700_r1", "p0800_r1", "p0900_r1", "rig2__p0800_r1", "uff_test", "csv_test")
BAD = {"truncated": "truncated", "wrong_layout": "'force' is missing", "clipped": "every hit"}


def _write_csv_folder(folder: Path, m) -> None:
    """The ``point<P>_hit<H>.csv`` layout with ``channels.csv`` (docs/ingest.md)."""
    folder.mkdir(parents=True)
    t = np.arange(m.force.shape[-1]) / m.sample_rate
    for p in range(m.n_points):
        for h in range(m.n_hits):
            cols = [t, m.force[p, h]] + [m.response[p, h, c] for c in range(m.n_channels)]
            np.savetxt(folder / f"point{p + 1:02d}_hit{h + 1}.csv", np.column_stack(cols), delimiter=",",
                       header="time_s,force_N," + ",".join(m.channel_name), comments="", fmt="%.9g")
    with open(folder / "channels.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["name", "location", "angle_deg"])
        for n, loc, a in zip(m.channel_name, m.channel_location, m.channel_angle):
            w.writerow([n, loc, np.rad2deg(a)])
    with open(folder / "points.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["point", "angle_deg"])
        for p, a in enumerate(m.point_angle):
            w.writerow([p + 1, np.rad2deg(a)])


def make_tree(root: Path) -> Path:
    """Six good and three bad tests under ``root/tree`` (seeded); returns the tree."""
    tree = root / "tree"
    simulate_campaign(tree, [7e5, 8e5, 9e5], seed=100)
    simulate_campaign(tree / "rig2", [8e5], seed=200)
    m = simulate(dataclasses.replace(CAMPAIGN_CONFIG, seed=300)).measurement
    _, mapping = write_uff_time(tree / "uff_test", m)
    (tree / "uff_test" / "mapping.toml").write_text(
        mapping_toml(mapping) + '\n[test]\ntire = "GL073A, UFF export"\ninflation_pressure = 8.0e5\n')
    _write_csv_folder(tree / "csv_test", simulate(dataclasses.replace(CAMPAIGN_CONFIG, seed=400)).measurement)
    bad = tree / "bad"
    good = simulate(dataclasses.replace(CAMPAIGN_CONFIG, seed=500)).measurement
    write_measurement(bad / "truncated.h5", good)
    size = (bad / "truncated.h5").stat().st_size
    with open(bad / "truncated.h5", "r+b") as fh:
        fh.truncate(size // 2)
    write_measurement(bad / "wrong_layout.h5", good)
    with h5py.File(bad / "wrong_layout.h5", "r+") as h:
        del h["force"]
    hits = [(p, h, "force") for p in range(34) for h in range(2)]
    clipped = simulate(dataclasses.replace(CAMPAIGN_CONFIG, seed=600, faults=Faults(clipped=tuple(hits))))
    write_measurement(bad / "clipped.h5", clipped.measurement)
    (root / "fast.toml").write_text(FAST)
    return tree


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """The tree and one local batch over it (2 worker processes), run through the CLI."""
    root = tmp_path_factory.mktemp("campaign")
    tree = make_tree(root)
    out = root / "out"
    res = run_cli(["batch", tree, "-o", out, "--jobs", 2, "--config", root / "fast.toml", "--json"])
    return root, tree, out, res


def _outputs(out: Path) -> list[Path]:
    return sorted(p for p in out.iterdir() if p.is_dir() and not p.name.startswith("."))


def test_good_and_bad_tests(campaign):
    root, tree, out, res = campaign
    assert res.exit_code == 1, res.output  # some tests failed: documented exit status 1
    recs = json.loads(res.stdout)
    by = {r["test"]: r for r in recs}
    assert sorted(by) == sorted(GOOD + tuple(f"bad__{k}" for k in BAD))
    for name in GOOD:
        assert by[name]["status"] == "done", by[name]["reason"]
        assert is_complete(out / name)
        assert by[name]["modes_found"] >= 25
        assert by[name]["rms_error_pct"] < 0.5  # each test fitted at its own recorded pressure
    for name, why in BAD.items():
        r = by[f"bad__{name}"]
        assert r["status"] == "failed" and why in r["reason"], r
        assert "\n" not in r["reason"]
        assert not (out / f"bad__{name}").exists()
    assert [p.name for p in _outputs(out)] == sorted(GOOD)
    assert not (out / ".partial").exists()
    with open(out / "summary.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 9 and sum(r["status"] == "failed" for r in rows) == 3
    assert {r["test"]: r["kind"] for r in rows}["uff_test"] == "uff"
    assert {r["test"]: r["kind"] for r in rows}["csv_test"] == "csv"
    assert by["uff_test"]["tire"] == "GL073A, UFF export" and by["uff_test"]["inflation_pressure"] == 8e5
    p = {r["test"]: float(r["inflation_pressure"]) for r in rows if r["inflation_pressure"]}
    assert p["p0700_r1"] == 7e5 and p["p0900_r1"] == 9e5
    assert all(float(r["k_r1"]) > 0 and float(r["k_r1_std_error"]) > 0 for r in rows if r["status"] == "done")
    # no mass on these tyres: no test's orders mix (run.json's orders_mix note); a failed test is not judged
    assert {r["orders_mix"] for r in rows if r["status"] == "done"} == {"False"}
    assert {r["orders_mix"] for r in rows if r["status"] == "failed"} == {""}
    assert len(read_summary(out)) == 9
    for f in ("campaign_parameters.png", "campaign_parameters.svg", "campaign_frequencies.png"):
        assert (out / f).stat().st_size > 1000
    # the stiffening with pressure is there in the campaign: n = 6 same-branch mode rises
    f6 = {r["test"]: next(m["frequency_hz"] for m in r["modes"] if m["n"] == 6 and m["branch"] == "same")
          for r in recs if r["test"] in ("p0700_r1", "p0800_r1", "p0900_r1")}
    assert f6["p0700_r1"] < f6["p0800_r1"] < f6["p0900_r1"]


def test_rerun_skips_complete_and_force_redoes(campaign):
    root, tree, out, _ = campaign
    man = {n: (out / n / MANIFEST).stat().st_mtime_ns for n in GOOD}
    res = run_cli(["batch", tree, "-o", out, "--jobs", 1, "--config", root / "fast.toml", "--json", "--no-plots"])
    recs = {r["test"]: r for r in json.loads(res.stdout)}
    assert res.exit_code == 1
    assert all(recs[n]["status"] == "skipped" for n in GOOD)
    assert {n: (out / n / MANIFEST).stat().st_mtime_ns for n in GOOD} == man
    assert all(recs[f"bad__{k}"]["status"] == "failed" for k in BAD)  # failures are retried
    # changed options are not "complete": a different seed redoes the test
    one = tree / "p0700_r1.h5"
    r2 = run_batch([one], root / "out_one", load_config(root / "fast.toml"))
    assert r2[0]["status"] == "done"
    r3 = run_batch([one], root / "out_one", load_config(root / "fast.toml", run_overrides={"seed": 1}))
    assert r3[0]["status"] == "done"
    r4 = run_batch([one], root / "out_one", load_config(root / "fast.toml", run_overrides={"seed": 1}))
    assert r4[0]["status"] == "skipped"
    r5 = run_batch([one], root / "out_one", load_config(root / "fast.toml", run_overrides={"seed": 1}), force=True)
    assert r5[0]["status"] == "done"


def _start_and_signal(tree, out, config, sig, *, after: int = 2):
    """Start a 2-worker batch in its own session; send ``sig`` to the whole group once
    ``after`` tests are in. Returns (exit status, stderr)."""
    cmd = [sys.executable, "-m", "tiremodal_cli", "batch", str(tree), "-o", str(out), "--jobs", "2",
           "--config", str(config), "--no-plots"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and proc.poll() is None:
            if out.exists() and len(_outputs(out)) >= after:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the batch finished before the signal"
        os.killpg(proc.pid, sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    time.sleep(0.5)  # let killed workers' file handles go
    return proc.returncode, err.decode()


def test_killed_batch_resumes_without_redoing(tmp_path, campaign):
    """SIGKILL the whole batch (parent and workers) once two tests are in; re-run."""
    root, tree, _, _ = campaign
    out = tmp_path / "out"
    _start_and_signal(tree, out, root / "fast.toml", signal.SIGKILL)
    before = _outputs(out)
    assert 2 <= len(before) < len(GOOD)
    for p in before:  # never a half-written folder: every visible one is complete
        assert is_complete(p), p
    stamps = {p.name: (p / MANIFEST).stat().st_mtime_ns for p in before}
    recs = run_batch([tree], out, load_config(root / "fast.toml"), jobs=2, plots=False)
    st = {r["test"]: r["status"] for r in recs}
    assert all(st[n] == "skipped" for n in stamps)
    assert all(st[n] == "done" for n in GOOD if n not in stamps)
    assert sum(s == "failed" for s in st.values()) == 3
    assert {n: (out / n / MANIFEST).stat().st_mtime_ns for n in stamps} == stamps
    assert [p.name for p in _outputs(out)] == sorted(GOOD) and not (out / ".partial").exists()


def test_ctrl_c_stops_the_workers_and_exits_130(tmp_path, campaign):
    root, tree, _, _ = campaign
    out = tmp_path / "out"
    rc, err = _start_and_signal(tree, out, root / "fast.toml", signal.SIGINT, after=1)
    assert rc == 130 and err.rstrip().endswith("Interrupted.")
    assert "Traceback" not in err
    done = _outputs(out)
    assert 1 <= len(done) < len(GOOD) and all(is_complete(p) for p in done)
    # rows of what was done before the interrupt (a folder a worker installed just as the
    # signal came may have no row yet: it is skipped next time)
    recs = read_summary(out) if (out / "summary.jsonl").exists() else []
    assert {r["test"] for r in recs if r["status"] == "done"} <= {p.name for p in done}
    again = run_batch([tree], out, load_config(root / "fast.toml"), plots=False)
    assert {r["test"] for r in again if r["status"] == "skipped"} == {p.name for p in done}


def _comparable(recs):
    drop = {"seconds", "pipeline_seconds", "output"}
    return [{k: v for k, v in r.items() if k not in drop} for r in recs]


def test_ctrl_c_is_raised_between_results_not_inside_the_callers_work():
    """While the batch handles a finished test, a Ctrl-C waits for the next result: it is
    raised from the wait, once, and Python's own handler is back afterwards."""
    before = signal.getsignal(signal.SIGINT)
    first, second = cf.Future(), cf.Future()
    first.set_result(1)
    results = as_completed([first, second], poll_s=0.01)
    assert next(results) is first
    os.kill(os.getpid(), signal.SIGINT)  # arrives while the caller works on `first`
    time.sleep(0.05)  # the handler runs here, and the caller's work goes on
    with pytest.raises(KeyboardInterrupt):
        next(results)
    assert signal.getsignal(signal.SIGINT) is before


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_dask_gives_the_same_summary(tmp_path, campaign):
    distributed = pytest.importorskip("distributed")
    root, tree, out, res0 = campaign
    local = json.loads(res0.stdout)  # the first local run (a later one rewrites the summary as "skipped")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        res = run_cli(["batch", tree, "-o", tmp_path / "dask", "--scheduler", cluster.scheduler_address,
                       "--config", root / "fast.toml", "--json"])
    assert res.exit_code == 1
    remote = json.loads(res.stdout)
    assert _comparable(remote) == _comparable(local)
    assert [p.name for p in _outputs(tmp_path / "dask")] == sorted(GOOD)


def test_discovery_rules(tmp_path):
    simulate_campaign(tmp_path / "a", [8e5], seed=1)
    (tmp_path / "a" / ".hidden").mkdir()
    shutil.copy(tmp_path / "a" / "p0800_r1.h5", tmp_path / "a" / ".hidden" / "x.h5")
    out = tmp_path / "a" / "out"
    r = run_batch([tmp_path / "a"], out, load_config(None, run_overrides={"max_effects": 0}), plots=False)
    assert [x["status"] for x in r] == ["done"]
    # the outputs (frf.h5, modal.h5) under the tree are not tests, nor is the batch folder
    tests = discover([tmp_path / "a"])
    assert [(t.name, t.kind) for t in tests] == [("p0800_r1", "measurement")]
    assert discover([tmp_path / "a"], exclude=[out]) == tests
    two = discover([tmp_path / "a", tmp_path / "a" / "p0800_r1.h5"])
    assert [t.name for t in two] == ["a__p0800_r1", "p0800_r1"]


def test_folder_checksum_sees_every_file(tmp_path):
    d = tmp_path / "t"
    d.mkdir()
    (d / "point1.csv").write_text("x")
    t = BatchTest("t", d, "csv")
    a = source_sha256(t)
    (d / "point2.csv").write_text("y")
    b = source_sha256(t)
    (d / "point2.csv").write_text("z")
    assert len({a, b, source_sha256(t)}) == 3


def test_config_errors_are_one_line(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[run]\nmax_efects = 1\n")
    with pytest.raises(ParameterError, match=r"c.toml \[run\]: unknown option 'max_efects'; allowed: frf_top"):
        load_config(cfg)
    cfg.write_text("[runs]\n")
    with pytest.raises(ParameterError, match=r"unknown table \[runs\]; allowed: \[run\], \[params\], \[ingest\]"):
        load_config(cfg)
    cfg.write_text("[run]\nband = [300, 40]\n")
    with pytest.raises(ParameterError, match="band needs 0 ≤ LO < HI"):
        load_config(cfg)
    cfg.write_text("[params]\nk_r3 = 1\n")
    with pytest.raises(ParameterError, match="unknown model parameter 'k_r3'"):
        load_config(cfg)
    cfg.write_text("[run]\nexp_end = false\nseed = 3\n[params]\nm_w = \"clamped\"\n")
    c = load_config(cfg)
    assert c.run == RunOptions(exp_end=None, seed=3) and c.params.m_w is None
    assert BatchConfig().params.m_w == 1000.0


def test_cli_usage_errors(tmp_path):
    (tmp_path / "empty").mkdir()
    res = run_cli(["batch", tmp_path / "empty", "-o", tmp_path / "o"])
    assert res.exit_code == 2
    assert res.stderr.strip().splitlines() == [
        f"Error: no tests under {tmp_path / 'empty'}: expected measurement files (*.h5) or UFF/CSV test folders"]
    res = run_cli(["batch", tmp_path / "nowhere", "-o", tmp_path / "o"])
    assert res.exit_code == 2 and "no such file or folder" in res.stderr
    res = run_cli(["batch", tmp_path / "empty", "-o", tmp_path / "o", "--jobs", 0])
    assert res.exit_code == 2 and "--jobs" in res.stderr


def test_second_batch_on_one_outdir_is_refused(tmp_path):
    import fcntl

    simulate_campaign(tmp_path / "a", [8e5], seed=1)
    out = tmp_path / "out"
    out.mkdir()
    with open(out / ".lock", "a+") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(ParameterError, match="another batch is writing there"):
            run_batch([tmp_path / "a"], out)


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_workers_die_with_a_killed_parent_and_hold_the_lock_until_then(tmp_path, campaign):
    """SIGKILL of the batch process alone (not its group): its forkserver and workers end
    within a second, install nothing after, and a new batch is refused only while they live."""
    psutil = pytest.importorskip("psutil")
    root, tree, _, _ = campaign
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "tiremodal_cli", "batch", str(tree), "-o", str(out), "--jobs", "2",
           "--config", str(root / "fast.toml"), "--no-plots"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and proc.poll() is None:  # both workers busy with a test
            if (out / ".partial").is_dir() and len(list((out / ".partial").iterdir())) >= 2:
                break
            time.sleep(0.02)
        assert proc.poll() is None, "the batch finished first"
        kids = psutil.Process(proc.pid).children(recursive=True)
        assert len(kids) >= 3  # the forkserver (and resource tracker) and the two workers
        proc.kill()  # the parent alone
        proc.wait()
        t0 = time.monotonic()
        gone, alive = psutil.wait_procs(kids, timeout=10)
        took = time.monotonic() - t0
        assert not alive, f"still running {took:.1f} s after the parent died: {[p.pid for p in alive]}"
        assert took < 3
        installed = _outputs(out)
        time.sleep(1.0)
        assert _outputs(out) == installed  # nothing installed after the workers were gone
    finally:
        os.killpg(proc.pid, signal.SIGKILL) if proc.poll() is None else None
        for p in psutil.Process().children(recursive=True):
            if p.pid != os.getpid() and p.cmdline()[:1] == [sys.executable] and str(out) in " ".join(p.cmdline()):
                p.kill()
    recs = run_batch([tree], out, load_config(root / "fast.toml"), jobs=1, plots=False)  # the lock is free
    assert sum(r["status"] in ("done", "skipped") for r in recs) == len(GOOD)


def test_worker_lock_of_a_killed_batch_refuses_a_new_one(tmp_path):
    """While a worker of a dead batch still holds its shared lock, a new batch is refused."""
    import fcntl

    simulate_campaign(tmp_path / "a", [8e5], seed=1)
    out = tmp_path / "out"
    out.mkdir()
    with open(out / ".lock.workers", "a+") as fh:
        fcntl.flock(fh, fcntl.LOCK_SH | fcntl.LOCK_NB)
        with pytest.raises(ParameterError, match="workers of an earlier batch are still running"):
            run_batch([tmp_path / "a"], out)


def test_relative_paths_reach_a_scheduler_absolute(tmp_path, monkeypatch):
    """A remote worker runs in another working folder: the jobs it gets name absolute paths
    (a relative one failed every test and left '.partial' in the worker's folder)."""
    import contextlib

    import tiremodal_cli.workflow.batch as batch

    simulate_campaign(tmp_path / "data" / "a", [8e5], seed=1)
    elsewhere = tmp_path / "worker_cwd"
    elsewhere.mkdir()
    seen = []

    @contextlib.contextmanager
    def remote(jobs=1, scheduler=None, **kw):
        class Remote(batch.SerialExecutor):
            def submit(self, fn, job):
                seen.append(job)
                here = os.getcwd()
                os.chdir(elsewhere)  # the worker's own folder
                try:
                    return super().submit(lambda j: batch.record(j.test, "done"), job)
                finally:
                    os.chdir(here)
        yield Remote()

    monkeypatch.setattr(batch, "executor", remote)
    monkeypatch.chdir(tmp_path)
    batch.run_batch([Path("data")], Path("out"), scheduler="tcp://nowhere:1", plots=False)
    assert seen and all(j.test.path.is_absolute() and j.outdir.is_absolute() and j.partial.is_absolute()
                        for j in seen)
    assert all(j.test.path.exists() for j in seen)
