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
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import OutputExistsError, ParameterError

def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _umask()

__all__ = ["atomic_path", "check_overwrite", "dumps", "install_dir", "sha256_file", "write_text_atomic"]


def check_overwrite(path: str | os.PathLike, overwrite: bool) -> Path:
    """Refuse an existing output unless ``overwrite`` is true; return the path."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise OutputExistsError(f"output {str(path)!r} exists; pass --overwrite to replace it")
    return path


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
        os.chmod(tmp_path, 0o666 & ~_UMASK)  # mkstemp makes 0600; give what open() would
        os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def install_dir(tmp: str | os.PathLike, final: str | os.PathLike, *, aside: str | os.PathLike | None = None) -> Path:
    """Rename the finished folder ``tmp`` to ``final``. An existing ``final`` is first moved
    into a fresh folder under ``aside`` (default: beside it) and removed after, so at every
    instant ``final`` is the old complete folder, absent, or the new one — never a mix."""
    import shutil

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
    import numpy as np

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
