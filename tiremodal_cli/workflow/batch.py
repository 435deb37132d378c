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
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import hashlib
import json
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from tiremodal_cli.errors import DataFormatError, ParameterError, TiremodalError
from tiremodal_cli.io.files import _UMASK, dumps, install_dir, sha256_file, write_text_atomic
from tiremodal_cli.io.ingest import test_folder_kind
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.workflow.manifest import is_complete, read_manifest
from tiremodal_cli.workflow.pipeline import run
from tiremodal_cli.workflow.run_options import RunOptions

__all__ = ["BatchTest", "Job", "BatchConfig", "discover", "load_config", "plan", "run_one", "executor", "run_batch",
           "summary_rows", "write_summary", "read_summary", "SUMMARY_CSV", "SUMMARY_JSONL", "PARTIAL"]

SUMMARY_CSV = "summary.csv"
SUMMARY_JSONL = "summary.jsonl"
PARTIAL = ".partial"
LOCK = ".lock"
WORKERS_LOCK = ".lock.workers"
MEASUREMENT_SUFFIXES = (".h5", ".hdf5", ".hdf")
#: tiremodal's own outputs: found under a tree, they are not tests
_OUTPUT_FORMATS = ("tiremodal.frf", "tiremodal.modal")


@dataclass(frozen=True)
class BatchTest:
    """One test: a measurement file (kind "measurement") or a UFF/CSV folder (kind "uff"/"csv").

    name : the output folder's name under OUTDIR (the path under its root, "/" → "__")
    """

    name: str
    path: Path
    kind: str


@dataclass(frozen=True)
class BatchConfig:
    """Everything a campaign passes to each test.

    run : RunOptions of every stage
    params : nominal model parameters (identify's and diagnose's start)
    mapping : name of the mapping file looked for in each UFF/CSV test folder
    """

    run: RunOptions = field(default_factory=RunOptions)
    params: TyreParameters = field(default_factory=lambda: TyreParameters(m_w=1000.0))
    mapping: str = "mapping.toml"


@dataclass(frozen=True)
class Job:
    """What a worker needs to run one test (picklable: paths and frozen dataclasses)."""

    test: BatchTest
    outdir: Path
    partial: Path
    config: BatchConfig
    source_sha256: str


# --------------------------------------------------------------------------- discovery

def _is_output_file(path: Path) -> bool:
    """True for a readable HDF5 file that tiremodal wrote as a stage output (frf, modal)."""
    import h5py

    try:
        with h5py.File(path, "r") as h:
            fmt = h.attrs.get("format")
    except OSError:
        return False  # unreadable: a test that will fail with its reason
    fmt = fmt.decode() if isinstance(fmt, bytes) else fmt
    return fmt in _OUTPUT_FORMATS


def discover(roots: Sequence, *, exclude: Sequence = ()) -> list[BatchTest]:
    """Every test under ``roots`` (files or folders), in a stable order.

    A test is a measurement file (``*.h5``, ``*.hdf5``, ``*.hdf``; tiremodal's own FRF and
    modal files are passed over) or a folder that ``ingest`` reads as one test (``point*.csv``
    files, or ``*.uff``/``*.unv`` files; its sub-folders are not searched). Hidden folders
    and the ``exclude`` folders (the batch's own output) are not searched.

    Raises ParameterError when a root does not exist.
    """
    roots = [Path(r) for r in roots]
    excl = {Path(e).resolve() for e in exclude}
    found: list[tuple[str, Path, str]] = []
    for root in roots:
        if not root.exists():
            raise ParameterError(f"{root}: no such file or folder")
        if root.is_file():
            found.append((root.stem, root, "measurement"))
            continue
        prefix = [root.resolve().name] if len(roots) > 1 else []
        for folder, dirs, files in os.walk(root):
            folder = Path(folder)
            dirs[:] = sorted(d for d in dirs if not d.startswith(".") and (folder / d).resolve() not in excl)
            rel = folder.relative_to(root).parts
            kind = test_folder_kind(folder)
            if kind is not None:
                found.append(("__".join(prefix + list(rel)) or root.resolve().name, folder, kind))
                dirs[:] = []
                continue
            for f in sorted(files):
                p = folder / f
                if p.suffix.lower() in MEASUREMENT_SUFFIXES and not f.startswith(".") and not _is_output_file(p):
                    found.append(("__".join(prefix + list(rel) + [p.stem]), p, "measurement"))
    tests, seen = [], {}
    for name, path, kind in found:
        k = seen.get(name, 0)
        seen[name] = k + 1
        tests.append(BatchTest(name if k == 0 else f"{name}-{k + 1}", path, kind))
    return tests


