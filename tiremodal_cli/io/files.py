"""Safe file output: atomic writes, an overwrite guard, checksums.

Every output is written under a temporary name in the target folder and renamed into
place only when complete (``os.replace`` is atomic on POSIX and Windows within one
file system), so an interrupted run never leaves a half-written result behind.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from tiremodal_cli.errors import OutputExistsError, ParameterError

def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: the process's file-creation mask, read once (reading it means setting it: not thread-safe)
UMASK = _umask()

__all__ = ["atomic_path", "check_overwrite", "check_writable", "dumps", "install_dir", "sha256_file", "write_text_atomic",
           "refuse_input_as_output", "path_lock", "check_size", "UMASK"]


def _same_or_inside(out: Path, inp: Path) -> bool:
    """True when ``out`` is ``inp`` (same file, also through links) or lies inside the folder ``inp``."""
    try:
        o, i = out.resolve(), inp.resolve()
    except (OSError, RuntimeError):
        return False
    if o == i or (o.exists() and i.exists() and os.path.samefile(o, i)):
        return True
    return i.is_dir() and i in o.parents


def refuse_input_as_output(outputs, inputs, *, read_from_folder=None) -> None:
    """Refuse an output that is one of the inputs or lies inside an input folder.

    Parameters
    ----------
    outputs : mapping option name → path (None entries ignored), e.g. ``{"-o": out, "--plot": p}``
    inputs : mapping name → path of what the command reads (None entries ignored)
    read_from_folder : callable(path) → bool, optional
        For commands that read a folder's files by pattern (``ingest``): an output inside
        an input folder is then refused only when it exists already (it would replace a
        file of the folder) or the command would read it (it would join the input);
        without it, any output inside an input folder is refused.

    Raises
    ------
    ParameterError
        Naming the option, the path and the input it would replace.
    """
    given = [(opt, Path(out)) for opt, out in outputs.items() if out is not None]
    for i, (opt, out) in enumerate(given):
        for opt2, out2 in given[:i]:
            if out.resolve() == out2.resolve():
                raise ParameterError(f"{opt} {str(out)!r} is also {opt2}; allowed: a different file for each output")
        for what, inp in inputs.items():
            if inp is None:
                continue
            if _same_or_inside(Path(out), Path(inp)):
                if (read_from_folder is not None and Path(inp).is_dir() and not Path(out).exists()
                        and not read_from_folder(Path(out))):
                    continue
                rel = "is" if Path(out).resolve() == Path(inp).resolve() else "is inside"
                raise ParameterError(f"{opt} {str(out)!r} {rel} the input {what} {str(inp)!r}; "
                                     "an input is never replaced: choose another output")


@contextlib.contextmanager
def path_lock(lock: str | os.PathLike, what: str) -> Iterator[None]:
    """Hold an exclusive advisory lock on the file ``lock`` (created; removed on release).

    Refuses at once (ParameterError naming ``what``) when another process holds it. The
    lock file is removed on release; a process that opened the file before the removal
    sees that its inode is gone and tries again, so two holders never coexist.
    """
    try:
        import fcntl  # here, not at the top: POSIX only (absent on Windows)
    except ImportError:  # not POSIX: no lock
        yield
        return
    lock = Path(lock)
    while True:
        fh = open(lock, "a+")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            fh.close()
            raise ParameterError(f"{what}: another process is writing there (lock {lock})") from None
        try:
            same = os.fstat(fh.fileno()).st_ino == os.stat(lock).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        fh.close()  # removed by the holder we waited on: take the new one
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            lock.unlink()
        fh.close()


#: memory a command may plan to hold at once before it refuses (bytes): a quarter of the
#: machine's physical memory, at most 8 GiB, so one job never takes the machine.
def memory_budget() -> int:
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        total = 8 << 30
    return int(min(total // 4, 8 << 30))


def check_size(nbytes: float, what: str, limit: int | None = None) -> None:
    """Refuse a planned allocation of ``nbytes`` larger than the memory budget, in one line
    naming ``what`` (the option(s) and values that set it)."""
    limit = memory_budget() if limit is None else limit
    if not nbytes <= limit:
        raise ParameterError(f"{what} needs about {nbytes / 2**30:.3g} GiB of memory; "
                             f"allowed: at most {limit / 2**30:.3g} GiB (a quarter of this machine's memory, ≤ 8 GiB)")


def check_overwrite(path: str | os.PathLike, overwrite: bool) -> Path:
    """Refuse an existing output unless ``overwrite`` is true, and an output that cannot be
    written (:func:`check_writable`); return the path. Commands call it for every output
    before any work, so that a bad second output never leaves the first one written."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise OutputExistsError(f"output {str(path)!r} exists; pass --overwrite to replace it")
    check_writable(path)
    return path


def check_writable(path: str | os.PathLike) -> None:
    """Refuse an output whose folder cannot be made or written: the nearest existing
    ancestor must be a folder in which a file can be created (probed with a temporary file,
    removed at once: permissions alone do not tell, e.g. for root or a read-only mount)."""
    path = Path(path).absolute()
    folder = path.parent
    while not folder.exists():
        folder = folder.parent
    if not folder.is_dir():
        raise ParameterError(f"output {str(path)!r}: {str(folder)!r} is a file, not a folder; "
                             "allowed: a path in a folder (existing or new)")
    try:
        fd, probe = tempfile.mkstemp(prefix=".tiremodal-probe.", dir=folder)
    except OSError as exc:
        raise ParameterError(f"output {str(path)!r}: cannot write in {str(folder)!r} ({exc.strerror}); "
                             "allowed: a folder you can write") from None
    os.close(fd)
    os.unlink(probe)


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike, *, overwrite: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it into place on success.

    The target's folder is created if missing. On any exception the temporary file is
    removed and ``target`` is left untouched.
    """
    target = check_overwrite(target, overwrite)
    folder = target.parent if str(target.parent) else Path(".")
    if folder.exists() and not folder.is_dir():
        raise ParameterError(f"output folder {str(folder)!r} is not a folder")
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=folder)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        os.chmod(tmp_path, 0o666 & ~UMASK)  # mkstemp makes 0600; give what open() would
        os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def install_dir(tmp: str | os.PathLike, final: str | os.PathLike, *, aside: str | os.PathLike | None = None) -> Path:
    """Rename the finished folder ``tmp`` to ``final``. An existing ``final`` is first moved
    into a fresh folder under ``aside`` (default: beside it) and removed after, so at every
    instant ``final`` is the old complete folder, absent, or the new one — never a mix."""
    tmp, final = Path(tmp), Path(final)
    old = None
    if final.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{final.name}.old.", dir=aside or final.parent))
        os.replace(final, old / "x")
    os.replace(tmp, final)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
    return final


def write_text_atomic(target: str | os.PathLike, text: str, *, overwrite: bool = False) -> Path:
    """Write ``text`` (UTF-8) to ``target`` atomically; return the target path."""
    with atomic_path(target, overwrite=overwrite) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(target)


def sha256_file(path: str | os.PathLike, *, chunk: int = 1 << 20) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while block := fh.read(chunk):
            h.update(block)
    return h.hexdigest()


def _default(o):
    import numpy as np  # start-up time: the CLI imports this module, `tiremodal --help` runs without numpy

    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        return float(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, (set, tuple)):
        return list(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def dumps(obj) -> str:
    """JSON text of ``obj`` (numpy scalars and arrays allowed; NaN refused)."""
    return json.dumps(obj, indent=2, default=_default, allow_nan=False) + "\n"
