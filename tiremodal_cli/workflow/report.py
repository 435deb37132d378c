"""``report``: a self-contained HTML page per test, and an index page for a batch.

A run folder (``run.json`` and the stage outputs) becomes ``report.html`` — every figure
embedded as a base64 PNG, the styles inline, no link outside the file — and the same
figures as PNG and SVG files in ``figures/``. A batch folder (``summary.jsonl``) gets a
report for each test that has outputs and an ``index.html``: the campaign table with each
test's status or reason, links to the tests' reports, and the campaign figures.

Figures come from :mod:`tiremodal_cli.plots`; this module only reads the outputs, lays
them out and writes (atomically: the figure folder is built aside and renamed into place).
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from tiremodal_cli import names, plots
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.export import shape_set
from tiremodal_cli.io.files import UMASK, install_dir, write_text_atomic
from tiremodal_cli.io.frffile import read_frf
from tiremodal_cli.io.modalfile import read_modal
from tiremodal_cli.workflow.html import escape, img, number, page, render
from tiremodal_cli.workflow.manifest import read_manifest, verify_manifest
from tiremodal_cli.workflow.run_options import MANIFEST
from tiremodal_cli.workflow.run_page import FIGURES, footer, run_body
from tiremodal_cli.workflow.summary import SUMMARY_JSONL, read_summary

__all__ = ["FIGURES", "report_run", "report_batch", "report", "REPORT_HTML", "INDEX_HTML"]

REPORT_HTML = "report.html"
INDEX_HTML = "index.html"
FIGURE_DIR = "figures"


def _figure_folder(parent: Path) -> Path:
    """A new private folder in ``parent`` to build a figure folder in (made as mkdir would)."""
    tmp = Path(tempfile.mkdtemp(prefix=f".{FIGURE_DIR}.", dir=parent))
    os.chmod(tmp, 0o777 & ~UMASK)  # mkdtemp makes 0700
    return tmp


def _load_json(path: Path) -> dict:
    """A run's JSON output; DataFormatError when missing or not JSON."""
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataFormatError(f"{path}: missing; the run folder is incomplete (re-run it)") from None
    except ValueError as exc:
        raise DataFormatError(f"{path}: not JSON ({exc})") from None


