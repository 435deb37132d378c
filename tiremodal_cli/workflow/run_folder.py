"""``run`` made atomic: a run folder written aside and installed whole, under a lock.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from tiremodal_cli.errors import OutputExistsError
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.io.files import UMASK, check_writable, install_dir, path_lock, refuse_input_as_output, sha256_file
from tiremodal_cli.io.frfuff import is_uff
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.workflow.pipeline import is_modes_table, run
from tiremodal_cli.workflow.run_options import MANIFEST, OUTPUTS, RunOptions

__all__ = ['run_folder']


#: views of a run folder that ``report`` writes; a new run does not carry them over (stale)
_VIEWS = ("report.html", "figures")


def _link_or_copy(src: str, dst: str) -> None:

    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def run_folder(measurement, outdir, opt: RunOptions = RunOptions(), *, params: TyreParameters | None = None,
               progress=None, overwrite: bool = False, mapping=None) -> dict:
    """:func:`run` made atomic: the outputs are written into a private folder beside
    ``outdir`` (``.NAME.partial.*``) and the folder is installed whole
    (:func:`~tiremodal_cli.io.files.install_dir`), under a lock (``.NAME.lock`` beside it).

    At every instant ``outdir`` is the complete old folder, absent, or the complete new one:
    an error or a kill leaves at most debris under ``.NAME.partial.*``/``.NAME.old.*``,
    removed by the next run into ``outdir``. Files of the old folder that are not run
    outputs (the measurement itself when it lies there, notes) are carried into the new
    one (hard links where possible); the report's views (report.html, figures/) are not.
    ``measurement`` may be a UFF file of FRFs (with an optional ``mapping``: see :func:`run`).

    Parameters
    ----------
    measurement, outdir, opt, params, progress, mapping : as for :func:`run`
    overwrite : bool
        Replace the outputs of an earlier run in ``outdir``.

    Returns
    -------
    dict
        The summary, as :func:`run`.

    Raises
    ------
    OutputExistsError : outputs exist in ``outdir`` and ``overwrite`` is false
    ParameterError : ``outdir`` is the measurement, or is a file, or another run holds its lock
    """
    measurement, outdir = Path(measurement), Path(outdir)
    refuse_input_as_output({"--output": outdir}, {"measurement": measurement,
                                                  **({"--mapping": Path(mapping)} if mapping else {})})
    if outdir.exists() and not outdir.is_dir():
        raise ParameterError(f"--output {str(outdir)!r} exists and is not a folder")
    if not measurement.is_file():
        raise DataFormatError(f"{measurement}: no such file")
    parent = outdir.parent
    check_writable(outdir)  # (a folder under a file, or one that cannot be written: exit 2, one line)
    parent.mkdir(parents=True, exist_ok=True)
    with path_lock(parent / f".{outdir.name}.lock", f"--output {str(outdir)!r}"):
        existing = [n for n in (*OUTPUTS, MANIFEST) if (outdir / n).exists()]
        if existing and not overwrite:
            raise OutputExistsError(f"output {str(outdir / existing[0])!r} exists; pass --overwrite to replace it")
        for debris in [*parent.glob(f".{outdir.name}.partial.*"), *parent.glob(f".{outdir.name}.old.*")]:
            shutil.rmtree(debris, ignore_errors=True)  # of a killed run (we hold the lock)
        tmp = Path(tempfile.mkdtemp(prefix=f".{outdir.name}.partial.", dir=parent))
        os.chmod(tmp, 0o777 & ~UMASK)
        try:
            meas = _carry_over(outdir, tmp, measurement)
            sha = sha256_file(measurement)
            kind = "uff-frf" if is_uff(measurement) else "modes-table" if is_modes_table(measurement) else "measurement"
            summary = run(meas, tmp, opt, params=params, progress=progress, mapping=mapping,
                          source={"path": str(measurement), "kind": kind, "sha256": sha})
            install_dir(tmp, outdir, aside=parent)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    return summary


def _carry_over(outdir: Path, tmp: Path, measurement: Path) -> Path:
    """Files of the old folder that are not run outputs or views, linked (or copied) into
    the new one; returns where the measurement is to be read from."""
    if not outdir.is_dir():
        return measurement
    for entry in outdir.iterdir():
        if entry.name in (*OUTPUTS, MANIFEST, *_VIEWS):
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.copytree(entry, tmp / entry.name, symlinks=True, copy_function=_link_or_copy)
        else:
            _link_or_copy(str(entry), str(tmp / entry.name))
    return tmp / measurement.name if measurement.resolve().parent == outdir.resolve() else measurement
