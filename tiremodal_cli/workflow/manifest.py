"""A run folder's manifest (``run.json``): provenance, checksums, and whether a folder is complete.
"""

from __future__ import annotations

import datetime
import hashlib
import json
import shlex
import subprocess
import sys
from pathlib import Path

from tiremodal_cli import __version__
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import sha256_file
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.workflow.run_options import MANIFEST, OUTPUTS, RunOptions, json_text, required_outputs

__all__ = ['provenance', 'files_sha256', 'read_manifest', 'verify_manifest', 'is_complete']


_COMMIT: str | None = None


def provenance() -> dict:
    """When and with what a result is made: UTC time, tiremodal's version and git commit (of
    the checkout the package runs from; absent when it is not one, e.g. an installed wheel),
    and the command line (``tiremodal …`` as typed)."""
    out = {"created_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
           "tiremodal_version": __version__}
    global _COMMIT
    if _COMMIT is None:
        _COMMIT = ""
        try:
            here = Path(__file__).resolve().parent
            rev = subprocess.run(["git", "-C", str(here), "rev-parse", "HEAD"], capture_output=True, text=True,
                                 timeout=5)
            # the package's own files must be tracked there: an installed copy inside some
            # other repository's tree (a virtualenv in a project) is not that commit
            tracked = subprocess.run(["git", "-C", str(here), "ls-files", "--error-unmatch", "pipeline.py"],
                                     capture_output=True, text=True, timeout=5)
            if rev.returncode == 0 and tracked.returncode == 0:
                dirty = subprocess.run(["git", "-C", str(here), "status", "--porcelain", "--untracked-files=no"],
                                       capture_output=True, text=True, timeout=5)
                _COMMIT = rev.stdout.strip()[:12] + ("+changes" if dirty.stdout.strip() else "")
        except (OSError, subprocess.SubprocessError):
            pass
    if _COMMIT:
        out["tiremodal_commit"] = _COMMIT
    argv = list(sys.argv)
    prog = Path(argv[0]).name if argv else "tiremodal"
    out["command"] = shlex.join(["tiremodal" if prog in ("tiremodal", "__main__.py") else prog] + argv[1:])
    return out


def files_sha256(paths) -> str:
    """SHA-256 of several files: of their names and checksums, sorted (any change counts)."""
    h = hashlib.sha256()
    for p in sorted(Path(q) for q in paths):
        h.update(f"{p.name}\0{sha256_file(p)}\n".encode())
    return h.hexdigest()


def read_manifest(outdir) -> dict | None:
    """The manifest of a run folder, or None when there is none or it does not parse."""
    try:
        return json.loads((Path(outdir) / MANIFEST).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def verify_manifest(folder, man: dict | None = None) -> dict:
    """The manifest of a run folder after checking every output it lists against its checksum.

    Raises
    ------
    DataFormatError
        No manifest, a manifest that does not parse, or an output missing or changed
        (named, with the expected and the found checksum).
    """
    folder = Path(folder)
    man = read_manifest(folder) if man is None else man
    if man is None:
        raise DataFormatError(f"{folder}: no readable run manifest ({MANIFEST}); run 'tiremodal run' first")
    outs = man.get("outputs") if isinstance(man, dict) else None
    need = required_outputs(man)
    if not isinstance(outs, dict) or not set(need) <= set(outs):
        raise DataFormatError(f"{folder / MANIFEST}: lists no checksums of {', '.join(need)}; "
                              "not a complete run folder")
    for name, h in outs.items():
        p = folder / name
        if not p.is_file():
            raise DataFormatError(f"{p}: missing; the folder does not match its manifest ({MANIFEST})")
        got = sha256_file(p)
        if got != h:
            raise DataFormatError(f"{p}: SHA-256 {got[:12]}… differs from the manifest's {str(h)[:12]}…; "
                                  f"the folder does not match {MANIFEST} (mixed or changed outputs)")
    return man


def is_complete(outdir, measurement=None, opt: RunOptions | None = None, *, input_sha256: str | None = None,
                params: TyreParameters | None = None) -> bool:
    """True when ``outdir`` holds a manifest whose outputs (all of :func:`required_outputs`) exist with
    their checksums and, where given, whose input checksum (of ``measurement``, or
    ``input_sha256``), options and nominal parameters match."""
    outdir = Path(outdir)
    man = read_manifest(outdir)
    try:
        if man is None or not set(required_outputs(man)) <= set(man["outputs"]):
            return False
        if any(sha256_file(outdir / n) != h for n, h in man["outputs"].items()):
            return False
        if measurement is not None and input_sha256 is None:
            input_sha256 = sha256_file(measurement)
        if input_sha256 is not None and input_sha256 not in (man["input_sha256"], man.get("source", {}).get("sha256")):
            return False
        if opt is not None and man["options"] != json.loads(json_text(opt.to_dict())):
            return False
        if params is not None and man["params"] != json.loads(json_text(params.to_dict())):
            return False
        return True
    except (OSError, ValueError, KeyError, TypeError):
        return False
