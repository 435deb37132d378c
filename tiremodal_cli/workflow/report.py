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

import base64
import html
import io
import json
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tiremodal_cli import names
from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.files import _UMASK, install_dir, write_text_atomic
from tiremodal_cli.workflow.manifest import read_manifest, verify_manifest
from tiremodal_cli.workflow.run_options import MANIFEST

__all__ = ["FIGURES", "report_run", "report_batch", "report", "REPORT_HTML", "INDEX_HTML"]

REPORT_HTML = "report.html"
INDEX_HTML = "index.html"
FIGURE_DIR = "figures"

#: The figures of a test's report, in page order: (file stem, caption).
FIGURES = (
    ("frf", "FRFs of two impact points with their coherence (accepted hits averaged, H1)."),
    ("stabilization", "Stabilization diagram: candidate poles by model order; adopted modes as lines."),
    ("mac", "AutoMAC of the mode shapes (tread, sidewall and rim residues at every point)."),
    ("shapes", "Mode shapes around the tyre: tread (blue) and sidewall (red), over the undeformed circle."),
    ("synthesis", "Measured FRFs (solid) against the modal model's re-synthesis (dashed)."),
    ("fit", "The identified model's frequencies against n (band: ± 2σ) with the measured modes."),
    ("convergence", "Evolutionary search: best RMS frequency error per generation."),
    ("residuals", "Frequency error of each mode before (base model) and after the diagnosis."),
    ("predictions", "Predicted frequencies of the final model to higher orders, with the measured ones."),
    ("sensitivity", "Normalised sensitivities ∂ln f/∂ln p of the final model at its parameters."),
)

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Helvetica,Arial,sans-serif;margin:2em auto;max-width:1100px;
color:#222;line-height:1.4;padding:0 1em}
h1{font-size:1.5em;border-bottom:2px solid #345;padding-bottom:.2em}h2{font-size:1.2em;margin-top:1.6em;color:#345}
table{border-collapse:collapse;font-size:.85em;margin:.5em 0}td,th{border:1px solid #ccc;padding:.2em .5em;
text-align:right}th{background:#eef2f6}td.l,th.l{text-align:left}figure{margin:1em 0}
figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.85em;color:#555}
.gifs{display:flex;flex-wrap:wrap;gap:.3em}.gifs figure{margin:0;width:150px}
.gifs img{width:150px;border:none}.gifs figcaption{font-size:.7em}
.ok{color:#161}.bad{color:#a11}.muted{color:#777;font-size:.85em}
"""


def _e(x) -> str:
    return html.escape("" if x is None else str(x))


def _num(v, fmt="{:.4g}") -> str:
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    return fmt.format(v) if isinstance(v, (int, float)) else _e(v)


def _table(rows: list[dict], cols: list[tuple[str, str]], *, left=()) -> str:
    """An HTML table of dict rows; cols = [(key, heading)]; ``left`` columns left-aligned."""
    def cell(tag, k, v):
        return f'<{tag} class="l">{v}</{tag}>' if k in left else f"<{tag}>{v}</{tag}>"

    def text(v):
        return _e(v) if isinstance(v, str) else _num(v)
    head = "".join(cell("th", k, _e(h)) for k, h in cols)
    body = "".join("<tr>" + "".join(cell("td", k, text(r.get(k))) for k, _ in cols) + "</tr>" for r in rows)
    return f"<table>{f'<tr>{head}</tr>' if any(h for _, h in cols) else ''}{body}</table>"


def _anchor(m) -> str:
    import re

    slug = re.sub(r"[^a-z0-9]+", "-", html.unescape(re.sub(r"<[^>]+>", "", m.group(2))).lower()).strip("-")
    return f'<{m.group(1)} id="{slug}">{m.group(2)}</{m.group(1)}>'


def _page(title: str, body: str, footer: str = "") -> str:
    """The page: every h2/h3 gets an id from its words (``#stabilization-diagram``) to link to."""
    import re

    body = re.sub(r"<(h[23])>(.*?)</\1>", _anchor, body)
    footer = re.sub(r"<(h[23])>(.*?)</\1>", _anchor, footer)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{_e(title)}</title>'
            f"<style>{_CSS}</style></head><body>\n{body}\n"
            f'<footer class="muted">{footer or _e(_written_by())}</footer></body></html>\n')


def _written_by() -> str:
    from tiremodal_cli.workflow.manifest import provenance

    p = provenance()
    return (f"Page written {p['created_utc']} by tiremodal {p['tiremodal_version']}"
            + (f" (commit {p['tiremodal_commit']})" if p.get("tiremodal_commit") else "") + ".")


def _footer(man: dict) -> str:
    """Provenance of a run's page: when and how the results were made, from what input."""
    rows = [("results made", man.get("created_utc", "not recorded (an older run)")),
            ("by", f"tiremodal {man.get('tiremodal_version', '?')}"
                   + (f", commit {man['tiremodal_commit']}" if man.get("tiremodal_commit") else
                      ", commit not known (not run from a git checkout)")),
            ("command", man.get("command", "not recorded")),
            ("options", ", ".join(f"{k} = {v}" for k, v in (man.get("options") or {}).items())),
            ("input", f"{man.get('input_file', '')} (SHA-256 {man.get('input_sha256', '')})")]
    return ("<h2>Provenance</h2>" + _table([{"k": k, "v": v} for k, v in rows], [("k", ""), ("v", "")],
                                             left=("k", "v"))
            + f"<p>{_e(_written_by())}</p>")


def _render(fig, folder: Path, stem: str) -> bytes:
    """Save ``fig`` as folder/stem.png and .svg; return the PNG bytes (for embedding)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    png = buf.getvalue()
    (folder / f"{stem}.png").write_bytes(png)
    fig.savefig(folder / f"{stem}.svg", format="svg")
    return png


def _img(png: bytes, caption: str) -> str:
    b64 = base64.b64encode(png).decode("ascii")
    return (f'<figure><img alt="{_e(caption)}" src="data:image/png;base64,{b64}">'
            f"<figcaption>{_e(caption)}</figcaption></figure>")


def _load_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DataFormatError(f"{path}: missing; the run folder is incomplete (re-run it)") from None
    except ValueError as exc:
        raise DataFormatError(f"{path}: not JSON ({exc})") from None


def _figures(folder: Path, man: dict, ident: dict, diag: dict, sens: dict) -> dict[str, Callable]:
    """Callables making each figure of :data:`FIGURES` from the run folder's outputs."""
    from tiremodal_cli import plots
    from tiremodal_cli.io.frffile import read_frf
    from tiremodal_cli.io.modalfile import read_modal

    r = read_frf(folder / "frf.h5")
    table = read_modal(folder / "modal.h5")
    n_p = r.point_angle.size

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

    return {
        "frf": lambda: plots.plot_frf(r, points=sorted({0, n_p // 4}))[0].figure,
        "stabilization": lambda: plots.stabilization_figure(table, r),
        "mac": lambda: plots.automac_figure(table),
        "shapes": lambda: plots.plot_shapes(table),
        "synthesis": lambda: plots.synthesis_figure(table, r),
        "fit": fit,
        "convergence": lambda: plots.plot_convergence([(h["generation"], h["rms_error_pct"] / 100)
                                                       for h in ident["history"]]).figure,
        "residuals": lambda: plots.plot_residuals(diag["modes"]),
        "predictions": predictions,
        "sensitivity": sensitivity,
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
    tmp = Path(tempfile.mkdtemp(prefix=f".{FIGURE_DIR}.", dir=folder))
    os.chmod(tmp, 0o777 & ~_UMASK)
    try:
        pngs = {}
        for stem, _ in FIGURES:
            if progress:
                progress(stem)
            pngs[stem] = _render(makers[stem](), tmp, stem)
        if progress:
            progress("mode animations")
        gifs = _mode_gifs(folder, tmp)
        body = _run_body(folder, man, ident, diag, pngs, gifs)
        html_text = _page(f"tiremodal report: {man['summary']['measurement']}", body, _footer(man))
        install_dir(tmp, folder / FIGURE_DIR)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return write_text_atomic(folder / REPORT_HTML, html_text, overwrite=True)


def _one_based(i):
    """A 0-based index as 1-based, or "all" for a rejection of every hit (a dead channel)."""
    return "all" if i is None else int(i) + 1


def _comparison_html(cmp: dict | None) -> list[str]:
    """The coupled model beside the classical flexible-tread model: RMS error by branch and band."""
    if not cmp:
        return []
    flex = cmp.get("flexible_tread", {})
    out = ["<h3>Where each model holds</h3>"]
    if "skipped" in flex:
        return out + [f"<p>The flexible-tread model was not fitted: {_e(flex['skipped'])}.</p>"]
    keys = list(dict.fromkeys(list(cmp["coupled"]["by_branch"]) + list(flex["by_branch"])))
    rows = []
    for name, d in (("coupled (tread, sidewall mass, rim)", cmp["coupled"]["by_branch"]),
                    ("flexible tread on an elastic foundation", flex["by_branch"])):
        rows.append({"model": name, **{k: d[k]["rms_error_pct"] if k in d else None for k in keys}})
    out.append("<p>RMS frequency error (%) by branch and band. The flexible-tread model has one mode of "
               "each order; it is fitted to the same-direction modes and set against every mode.</p>")
    out.append(_table(rows, [("model", "model")] + [(k, f"{k} [%]") for k in keys], left=("model",)))
    return out


def _mode_gifs(folder: Path, figdir: Path) -> list[tuple[str, bytes]]:
    """Each mode moving (tread, sidewall and rim rings in the tyre's plane), as GIFs: written
    to ``figures/modes/mode_NN.gif`` and returned as (caption, bytes) for the page
    (about 40 kB a mode: a 34-mode report stays well under 10 MB)."""
    from tiremodal_cli.io.export import shape_set
    from tiremodal_cli.io.modalfile import read_modal
    from tiremodal_cli.plots import mode_gifs

    table = read_modal(folder / "modal.h5")
    if table.n_modes == 0 or "tread" not in table.channel_location:
        return []
    s = shape_set(table)
    (figdir / "modes").mkdir()
    out = []
    for k, gif in enumerate(mode_gifs(s)):
        (figdir / "modes" / f"mode_{k + 1:02d}.gif").write_bytes(gif)
        out.append((f"mode {k + 1}: {s.frequency_hz[k]:.1f} Hz {s.label[k]}", gif))
    return out


def _gif_grid(gifs: list[tuple[str, bytes]]) -> str:
    cells = "".join(f'<figure class="gif"><img alt="{_e(c)}" src="data:image/gif;base64,'
                    f'{base64.b64encode(b).decode("ascii")}"><figcaption>{_e(c)}</figcaption></figure>'
                    for c, b in gifs)
    return f'<div class="gifs">{cells}</div>'


@dataclass(frozen=True)
class _RunPage:
    """What every section of a run's page reads: the folder, its manifest and JSON outputs,
    the rendered figures (PNG bytes by stem) and the mode animations."""

    folder: Path
    man: dict
    ident: dict
    diag: dict
    pngs: dict
    gifs: tuple = ()

    @property
    def summary(self) -> dict:
        return self.man["summary"]

    def fig(self, stem: str) -> str:
        cap = dict(FIGURES)[stem]
        if stem == "frf" and self.summary.get("starts_at") == "lsce":
            cap = "FRFs of two impact points with their coherence, as the other system estimated them (in SI)."
        return _img(self.pngs[stem], cap)


def _head(p: _RunPage) -> list[str]:
    s = p.summary
    out = [f"<h1>Modal test report — {_e(Path(s['measurement']).name)}</h1>",
           f"<p><b>Diagnosis:</b> {_e(_in_words(s['verdict']))}</p>"]
    if s.get("starts_at") == "lsce":
        out.append("<p><b>Input:</b> FRFs from another system (UFF 58): the pipeline started at lsce. "
                   "There were no time records, so no hit checks, no windows and no force spectrum here; "
                   "the FRFs are the other system's, taken to SI as stated below.</p>")
    return out


def _test_section(p: _RunPage) -> list[str]:
    s = p.summary
    out = ["<h2>Test</h2>", _table([{"k": k, "v": v} for k, v in _test_facts(p.man)], [("k", ""), ("v", "")],
                                   left=("k", "v"))]
    rej = s.get("rejected_hits") or []
    out.append(f"<h2>Rejected hits ({len(rej)})</h2>")
    out.append(_table([{**x, "point": _one_based(x.get("point")), "hit": _one_based(x.get("hit"))} for x in rej],
                      [("point", "point"), ("hit", "hit"), ("channel", "channel"), ("reason", "reason")],
                      left=("channel", "reason")) if rej else
               "<p>Not checked: the input holds FRFs, not hits.</p>" if s.get("starts_at") == "lsce" else
               "<p>None: every hit passed the checks.</p>")
    return out


def _modes_section(p: _RunPage) -> list[str]:
    out = ["<h2>FRFs and coherence</h2>", p.fig("frf"), "<h2>Stabilization diagram</h2>", p.fig("stabilization")]
    out += ["<h2>Modal table</h2>", _table(_modes_rows(p.folder),
                                           [("mode", "mode"), ("frequency_hz", "f [Hz]"), ("damping_pct", "ζ [%]"),
                                            ("n", "n"), ("branch", "branch"), ("n_confidence", "n conf."),
                                            ("mpc", "MPC"), ("frequency_uncertainty_hz", "σf [Hz]")],
                                           left=("branch",))]
    out += ["<h2>MAC matrix</h2>", p.fig("mac"), "<h2>Mode shapes</h2>", p.fig("shapes")]
    if p.gifs:
        out += ["<h3>The modes moving</h3>",
                "<p>Each mode over one period: tread (blue), sidewall (red) and rim (grey) displaced radially "
                "by Re(φ e<sup>iωt</sup>), the largest displacement drawn at a fifth of the radius.</p>",
                _gif_grid(p.gifs)]
    return out + ["<h2>Measured against synthesised FRFs</h2>", p.fig("synthesis")]


def _identification_section(p: _RunPage) -> list[str]:
    ident = p.ident
    par = [{"name": names.long_label(k), "value": v["value"], "std_error": v["std_error"],
            "rel": 100 * v["std_error"] / abs(v["value"]) if v["value"] else None} for k, v in ident["parameters"].items()]
    out = ["<h2>Model identification</h2>",
           f"<p>RMS frequency error {ident['rms_error_pct']:.3f} %, max {ident['max_error_pct']:.3f} % over "
           f"{len(ident['modes'])} modes.</p>",
           _table(par, [("name", "parameter"), ("value", "value"), ("std_error", "std. error"), ("rel", "rel. [%]")],
                  left=("name",))]
    if ident.get("undetermined"):
        out.append("<p>Not determined by these data: " + "; ".join(f"{_e(names.long_label(k))} ({_e(v)})"
                                                                   for k, v in ident["undetermined"].items()) + "</p>")
    out += _set_aside_html(ident)
    out += [p.fig("fit"), p.fig("convergence")]
    return out + _comparison_html(ident.get("model_comparison"))


def _diagnosis_section(p: _RunPage) -> list[str]:
    diag = p.diag
    before, after = diag["residual_before"], diag["residual_after"]
    out = ["<h2>Residual diagnosis</h2>", f"<p>{_e(_in_words(diag['verdict']))}</p>",
           _table([{"k": "before", "rms": before["rms_error_pct"], "max": before["max_error_pct"],
                    "chi2": before["chi2"], "dof": before["dof"], "p": before["p_value"]},
                   {"k": "after", "rms": after["rms_error_pct"], "max": after["max_error_pct"],
                    "chi2": after["chi2"], "dof": after["dof"], "p": after["p_value"]}],
                  [("k", ""), ("rms", "RMS error [%]"), ("max", "max error [%]"), ("chi2", "χ²"), ("dof", "dof"),
                   ("p", "p")], left=("k",)),
           p.fig("residuals"), "<h3>Candidates</h3>",
           _table([{**c, "name": f"{names.effect_title(c['name'])} ({c['name']})",
                    "adopted": "yes" if c["adopted"] else ""} for c in diag["candidates"]],
                  [("name", "candidate"), ("round", "round"), ("rms_error_pct", "RMS [%]"), ("score", "ΔAICc"),
                   ("f_p_value", "F-test p"), ("adopted", "adopted"), ("reason", "reason")],
                  left=("name", "adopted", "reason"))]
    final = (diag.get("augmented") or {}).get("parameters") or {}
    if final:
        out += ["<h3>The final model's parameters</h3>",
                _table([{"name": names.long_label(k), "value": v.get("value"), "std_error": v.get("std_error")}
                        for k, v in final.items()],
                       [("name", "parameter"), ("value", "value"), ("std_error", "std. error")], left=("name",))]
    if diag.get("unexplained_modes"):
        out += ["<h3>Modes no (n, branch) explains</h3>",
                _table(diag["unexplained_modes"], [("frequency_hz", "f [Hz]"), ("n", "n"), ("reason", "reason")],
                       left=("reason",))]
    return out


def _predictions_section(p: _RunPage) -> list[str]:
    preds = p.diag["predictions"]["augmented"]
    return ["<h2>Predictions</h2>", p.fig("predictions"),
            _table(_predictions_rows(preds, p.diag["modes"]),
                   [("n", "n"), ("branch", "branch"), ("model_hz", "model [Hz]"), ("std_hz", "σ [Hz]"),
                    ("measured", "measured [Hz]")], left=("branch",)),
            "<h2>Parameter sensitivity</h2>", p.fig("sensitivity")]


#: The sections of a run's page, in order: each a function of :class:`_RunPage` returning
#: HTML parts. A new section (e.g. the modes the diagnosis set aside, or the verdict's
#: uncertainty) is one function added here; the provenance footer follows the last.
SECTIONS = (_head, _test_section, _modes_section, _identification_section, _diagnosis_section,
            _predictions_section)


def _run_body(folder: Path, man: dict, ident: dict, diag: dict, pngs: dict, gifs=()) -> str:
    page = _RunPage(folder, man, ident, diag, pngs, tuple(gifs))
    return "\n".join(part for section in SECTIONS for part in section(page))


def _in_words(text: str) -> str:
    """A sentence with each effect's code name followed by its title in words."""
    import re

    from tiremodal_cli.tyre.effects import EFFECTS

    for k in EFFECTS:
        text = re.sub(rf"\b{re.escape(k)}\b", f"{k} ({names.effect_title(k)})", text)
    return text


def _predictions_rows(preds: list[dict], modes: list[dict]) -> list[dict]:
    """The final model's predictions with the measured frequency of each (n, branch) in Hz
    (several, joined, for a split pair; blank where the test has none)."""
    out = []
    for p in preds:
        f = [m["measured_hz"] for m in modes if m["n"] == p["n"] and m["branch"] == p["branch"]]
        out.append({**p, "measured": "; ".join(f"{x:.4g}" for x in sorted(f))})
    return out


def _test_facts(man: dict) -> list[tuple[str, object]]:
    """The test's facts for the page's first table: (label, value) rows."""
    s = man["summary"]
    p_kpa = None if s.get("inflation_pressure") is None else s["inflation_pressure"] / 1e3
    facts = [("measurement", s["measurement"]), ("tyre", s.get("tire")),
             ("inflation pressure", None if p_kpa is None else f"{p_kpa:g} kPa")]
    src = s.get("frf_source")
    if src:
        from tiremodal_cli.io.frffile import UNITS

        facts += [("input", f"{src['kind']}; the pipeline started at lsce"),
                  ("impact points", s["n_points"]),
                  ("FRF units", f"{src['unit_in_file']} in the file, × {src['to_si']:.6g} → {UNITS[src['form']]} "
                                f"({src['form']}); from {src['from']}"),
                  ("point angles from", src["geometry"]),
                  ("sign flipped (negative direction code)", ", ".join(src["sign_flipped"]) or "none")]
        if src.get("options_not_used"):
            facts.append(("options not used", src["options_not_used"]))
        if src.get("header"):
            facts.append(("file header (UFF 151)", "; ".join(f"{k}: {v}" for k, v in src["header"].items() if v)))
    else:
        facts += [("impact points × hits", f"{s['n_points']} × {s['n_hits']}"),
                  ("sample rate", f"{s['sample_rate']:g} Hz")]
    facts += [("modes found", s["modes_found"]),
              ("model P0", f"{man.get('model_P0', man['params']['P0']) / 1e3:g} kPa"),
              ("rim", s.get("rim", "from the parameters")),
              ("input SHA-256", man["input_sha256"][:16] + "…")]
    return facts


def _set_aside_html(ident: dict) -> list[str]:
    """The modes the robust base fit set aside, each with its reason, and the rule."""
    aside, rule = ident.get("set_aside"), ident.get("outlier_rule") or {}
    if aside is None:
        return []
    head = [f"<h3>Modes set aside ({len(aside)})</h3>"]
    how = (f"<p>A mode is set aside when its error stands out of the others' by more than "
           f"{rule.get('z_crit', float('nan')):.2f} robust standard deviations (the Bonferroni limit for "
           f"{len(ident.get('modes', [])) + len(aside)} modes at a false-rejection rate of "
           f"{rule.get('alpha', float('nan')):g} per fit); the diagnosis asks which candidate brings it back.</p>")
    if not aside:
        return head + ["<p>None: the model represents every mode.</p>", how]
    return head + [_table(aside, [("n", "n"), ("branch", "branch"), ("frequency_hz", "measured [Hz]"),
                                  ("model_hz", "model [Hz]"), ("error_pct", "error [%]"), ("reason", "reason")],
                          left=("branch", "reason")), how]


def _modes_rows(folder: Path) -> list[dict]:
    """The modal table (``modes.csv``) as rows for the page."""
    from tiremodal_cli.io.modalfile import read_modal_csv

    rows = read_modal_csv(folder / "modes.csv")
    out = []
    for r in rows:
        def f(k):
            try:
                return float(r[k]) if r.get(k) not in (None, "") else None
            except ValueError:
                return None
        out.append({"mode": int(r["mode"]), "frequency_hz": f("frequency_hz"),
                    "damping_pct": None if f("damping_ratio") is None else 100 * f("damping_ratio"),
                    "n": None if r.get("n") in (None, "") else int(r["n"]), "branch": r.get("branch", ""),
                    "n_confidence": f("n_confidence"), "mpc": f("mpc"),
                    "frequency_uncertainty_hz": f("frequency_uncertainty_hz")})
    return out


def report_batch(outdir, *, progress: Callable[[str, int, int], None] | None = None) -> Path:
    """Reports for every test of a batch folder with outputs, and ``index.html``.

    progress : callable(test name, done, total), optional. Returns the index's path.
    """
    from tiremodal_cli.workflow.batch import read_summary
    from tiremodal_cli.plots import plot_campaign_frequencies, plot_campaign_parameters

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
    figs = []
    if with_outputs:
        tmp = Path(tempfile.mkdtemp(prefix=f".{FIGURE_DIR}.", dir=outdir))
        os.chmod(tmp, 0o777 & ~_UMASK)
        try:
            figs = [(_render(plot_campaign_parameters(recs), tmp, "campaign_parameters"),
                     "Identified parameters across the tests (± 1 standard error), and the parameters of the "
                     "effects the diagnosis added (final model); repeats at one condition side by side."),
                    (_render(plot_campaign_frequencies(recs), tmp, "campaign_frequencies"),
                     "Measured frequency of each (n, branch) across the tests.")]
            install_dir(tmp, outdir / FIGURE_DIR)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
    n = {k: sum(r["status"] == k for r in recs) for k in ("done", "skipped", "failed")}
    rows = []
    for r in recs:
        name = (f'<a href="{_e(links[r["test"]])}">{_e(r["test"])}</a>' if r["test"] in links else _e(r["test"]))
        cls = "bad" if r["status"] == "failed" else "ok"
        p = r.get("inflation_pressure")
        rows.append("<tr>" + "".join([
            f'<td class="l">{name}</td>', f'<td class="l {cls}">{_e(r["status"])}</td>',
            f"<td>{_num(None if p is None else p / 1e3, '{:g}')}</td>", f"<td>{_num(r.get('modes_found'))}</td>",
            f"<td>{_num(r.get('rms_before_pct'), '{:.3f}')}</td>", f"<td>{_num(r.get('rms_after_pct'), '{:.3f}')}</td>",
            f'<td class="l">{_e(_added(r))}</td>',
            f'<td class="l">{_e(_effect_values(r))}</td>',
            f'<td class="l">{_e(r.get("reason"))}</td>']) + "</tr>")
    head = "".join(f'<th class="{c}">{h}</th>' for h, c in (
        ("test", "l"), ("status", "l"), ("pressure [kPa]", ""), ("modes", ""), ("RMS before [%]", ""),
        ("RMS after [%]", ""), ("added to the model", "l"), ("its parameters (final model)", "l"), ("reason", "l")))
    body = [f"<h1>Campaign report — {_e(outdir.resolve().name)}</h1>",
            f"<p>{len(recs)} tests: {n['done'] + n['skipped']} with outputs, {n['failed']} failed.</p>",
            f"<table><tr>{head}</tr>{''.join(rows)}</table>"]
    body += [_img(png, cap) for png, cap in figs]
    return write_text_atomic(outdir / INDEX_HTML, _page(f"tiremodal campaign: {outdir.name}", "\n".join(body)),
                             overwrite=True)


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
    from tiremodal_cli.workflow.batch import SUMMARY_JSONL

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
