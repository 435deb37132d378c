"""``batch``: the whole pipeline (``run``) over every test found under some folders.

The way of the data: **discover** the tests (measurement files; UFF/CSV test folders by
``ingest``'s rules) → **plan** (one job per test; a test whose output folder is complete
for the same input and options is skipped) → **execute** the jobs on an executor (a local
process pool, or a Dask cluster through the same ``concurrent.futures.Executor``
interface) → **summarise** (one row per test, CSV and JSON lines; plots across the tests).

Guarantees
----------
* A failing test never stops the others; it is recorded with its one-line reason.
* An output folder is complete or absent: each test runs in a private folder under
  ``OUTDIR/.partial/`` and is renamed into place (``os.replace``, atomic within one file
  system) only when every output and the manifest are written. A batch killed at any
  moment leaves complete folders and debris under ``.partial/``, which the next batch
  removes before it starts.
* One batch at a time per OUTDIR (an advisory lock on ``OUTDIR/.lock``).
* Resume: a test is skipped when its folder's manifest (``run.json``) has every output with
  its checksum, the same source checksum (the measurement file, or the test folder's files),
  the same options and the same nominal parameters. ``force`` redoes it.

The steps live in :mod:`~tiremodal_cli.workflow.discovery` (the tests),
:mod:`~tiremodal_cli.workflow.executors` (where the jobs run) and
:mod:`~tiremodal_cli.workflow.summary` (the records, CSV and JSON lines); this module
holds the campaign's configuration, one test's job and the batch itself.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from threadpoolctl import threadpool_limits

from tiremodal_cli.errors import DataFormatError, ParameterError, TiremodalError
from tiremodal_cli.io.config import load_mapping
from tiremodal_cli.io.files import UMASK, install_dir
from tiremodal_cli.io.frfuff import uff_function_types
from tiremodal_cli.io.ingest import read_source
from tiremodal_cli.io.ingest.uff import uff_files
from tiremodal_cli.io.measurement import write_measurement
from tiremodal_cli.tyre.model import NOMINAL_RIM_KG, TyreParameters
from tiremodal_cli.workflow.discovery import BatchTest, discover, source_sha256
from tiremodal_cli.workflow.executors import SerialExecutor, as_completed, dask_client_class, executor
from tiremodal_cli.workflow.manifest import is_complete, read_manifest
from tiremodal_cli.workflow.pipeline import run
from tiremodal_cli.workflow.run_options import RunOptions
from tiremodal_cli.workflow.summary import SUMMARY_CSV, SUMMARY_JSONL, read_summary, summary_rows, write_summary

__all__ = ["BatchTest", "Job", "BatchConfig", "discover", "load_config", "plan", "run_one", "executor", "run_batch",
           "summary_rows", "write_summary", "read_summary", "SUMMARY_CSV", "SUMMARY_JSONL", "PARTIAL",
           "SerialExecutor", "record", "source_sha256"]

PARTIAL = ".partial"
LOCK = ".lock"
WORKERS_LOCK = ".lock.workers"


@dataclass(frozen=True)
class BatchConfig:
    """Everything a campaign passes to each test.

    run : RunOptions of every stage
    params : nominal model parameters (identify's and diagnose's start)
    mapping : name of the mapping file looked for in each UFF/CSV test folder
    """

    run: RunOptions = field(default_factory=RunOptions)
    params: TyreParameters = field(default_factory=lambda: TyreParameters(m_w=NOMINAL_RIM_KG))
    mapping: str = "mapping.toml"


@dataclass(frozen=True)
class Job:
    """What a worker needs to run one test (picklable: paths and frozen dataclasses)."""

    test: BatchTest
    outdir: Path
    partial: Path
    config: BatchConfig
    source_sha256: str


# --------------------------------------------------------------------------- configuration

def load_config(path=None, *, run_overrides: dict | None = None, param_overrides: dict | None = None) -> BatchConfig:
    """A campaign's configuration from a TOML/JSON file and command-line overrides.

    The file has up to three tables: ``[run]`` (the fields of :class:`RunOptions`),
    ``[params]`` (nominal parameters; default the paper's with m_w = 1000 kg) and
    ``[ingest]`` (``mapping``: the mapping file's name inside each UFF/CSV test folder).
    Unknown tables or keys are errors (a misspelt option must not pass silently).
    """
    data = load_mapping(path) if path else {}
    where = str(path) if path else "options"
    unknown = sorted(set(data) - {"run", "params", "ingest"})
    if unknown:
        raise ParameterError(f"{where}: unknown table [{unknown[0]}]; allowed: [run], [params], [ingest]")
    for t in ("run", "params", "ingest"):
        if t in data and not isinstance(data[t], dict):
            raise ParameterError(f"{where}: {t} = {data[t]!r} is not a table; allowed: a [{t}] table")
    run_d = {**dict(data.get("run", {})), **(run_overrides or {})}
    opt = RunOptions.from_mapping(run_d, f"{where} [run]")
    par = {"m_w": NOMINAL_RIM_KG, **dict(data.get("params", {})), **(param_overrides or {})}
    try:
        params = TyreParameters.from_mapping(par)
    except TiremodalError as exc:
        raise ParameterError(f"{where} [params]: {exc}") from None
    ing = dict(data.get("ingest", {}))
    bad = sorted(set(ing) - {"mapping"})
    if bad:
        raise ParameterError(f"{where} [ingest]: unknown option {bad[0]!r}; allowed: mapping")
    if "mapping" in ing and not (isinstance(ing["mapping"], str) and ing["mapping"].strip()
                                 and "/" not in ing["mapping"] and "\\" not in ing["mapping"]):
        raise ParameterError(f"{where} [ingest]: mapping = {ing['mapping']!r}; allowed: a file name (text, no folder)")
    return BatchConfig(run=opt, params=params, mapping=str(ing.get("mapping", "mapping.toml")))


# --------------------------------------------------------------------------- one test (in a worker)

def _read_folder_test(test: BatchTest, mapping_name: str):
    """Ingest a UFF/CSV test folder; tyre and pressure from the mapping's optional [test]."""
    mp = test.path / mapping_name
    mapping = mp if mp.is_file() else None
    meta = dict(load_mapping(mapping).get("test", {})) if mapping else {}
    pressure = meta.get("inflation_pressure")
    return read_source([test.path], test.kind, mapping,
                       inflation_pressure=None if pressure is None else float(pressure),
                       tire=None if meta.get("tire") is None else str(meta["tire"]),
                       description=f"ingested from {test.kind}: {test.path}")


def run_one(job: Job) -> dict:
    """Run one test in a private folder and install it; never raises for a test's failure.

    Returns the test's record (see :func:`record`); status "done" or "failed" with reason.
    BLAS is held to one thread: the batch's parallelism is over tests, and small solves
    run slower multithreaded on the small machines this targets.
    """
    t0 = time.perf_counter()
    job.partial.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f"{job.test.name}.", dir=job.partial))
    os.chmod(tmp, 0o777 & ~UMASK)  # mkdtemp makes 0700; give what mkdir would
    try:
        with threadpool_limits(1):
            meas, mapping = job.test.path, None
            if job.test.kind == "uff" and 4 in uff_function_types(uff_files([job.test.path])):
                # FRFs from another system: the test starts at lsce (pipeline.read_uff_test)
                meas = uff_files([job.test.path])
                mp = job.test.path / job.config.mapping
                mapping = mp if mp.is_file() else None
            elif job.test.kind != "measurement":
                meas = tmp / "measurement.h5"
                write_measurement(meas, _read_folder_test(job.test, job.config.mapping))
            run(meas, tmp, job.config.run, params=job.config.params, mapping=mapping,
                source={"path": str(job.test.path), "kind": job.test.kind, "sha256": job.source_sha256})
        install_dir(tmp, job.outdir, aside=job.partial)
        return record(job.test, "done", outdir=job.outdir, seconds=time.perf_counter() - t0)
    except TiremodalError as exc:
        return record(job.test, "failed", reason=str(exc), seconds=time.perf_counter() - t0)
    except Exception as exc:  # noqa: BLE001 — a bug in one test must not stop the campaign
        return record(job.test, "failed", reason=f"internal error: {type(exc).__name__}: {exc}",
                      seconds=time.perf_counter() - t0)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def record(test: BatchTest, status: str, *, outdir: Path | None = None, reason: str = "", seconds: float = 0.0) -> dict:
    """One test's summary row (nested; :func:`summary_rows` flattens it for CSV).

    From a complete output folder: the manifest's summary and the measured modes (n, branch,
    frequency) from the diagnosis.
    """
    rec = {"test": test.name, "file": str(test.path), "kind": test.kind, "status": status, "reason": reason,
           "seconds": round(float(seconds), 3), "output": str(outdir) if outdir else None}
    if outdir is not None:
        man = read_manifest(outdir) or {}
        s = man.get("summary", {})
        rec.update({k: s.get(k) for k in ("tire", "inflation_pressure", "n_points", "n_hits", "modes_found",
                                          "identified", "rms_error_pct", "adopted_effects", "parameter_off",
                                          "rms_before_pct", "rms_after_pct", "augmented_parameters", "verdict")})
        rec["rejected_hits"] = len(s.get("rejected_hits") or [])
        # whether the test's orders mix (run.json's note, modal.mixing): None where not judged (a table of modes)
        rec["orders_mix"] = bool(s["orders_mix"]) if "orders_mix" in s else None
        rec["pipeline_seconds"] = s.get("seconds")
        try:
            d = json.loads((Path(outdir) / "diagnosis.json").read_text(encoding="utf-8"))
            rec["modes"] = [{"n": m["n"], "branch": m["branch"], "frequency_hz": m["measured_hz"]} for m in d["modes"]]
        except (OSError, ValueError, KeyError):
            rec["modes"] = []
    return rec