def source_sha256(test: BatchTest) -> str:
    """Checksum of a test's input: the file's SHA-256, or for a folder the SHA-256 of its
    files' names and checksums (sorted), so any changed, added or removed file counts."""
    if test.kind == "measurement":
        return sha256_file(test.path)
    h = hashlib.sha256()
    for p in sorted(q for q in test.path.iterdir() if q.is_file() and not q.name.startswith(".")):
        h.update(f"{p.name}\0{sha256_file(p)}\n".encode())
    return h.hexdigest()


# --------------------------------------------------------------------------- configuration

def load_config(path=None, *, run_overrides: dict | None = None, param_overrides: dict | None = None) -> BatchConfig:
    """A campaign's configuration from a TOML/JSON file and command-line overrides.

    The file has up to three tables: ``[run]`` (the fields of :class:`RunOptions`),
    ``[params]`` (nominal parameters; default the paper's with m_w = 1000 kg) and
    ``[ingest]`` (``mapping``: the mapping file's name inside each UFF/CSV test folder).
    Unknown tables or keys are errors (a misspelt option must not pass silently).
    """
    from tiremodal_cli.io.config import load_mapping

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
    par = {"m_w": 1000.0, **dict(data.get("params", {})), **(param_overrides or {})}
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
    from tiremodal_cli.io.config import load_mapping
    from tiremodal_cli.io.ingest import read_source

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
    from threadpoolctl import threadpool_limits

    from tiremodal_cli.io.frffile import uff_function_types
    from tiremodal_cli.io.ingest.uff import uff_files
    from tiremodal_cli.io.measurement import write_measurement

    t0 = time.perf_counter()
    job.partial.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f"{job.test.name}.", dir=job.partial))
    os.chmod(tmp, 0o777 & ~_UMASK)  # mkdtemp makes 0700; give what mkdir would
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
        rec["pipeline_seconds"] = s.get("seconds")
        try:
            d = json.loads((Path(outdir) / "diagnosis.json").read_text(encoding="utf-8"))
            rec["modes"] = [{"n": m["n"], "branch": m["branch"], "frequency_hz": m["measured_hz"]} for m in d["modes"]]
        except (OSError, ValueError, KeyError):
            rec["modes"] = []
    return rec


# --------------------------------------------------------------------------- executors

class SerialExecutor(cf.Executor):
    """Runs each job in this process when submitted (``--jobs 1``: no pool to start)."""

    def submit(self, fn, /, *args, **kwargs):
        f = cf.Future()
        try:
            f.set_result(fn(*args, **kwargs))
        except BaseException as exc:  # noqa: BLE001 — handed to the caller through the future
            f.set_exception(exc)
            if isinstance(exc, KeyboardInterrupt):
                raise
        return f


_WORKER_LOCK = None  # a worker's shared lock on OUTDIR/.lock.workers (held for its life)


