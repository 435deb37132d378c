"""``batch``'s first step: every test found under some folders, and its input's checksum.

A test is a measurement file, or a UFF/CSV folder that ``ingest`` reads as one test; its
name is its path under the root (the name of its output folder).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import h5py

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.io.files import sha256_file
from tiremodal_cli.io.ingest import test_folder_kind

__all__ = ["BatchTest", "discover", "source_sha256", "MEASUREMENT_SUFFIXES"]

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


def _is_output_file(path: Path) -> bool:
    """True for a readable HDF5 file that tiremodal wrote as a stage output (frf, modal)."""
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
