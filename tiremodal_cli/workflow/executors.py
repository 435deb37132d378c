"""Where ``batch``'s jobs run: in this process, a local process pool, or a Dask cluster, all
through the ``concurrent.futures.Executor`` interface; local workers end with the batch."""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ctypes
import multiprocessing as mp
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator

from tiremodal_cli.errors import ParameterError

__all__ = ["SerialExecutor", "as_completed", "dask_client_class", "executor"]


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
    if sys.platform.startswith("linux"):
        try:
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
    """A pool worker's start: die with the batch; ignore Ctrl-C; hold a shared lock on
    ``workers_lock`` so that no other batch takes OUTDIR while this worker lives.

    Ctrl-C reaches the terminal's whole process group. A worker that took it would raise
    KeyboardInterrupt wherever it happened to be, also inside a garbage collector's weakref
    callback, where Python prints "Exception ignored ... Traceback" to the shared stderr.
    The batch alone answers Ctrl-C: it ends its workers (:func:`_stop`).
    """
    global _WORKER_LOCK
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with(parent_pid)
    if workers_lock is not None:
        try:
            import fcntl  # here, not at the top: POSIX only
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
        with _dask_executor(scheduler) as ex:
            yield ex
        return
    if jobs < 1:
        raise ParameterError(f"--jobs {jobs}: must be at least 1")
    if jobs == 1:
        yield SerialExecutor()
        return
    # forkserver: workers start from a clean process (no inherited BLAS or lock state)
    pool = cf.ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("forkserver"),
                                  initializer=_worker_init,
                                  initargs=(os.getpid(), None if workers_lock is None else str(workers_lock)))
    try:
        yield pool
    except BaseException:
        _stop(pool)  # interrupted: stop now, not after the jobs already queued to the workers
        raise
    else:
        pool.shutdown(wait=True)


def as_completed(futures, *, poll_s: float = 0.1) -> Iterator[cf.Future]:
    """The futures as they finish (``concurrent.futures.as_completed``), with Ctrl-C raised
    here, between results, as KeyboardInterrupt.

    While it waits, SIGINT only sets a flag (in the main thread; elsewhere the handler
    cannot be set and Ctrl-C acts as usual). Python's own handler raises KeyboardInterrupt
    at whatever line runs, and a line inside a weakref callback swallows it with a printed
    traceback; here it comes from one place, at most ``poll_s`` (s) after the signal.
    """
    pending = set(futures)
    if threading.current_thread() is not threading.main_thread():
        yield from cf.as_completed(pending)
        return
    hit: list[int] = []  # a list, not an Event: the handler takes no lock
    old = signal.signal(signal.SIGINT, lambda signum, frame: hit.append(signum))
    try:
        while pending:
            done, pending = cf.wait(pending, timeout=poll_s, return_when=cf.FIRST_COMPLETED)
            for fut in done:
                if hit:
                    raise KeyboardInterrupt
                yield fut
            if hit:
                raise KeyboardInterrupt
    finally:
        signal.signal(signal.SIGINT, old)


def dask_client_class():
    """``distributed.Client``, or a clear error when the optional [dask] extra is missing
    (``batch`` asks before any work)."""
    try:
        from distributed import Client  # here, not at the top: an optional dependency (the [dask] extra)
    except ImportError:
        raise ParameterError("--scheduler needs dask.distributed: pip install 'tiremodal[dask]'") from None
    return Client


@contextlib.contextmanager
def _dask_executor(scheduler: str) -> Iterator[cf.Executor]:
    """The executor of a Dask cluster's workers (``distributed.Client.get_executor()``)."""
    Client = dask_client_class()
    try:
        client = Client(scheduler, timeout="10s")
    except (OSError, TimeoutError) as exc:
        raise ParameterError(f"--scheduler {scheduler}: cannot connect ({exc})") from None
    try:
        yield client.get_executor(pure=False)
    finally:
        client.close()


def _stop(pool: cf.ProcessPoolExecutor) -> None:
    """End a local pool's workers now, the jobs queued to them dropped."""
    stop = getattr(pool, "terminate_workers", None)  # Python ≥ 3.14
    if stop is not None:
        stop()
    else:  # before 3.14: the pool's processes (shutdown forgets them, so take them first)
        procs = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for proc in procs:
            proc.terminate()