def _die_with(parent_pid: int) -> None:
    """Make this process end when ``parent_pid`` (the batch) ends, even by SIGKILL.

    On Linux, PR_SET_PDEATHSIG asks the kernel for SIGKILL when the parent (the
    forkserver, which exits at once when the batch does) dies; everywhere, a daemon
    thread checks every 0.2 s that the batch is alive and ends the worker when not.
    """
    import sys
    import threading

    if sys.platform.startswith("linux"):
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            PR_SET_PDEATHSIG = 1
            libc.prctl(PR_SET_PDEATHSIG, 9, 0, 0, 0)  # SIGKILL
        except (OSError, AttributeError):  # no libc prctl: the thread below still watches
            pass

    def watch():
        while True:
            try:
                os.kill(parent_pid, 0)
            except ProcessLookupError:
                os._exit(137)
            except PermissionError:  # alive, another user's (cannot happen for our parent)
                pass
            time.sleep(0.2)

    threading.Thread(target=watch, name="tiremodal-parent-watch", daemon=True).start()


def _worker_init(parent_pid: int, workers_lock: str | None) -> None:
    """A pool worker's start: die with the batch; hold a shared lock on ``workers_lock``
    so that no other batch takes OUTDIR while this worker lives (see :func:`_lock`)."""
    global _WORKER_LOCK
    _die_with(parent_pid)
    if workers_lock is not None:
        try:
            import fcntl
        except ImportError:
            return
        _WORKER_LOCK = open(workers_lock, "a+")
        fcntl.flock(_WORKER_LOCK, fcntl.LOCK_SH)


@contextlib.contextmanager
def executor(jobs: int = 1, scheduler: str | None = None, *, workers_lock=None) -> Iterator[cf.Executor]:
    """A ``concurrent.futures.Executor`` for the jobs.

    scheduler : address of a Dask scheduler (``tcp://host:8786``): the jobs go to its
        workers through ``distributed.Client.get_executor()``. The workers must see the
        same paths (a shared file system) and have tiremodal installed.
    jobs : local worker processes when no scheduler is given (1: in this process).
    workers_lock : a file each local worker holds a shared lock on while it lives (the batch
        takes it exclusively before it starts: a batch killed with SIGKILL keeps its OUTDIR
        locked until its workers are gone). Local workers end with the batch, also when it
        is killed with SIGKILL (:func:`_die_with`).
    """
    if scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise ParameterError("--scheduler needs dask.distributed: pip install 'tiremodal[dask]'") from None
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as exc:
            raise ParameterError(f"--scheduler {scheduler}: cannot connect ({exc})") from None
        try:
            yield client.get_executor(pure=False)
        finally:
            client.close()
        return
    if jobs < 1:
        raise ParameterError(f"--jobs {jobs}: must be at least 1")
    if jobs == 1:
        yield SerialExecutor()
        return
    import multiprocessing as mp

    # forkserver: workers start from a clean process (no inherited BLAS or lock state)
    pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("forkserver"),
                                  initializer=_worker_init,
                                  initargs=(os.getpid(), None if workers_lock is None else str(workers_lock)))
    try:
        yield pool
    except BaseException:
        # interrupted: stop now, not after the jobs already queued to the workers
        stop = getattr(pool, "terminate_workers", None)  # Python ≥ 3.14
        if stop is not None:
            stop()
        else:  # before 3.14: the pool's processes (shutdown forgets them, so take them first)
            procs = list((getattr(pool, "_processes", None) or {}).values())
            pool.shutdown(wait=False, cancel_futures=True)
            for proc in procs:
                proc.terminate()
        raise
    else:
        pool.shutdown(wait=True)


# --------------------------------------------------------------------------- the batch

@contextlib.contextmanager
def _lock(outdir: Path):
    """Hold ``OUTDIR/.lock`` (advisory; POSIX) so two batches never write one OUTDIR."""
    try:
        import fcntl
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
        order = {t.name: i for i, t in enumerate(tests)}
        results = {r["test"]: r for r in finished}
        total = len(tests)

        def sorted_records():
            return sorted(results.values(), key=lambda r: order[r["test"]])

        for i, r in enumerate(finished):
            if progress:
                progress(r, i + 1, total)
        if todo:
            with executor(jobs, scheduler, workers_lock=outdir / WORKERS_LOCK) as ex:
                futures = {ex.submit(run_one, j): j for j in todo}
                for fut in cf.as_completed(futures):
                    j = futures[fut]
                    try:
                        rec = fut.result()
                    except Exception as exc:  # noqa: BLE001 — a worker died (killed, out of memory)
                        rec = record(j.test, "failed", reason=f"worker lost: {type(exc).__name__}: {exc}")
                    results[rec["test"]] = rec
                    write_summary(outdir, sorted_records(), plots=False)  # a killed batch keeps its rows
                    if progress:
                        progress(rec, len(results), total)
        recs = sorted_records()
        write_summary(outdir, recs, plots=plots)
        shutil.rmtree(outdir / PARTIAL, ignore_errors=True)
    return recs