# --------------------------------------------------------------------------- the batch

@contextlib.contextmanager
def _lock(outdir: Path):
    """Hold ``OUTDIR/.lock`` (advisory; POSIX) so two batches never write one OUTDIR."""
    try:
        import fcntl  # here, not at the top: POSIX only
    except ImportError:  # not POSIX: no lock
        yield
        return
    fh = open(outdir / LOCK, "a+")
    try:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise ParameterError(f"{outdir}: another batch is writing there (lock {outdir / LOCK})") from None
        # workers of a batch killed with SIGKILL hold this one (shared) until they are gone
        with open(outdir / WORKERS_LOCK, "a+") as wl:
            try:
                fcntl.flock(wl, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                raise ParameterError(f"{outdir}: workers of an earlier batch are still running there "
                                     f"(lock {outdir / WORKERS_LOCK}); try again when they are gone") from None
        yield
    finally:
        fh.close()


def plan(tests: Sequence[BatchTest], outdir: Path, config: BatchConfig, *, force: bool = False):
    """Split the tests into jobs to run and records of tests already complete.

    Returns
    -------
    jobs : list of Job ; done : list of record dicts (status "skipped")
    """
    jobs, done = [], []
    partial = outdir / PARTIAL
    for t in tests:
        try:
            sha = source_sha256(t)
        except OSError as exc:
            done.append(record(t, "failed", reason=f"{t.path}: cannot read ({exc.strerror or exc})"))
            continue
        final = outdir / t.name
        if not force and is_complete(final, opt=config.run, input_sha256=sha, params=config.params):
            done.append(record(t, "skipped", outdir=final))
            continue
        jobs.append(Job(t, final, partial, config, sha))
    return jobs, done


@dataclass
class _Records:
    """The tests' records as they come in, given back in discovery order (``order``: test
    name → its place)."""

    order: dict[str, int]
    by_test: dict[str, dict] = field(default_factory=dict)

    def add(self, rec: dict) -> None:
        self.by_test[rec["test"]] = rec

    @property
    def count(self) -> int:
        return len(self.by_test)

    def in_order(self) -> list[dict]:
        return sorted(self.by_test.values(), key=lambda r: self.order[r["test"]])


def _execute(todo: Sequence[Job], outdir: Path, records: _Records, *, jobs: int, scheduler: str | None,
             progress: Callable[[dict, int], None] | None) -> None:
    """Run the jobs on the executor; after each, its record added, the summary rewritten
    (a killed batch keeps its rows) and ``progress(record, done)`` called."""
    with executor(jobs, scheduler, workers_lock=outdir / WORKERS_LOCK) as ex:
        futures = {ex.submit(run_one, j): j for j in todo}
        for fut in as_completed(futures):
            j = futures[fut]
            try:
                rec = fut.result()
            except Exception as exc:  # noqa: BLE001 — a worker died (killed, out of memory)
                rec = record(j.test, "failed", reason=f"worker lost: {type(exc).__name__}: {exc}")
            records.add(rec)
            write_summary(outdir, records.in_order(), plots=False)  # a killed batch keeps its rows
            if progress:
                progress(rec, records.count)


def run_batch(roots: Sequence, outdir, config: BatchConfig = BatchConfig(), *, jobs: int = 1,
              scheduler: str | None = None, force: bool = False,
              progress: Callable[[dict, int, int], None] | None = None, plots: bool = True) -> list[dict]:
    """Discover, plan, execute and summarise; return the records in discovery order.

    Parameters
    ----------
    roots : folders (or files) to search
    outdir : the batch's output folder (one sub-folder per test, the summary files)
    config : BatchConfig
    jobs, scheduler : see :func:`executor`
    force : redo tests whose outputs are complete
    progress : callable(record, done, total) after each finished test, optional
    plots : write the campaign plots (PNG and SVG)

    Raises
    ------
    ParameterError
        No tests found, a root missing, OUTDIR is a file or locked by another batch.
    """
    outdir = Path(outdir)
    if scheduler:  # a remote worker's working folder is not ours: every path it sees is absolute
        dask_client_class()  # (the optional extra is there: said before any work)
        roots, outdir = [Path(os.path.abspath(r)) for r in roots], Path(os.path.abspath(outdir))
    if outdir.exists() and not outdir.is_dir():
        raise ParameterError(f"{outdir}: exists and is not a folder")
    tests = discover(roots, exclude=[outdir])
    if not tests:
        raise DataFormatError(f"no tests under {', '.join(map(str, roots))}: expected measurement files "
                              "(*.h5) or UFF/CSV test folders")
    outdir.mkdir(parents=True, exist_ok=True)
    with _lock(outdir):
        shutil.rmtree(outdir / PARTIAL, ignore_errors=True)  # debris of a killed batch
        todo, finished = plan(tests, outdir, config, force=force)
        records = _Records({t.name: i for i, t in enumerate(tests)})
        for r in finished:
            records.add(r)
            if progress:
                progress(r, records.count, len(tests))
        if todo:
            _execute(todo, outdir, records, jobs=jobs, scheduler=scheduler,
                     progress=None if progress is None else lambda rec, done: progress(rec, done, len(tests)))
        recs = records.in_order()
        write_summary(outdir, recs, plots=plots)
        shutil.rmtree(outdir / PARTIAL, ignore_errors=True)
    return recs