def _figures(folder: Path, man: dict, ident: dict, diag: dict, sens: dict) -> dict[str, Callable]:
    """Callables making each figure of :data:`FIGURES` from the run folder's outputs (a run
    that started at identify, on a table of modes, has no FRF or modal figures)."""
    from_modes = man.get("summary", {}).get("starts_at") == "identify"
    r = None if from_modes else read_frf(folder / "frf.h5")
    table = None if from_modes else read_modal(folder / "modal.h5")

    def fit():
        ax = plots.plot_dispersion(ident["predictions"], measured=ident["modes"])
        ax.set_title(f"identified model (RMS error {ident['rms_error_pct']:.3f} %)")
        return ax.figure

    def predictions():
        aug = diag["predictions"]["augmented"]
        ax = plots.plot_dispersion(aug, measured=[{"n": m["n"], "branch": m["branch"], "measured_hz": m["measured_hz"]}
                                                  for m in diag["modes"]])
        ax.set_title("final model: " + (", ".join(diag["adopted_effects"] + diag["parameter_off"]) or "no effect added"))
        return ax.figure

    def sensitivity():
        c = sens["coefficients"]
        S = np.array([[row[k] for k in sens["names"]] for row in c])
        return plots.plot_sensitivity([row["n"] for row in c], [row["branch"] for row in c], S,
                                      sens["names"])[0].figure

    model = {
        "fit": fit,
        "convergence": lambda: plots.plot_convergence([(h["generation"], h["rms_error_pct"] / 100)
                                                       for h in ident["history"]]).figure,
        "residuals": lambda: plots.plot_residuals(diag["modes"]),
        "predictions": predictions,
        "sensitivity": sensitivity,
    }
    if from_modes:
        return model
    n_p = r.point_angle.size
    return {
        "frf": lambda: plots.plot_frf(r, points=sorted({0, n_p // 4}))[0].figure,
        "stabilization": lambda: plots.stabilization_figure(table, r),
        "mac": lambda: plots.automac_figure(table),
        "shapes": lambda: plots.plot_shapes(table),
        "synthesis": lambda: plots.synthesis_figure(table, r),
        **model,
    }


def report_run(folder, *, progress: Callable[[str], None] | None = None) -> Path:
    """Write ``folder/report.html`` and ``folder/figures/*.png|svg`` for one run folder.

    Returns the report's path. Raises DataFormatError when the folder is not a complete run.
    """
    folder = Path(folder)
    man = read_manifest(folder)
    if man is None or man.get("format") != "tiremodal.run":
        raise DataFormatError(f"{folder}: no run manifest ({MANIFEST}); run 'tiremodal run' or 'batch' first")
    verify_manifest(folder, man)  # a folder mixing two runs, or changed since, is refused
    ident = _load_json(folder / "identify.json")
    diag = _load_json(folder / "diagnosis.json")
    sens = _load_json(folder / "sensitivity.json")
    makers = _figures(folder, man, ident, diag, sens)
    tmp = _figure_folder(folder)
    try:
        pngs = {}
        for stem, _ in FIGURES:
            if stem not in makers:
                continue
            if progress:
                progress(stem)
            pngs[stem] = render(makers[stem](), tmp, stem)
        if progress:
            progress("mode animations")
        gifs = _mode_gifs(folder, tmp)
        body = run_body(folder, man, ident, diag, pngs, gifs)
        html_text = page(f"tiremodal report: {man['summary']['measurement']}", body, footer(man))
        install_dir(tmp, folder / FIGURE_DIR)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return write_text_atomic(folder / REPORT_HTML, html_text, overwrite=True)


def _mode_gifs(folder: Path, figdir: Path) -> list[tuple[str, bytes]]:
    """Each mode moving (tread, sidewall and rim rings in the tyre's plane), as GIFs: written
    to ``figures/modes/mode_NN.gif`` and returned as (caption, bytes) for the page
    (about 40 kB a mode: a 34-mode report stays well under 10 MB)."""
    if not (folder / "modal.h5").is_file():  # (a run on a table of modes: no shapes)
        return []
    table = read_modal(folder / "modal.h5")
    if table.n_modes == 0 or "tread" not in table.channel_location:
        return []
    s = shape_set(table)
    (figdir / "modes").mkdir()
    out = []
    for k, gif in enumerate(plots.mode_gifs(s)):
        (figdir / "modes" / f"mode_{k + 1:02d}.gif").write_bytes(gif)
        out.append((f"mode {k + 1}: {s.frequency_hz[k]:.1f} Hz {s.label[k]}", gif))
    return out


def report_batch(outdir, *, progress: Callable[[str, int, int], None] | None = None) -> Path:
    """Reports for every test of a batch folder with outputs, and ``index.html``.

    progress : callable(test name, done, total), optional. Returns the index's path.
    """
    outdir = Path(outdir)
    recs = read_summary(outdir)
    with_outputs = [r for r in recs if r["status"] in ("done", "skipped") and r.get("output")]
    links = {}
    for i, r in enumerate(with_outputs):
        folder = outdir / Path(r["output"]).name
        report_run(folder)
        links[r["test"]] = f"{folder.name}/{REPORT_HTML}"
        if progress:
            progress(r["test"], i + 1, len(with_outputs))
    figs = _campaign_figures(outdir, recs) if with_outputs else []
    n = {k: sum(r["status"] == k for r in recs) for k in ("done", "skipped", "failed")}
    head = "".join(f'<th class="{c}">{h}</th>' for h, c in (
        ("test", "l"), ("status", "l"), ("pressure [kPa]", ""), ("modes", ""), ("RMS before [%]", ""),
        ("RMS after [%]", ""), ("added to the model", "l"), ("its parameters (final model)", "l"), ("reason", "l")))
    body = [f"<h1>Campaign report — {escape(outdir.resolve().name)}</h1>",
            f"<p>{len(recs)} tests: {n['done'] + n['skipped']} with outputs, {n['failed']} failed.</p>",
            f"<table><tr>{head}</tr>{''.join(_index_row(r, links) for r in recs)}</table>"]
    body += [img(png, cap) for png, cap in figs]
    return write_text_atomic(outdir / INDEX_HTML, page(f"tiremodal campaign: {outdir.name}", "\n".join(body)),
                             overwrite=True)


def _campaign_figures(outdir: Path, recs: list[dict]) -> list[tuple[bytes, str]]:
    """The campaign figures written to ``outdir/figures`` (built aside, renamed into place);
    returned as (PNG bytes, caption) for the index."""
    tmp = _figure_folder(outdir)
    try:
        figs = [(render(plots.plot_campaign_parameters(recs), tmp, "campaign_parameters"),
                 "Identified parameters across the tests (± 1 standard error), and the parameters of the "
                 "effects the diagnosis added (final model); repeats at one condition side by side."),
                (render(plots.plot_campaign_frequencies(recs), tmp, "campaign_frequencies"),
                 "Measured frequency of each (n, branch) across the tests.")]
        install_dir(tmp, outdir / FIGURE_DIR)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return figs


def _index_row(r: dict, links: dict[str, str]) -> str:
    """One test's row of the index: its name (linked to its page when it has one), status,
    pressure, modes, errors before and after, what the diagnosis added, and the reason."""
    name = (f'<a href="{escape(links[r["test"]])}">{escape(r["test"])}</a>' if r["test"] in links
            else escape(r["test"]))
    cls = "bad" if r["status"] == "failed" else "ok"
    p = r.get("inflation_pressure")
    return "<tr>" + "".join([
        f'<td class="l">{name}</td>', f'<td class="l {cls}">{escape(r["status"])}</td>',
        f"<td>{number(None if p is None else p / 1e3, '{:g}')}</td>", f"<td>{number(r.get('modes_found'))}</td>",
        f"<td>{number(r.get('rms_before_pct'), '{:.3f}')}</td>", f"<td>{number(r.get('rms_after_pct'), '{:.3f}')}</td>",
        f'<td class="l">{escape(_added(r))}</td>',
        f'<td class="l">{escape(_effect_values(r))}</td>',
        f'<td class="l">{escape(r.get("reason"))}</td>']) + "</tr>"


def _added(rec: dict) -> str:
    """What the diagnosis added to the model of one test, in words."""
    return "; ".join(names.effect_title(x) for x in (rec.get("adopted_effects") or []) + (rec.get("parameter_off") or []))


def _effect_values(rec: dict) -> str:
    """The final model's effect parameters of one test: ``T_s [N] = 2.16e+04 ± 35``."""
    out = []
    for k, v in (rec.get("augmented_parameters") or {}).items():
        if "." in k:
            v = v if isinstance(v, dict) else {"value": v}
            e = v.get("std_error")
            out.append(f"{names.label(k)} = {v['value']:.4g}" + ("" if e is None else f" ± {e:.2g}"))
    return "; ".join(out)


def report(outdir, *, progress=None) -> list[Path]:
    """Report a run folder (``run.json``) or a batch folder (``summary.jsonl``).

    Parameters
    ----------
    outdir : path-like
        A folder written by ``run`` (:func:`tiremodal_cli.workflow.run_folder.run_folder`) or ``batch``.
    progress : callable, optional
        For a batch: called with (test name, done, total) after each test's page.

    Returns
    -------
    list of pathlib.Path
        The HTML pages written (the index last for a batch).

    Raises
    ------
    DataFormatError
        Neither a run nor a batch folder, or a run folder that does not match its manifest.
    """
    outdir = Path(outdir)
    if (outdir / MANIFEST).is_file():
        return [report_run(outdir)]
    if (outdir / SUMMARY_JSONL).is_file():
        index = report_batch(outdir, progress=progress)
        pages = sorted(outdir.glob(f"*/{REPORT_HTML}"))
        return pages + [index]
    if not outdir.is_dir():
        raise DataFormatError(f"{outdir}: no such folder")
    raise DataFormatError(f"{outdir}: neither a run folder ({MANIFEST}) nor a batch folder ({SUMMARY_JSONL})")