# --------------------------------------------------------------------------- summary

_SCALARS = ("test", "file", "kind", "status", "reason", "tire", "inflation_pressure", "n_points", "n_hits",
            "rejected_hits", "modes_found")
_TAIL = ("adopted_effects", "parameter_off", "rms_error_pct", "rms_before_pct", "rms_after_pct", "verdict",
         "seconds", "output")


def summary_rows(records: Sequence[dict]) -> tuple[list[dict], list[str]]:
    """Flat rows for the CSV: identified parameters as ``NAME`` and ``NAME_std_error``
    columns, effect parameters of the final model as ``EFFECT.PARAM``, lists joined by ";".

    Returns rows and the column names (the union over the tests, in a stable order).
    """
    pcols, ecols = [], []
    for r in records:
        for k in (r.get("identified") or {}):
            if k not in pcols:
                pcols.append(k)
        for k in (r.get("augmented_parameters") or {}):
            if "." in k and k not in ecols:
                ecols.append(k)
    cols = list(_SCALARS) + [c for k in pcols for c in (k, f"{k}_std_error")] + ecols + list(_TAIL)
    rows = []
    for r in records:
        row = {k: r.get(k) for k in _SCALARS + _TAIL}
        for k in ("adopted_effects", "parameter_off"):
            row[k] = ";".join(r.get(k) or [])
        for k, v in (r.get("identified") or {}).items():
            row[k], row[f"{k}_std_error"] = v.get("value"), v.get("std_error")
        for k in ecols:
            v = (r.get("augmented_parameters") or {}).get(k)
            row[k] = v.get("value") if isinstance(v, dict) else v
        rows.append({k: ("" if row.get(k) is None else row.get(k)) for k in cols})
    return rows, cols


def write_summary(outdir, records: Sequence[dict], *, plots: bool = True) -> list[Path]:
    """Write ``summary.csv``, ``summary.jsonl`` and (``plots``) the campaign figures, each
    atomically. Returns the paths written."""
    from tiremodal_cli.cli.options import rows_to_csv

    outdir = Path(outdir)
    rows, cols = summary_rows(records)
    out = [write_text_atomic(outdir / SUMMARY_CSV, rows_to_csv(rows, cols), overwrite=True),
           write_text_atomic(outdir / SUMMARY_JSONL, "".join(dumps(r).replace("\n", "") + "\n" for r in records),
                             overwrite=True)]
    if plots and any(r["status"] in ("done", "skipped") for r in records):
        from tiremodal_cli.plots import plot_campaign_frequencies, plot_campaign_parameters, save_figure

        for name, make in (("campaign_parameters", plot_campaign_parameters),
                           ("campaign_frequencies", plot_campaign_frequencies)):
            for ext in ("png", "svg"):
                save_figure(make(records), outdir / f"{name}.{ext}", overwrite=True)
                out.append(outdir / f"{name}.{ext}")
    return out


def read_summary(outdir) -> list[dict]:
    """The records of a batch (``summary.jsonl``)."""
    p = Path(outdir) / SUMMARY_JSONL
    try:
        return [json.loads(line) for line in p.read_text(encoding="utf-8").splitlines() if line.strip()]
    except OSError:
        raise DataFormatError(f"{outdir}: no batch summary ({SUMMARY_JSONL}); run 'tiremodal batch' first") from None
    except ValueError as exc:
        raise DataFormatError(f"{p}: not JSON lines ({exc})") from None

