"""The page of one run: its sections, each a function of the run's outputs (the manifest,
``identify.json``, ``diagnosis.json``, ``modes.csv``) and its rendered figures."""

from __future__ import annotations

import base64
import re
from dataclasses import dataclass
from pathlib import Path

from tiremodal_cli import names
from tiremodal_cli.conventions import FORM_UNITS
from tiremodal_cli.io.modalfile import read_modal_csv
from tiremodal_cli.tyre.effects import EFFECTS
from tiremodal_cli.workflow.html import escape, img, table, written_by

__all__ = ["FIGURES", "SECTIONS", "footer", "run_body"]

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


def footer(man: dict) -> str:
    """Provenance of a run's page: when and how the results were made, from what input."""
    rows = [("results made", man.get("created_utc", "not recorded (an older run)")),
            ("by", f"tiremodal {man.get('tiremodal_version', '?')}"
                   + (f", commit {man['tiremodal_commit']}" if man.get("tiremodal_commit") else
                      ", commit not known (not run from a git checkout)")),
            ("command", man.get("command", "not recorded")),
            ("options", ", ".join(f"{k} = {v}" for k, v in (man.get("options") or {}).items())),
            ("input", f"{man.get('input_file', '')} (SHA-256 {man.get('input_sha256', '')})")]
    return ("<h2>Provenance</h2>" + table([{"k": k, "v": v} for k, v in rows], [("k", ""), ("v", "")],
                                          left=("k", "v"))
            + f"<p>{escape(written_by())}</p>")


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
        return out + [f"<p>The flexible-tread model was not fitted: {escape(flex['skipped'])}.</p>"]
    keys = list(dict.fromkeys(list(cmp["coupled"]["by_branch"]) + list(flex["by_branch"])))
    rows = []
    for name, d in (("coupled (tread, sidewall mass, rim)", cmp["coupled"]["by_branch"]),
                    ("flexible tread on an elastic foundation", flex["by_branch"])):
        rows.append({"model": name, **{k: d[k]["rms_error_pct"] if k in d else None for k in keys}})
    out.append("<p>RMS frequency error (%) by branch and band. The flexible-tread model has one mode of "
               "each order; it is fitted to the same-direction modes and set against every mode.</p>")
    out.append(table(rows, [("model", "model")] + [(k, f"{k} [%]") for k in keys], left=("model",)))
    return out


def _gif_grid(gifs: list[tuple[str, bytes]]) -> str:
    """The modes' GIFs side by side, each with its caption."""
    cells = "".join(f'<figure class="gif"><img alt="{escape(c)}" src="data:image/gif;base64,'
                    f'{base64.b64encode(b).decode("ascii")}"><figcaption>{escape(c)}</figcaption></figure>'
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
        return img(self.pngs[stem], cap)


def _head(p: _RunPage) -> list[str]:
    s = p.summary
    out = [f"<h1>Modal test report — {escape(Path(s['measurement']).name)}</h1>",
           f"<p><b>Diagnosis:</b> {escape(_in_words(s['verdict']))}</p>"]
    if s.get("starts_at") == "identify":
        out.append("<p><b>Input:</b> a table of measured modes (frequency, circumferential order n, "
                   "branch): the pipeline started at identify. There were no records, so no FRFs, no modal "
                   "estimate and no shapes here; the rim and the pressure are the parameters'.</p>")
    if s.get("starts_at") == "lsce":
        out.append("<p><b>Input:</b> FRFs from another system (UFF 58): the pipeline started at lsce. "
                   "There were no time records, so no hit checks, no windows and no force spectrum here; "
                   "the FRFs are the other system's, taken to SI as stated below.</p>")
    return out


def _test_section(p: _RunPage) -> list[str]:
    s = p.summary
    out = ["<h2>Test</h2>", table([{"k": k, "v": v} for k, v in _test_facts(p.man)], [("k", ""), ("v", "")],
                                   left=("k", "v"))]
    rej = s.get("rejected_hits") or []
    out.append(f"<h2>Rejected hits ({len(rej)})</h2>")
    out.append(table([{**x, "point": _one_based(x.get("point")), "hit": _one_based(x.get("hit"))} for x in rej],
                      [("point", "point"), ("hit", "hit"), ("channel", "channel"), ("reason", "reason")],
                      left=("channel", "reason")) if rej else
               "<p>Not checked: the input holds FRFs, not hits.</p>" if s.get("starts_at") == "lsce" else
               "<p>Not checked: the input is a table of modes, not hits.</p>" if s.get("starts_at") == "identify" else
               "<p>None: every hit passed the checks.</p>")
    return out


def _modes_section(p: _RunPage) -> list[str]:
    from_modes = p.summary.get("starts_at") == "identify"
    out = [] if from_modes else ["<h2>FRFs and coherence</h2>", p.fig("frf"), "<h2>Stabilization diagram</h2>",
                                 p.fig("stabilization")]
    out += ["<h2>Modal table" + (" (as given)" if from_modes else "") + "</h2>", table(_modes_rows(p.folder),
                                           [("mode", "mode"), ("frequency_hz", "f [Hz]"), ("damping_pct", "ζ [%]"),
                                            ("n", "n"), ("branch", "branch"), ("n_confidence", "n conf."),
                                            ("mpc", "MPC"), ("frequency_uncertainty_hz", "σf [Hz]")],
                                           left=("branch",))]
    if p.summary.get("orders_mix"):  # (modal.mixing.mixed_orders_note)
        out.append(f"<p><b>Completeness:</b> {escape(p.summary['orders_mix']['statement'])}.</p>")
    if from_modes:
        return out
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
           table(par, [("name", "parameter"), ("value", "value"), ("std_error", "std. error"), ("rel", "rel. [%]")],
                  left=("name",))]
    if ident.get("undetermined"):
        out.append("<p>Not determined by these data: " + "; ".join(f"{escape(names.long_label(k))} ({escape(v)})"
                                                                   for k, v in ident["undetermined"].items()) + "</p>")
    out += _set_aside_html(ident)
    out += [p.fig("fit"), p.fig("convergence")]
    return out + _comparison_html(ident.get("model_comparison"))


def _diagnosis_section(p: _RunPage) -> list[str]:
    diag = p.diag
    before, after = diag["residual_before"], diag["residual_after"]
    out = ["<h2>Residual diagnosis</h2>", f"<p>{escape(_in_words(diag['verdict']))}</p>",
           table([{"k": "before", "rms": before["rms_error_pct"], "max": before["max_error_pct"],
                    "chi2": before["chi2"], "dof": before["dof"], "p": before["p_value"]},
                   {"k": "after", "rms": after["rms_error_pct"], "max": after["max_error_pct"],
                    "chi2": after["chi2"], "dof": after["dof"], "p": after["p_value"]}],
                  [("k", ""), ("rms", "RMS error [%]"), ("max", "max error [%]"), ("chi2", "χ²"), ("dof", "dof"),
                   ("p", "p")], left=("k",)),
           p.fig("residuals"), "<h3>Candidates</h3>",
           table([{**c, "name": f"{names.effect_title(c['name'])} ({c['name']})",
                    "adopted": "yes" if c["adopted"] else ""} for c in diag["candidates"]],
                  [("name", "candidate"), ("round", "round"), ("rms_error_pct", "RMS [%]"), ("score", "ΔAICc"),
                   ("f_p_value", "F-test p"), ("adopted", "adopted"), ("reason", "reason")],
                  left=("name", "adopted", "reason"))]
    final = (diag.get("augmented") or {}).get("parameters") or {}
    if final:
        out += ["<h3>The final model's parameters</h3>",
                table([{"name": names.long_label(k), "value": v.get("value"), "std_error": v.get("std_error")}
                        for k, v in final.items()],
                       [("name", "parameter"), ("value", "value"), ("std_error", "std. error")], left=("name",))]
    if diag.get("unexplained_modes"):
        out += ["<h3>Modes no (n, branch) explains</h3>",
                table(diag["unexplained_modes"], [("frequency_hz", "f [Hz]"), ("n", "n"), ("reason", "reason")],
                       left=("reason",))]
    return out


def _predictions_section(p: _RunPage) -> list[str]:
    preds = p.diag["predictions"]["augmented"]
    return ["<h2>Predictions</h2>", p.fig("predictions"),
            table(_predictions_rows(preds, p.diag["modes"]),
                   [("n", "n"), ("branch", "branch"), ("model_hz", "model [Hz]"), ("std_hz", "σ [Hz]"),
                    ("measured", "measured [Hz]")], left=("branch",)),
            "<h2>Parameter sensitivity</h2>", p.fig("sensitivity")]


#: The sections of a run's page, in order: each a function of :class:`_RunPage` returning
#: HTML parts. A new section (e.g. the modes the diagnosis set aside, or the verdict's
#: uncertainty) is one function added here; the provenance footer follows the last.
SECTIONS = (_head, _test_section, _modes_section, _identification_section, _diagnosis_section,
            _predictions_section)


def run_body(folder: Path, man: dict, ident: dict, diag: dict, pngs: dict, gifs=()) -> str:
    """The page's body: every section of :data:`SECTIONS` in order.

    pngs : the rendered figures, PNG bytes by stem (:data:`FIGURES`); gifs : (caption, GIF bytes)
    of the modes moving.
    """
    page = _RunPage(folder, man, ident, diag, pngs, tuple(gifs))
    return "\n".join(part for section in SECTIONS for part in section(page))


def _in_words(text: str) -> str:
    """A sentence with each effect's code name followed by its title in words."""
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
        facts += [("input", f"{src['kind']}; the pipeline started at lsce"),
                  ("impact points", s["n_points"]),
                  ("FRF units", f"{src['unit_in_file']} in the file, × {src['to_si']:.6g} → {FORM_UNITS[src['form']]} "
                                f"({src['form']}); from {src['from']}"),
                  ("point angles from", src["geometry"]),
                  ("sign flipped (negative direction code)", ", ".join(src["sign_flipped"]) or "none")]
        if src.get("options_not_used"):
            facts.append(("options not used", src["options_not_used"]))
        if src.get("header"):
            facts.append(("file header (UFF 151)", "; ".join(f"{k}: {v}" for k, v in src["header"].items() if v)))
    elif s.get("starts_at") == "identify":
        facts += [("input", "a table of measured modes; the pipeline started at identify")]
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
    return head + [table(aside, [("n", "n"), ("branch", "branch"), ("frequency_hz", "measured [Hz]"),
                                  ("model_hz", "model [Hz]"), ("error_pct", "error [%]"), ("reason", "reason")],
                          left=("branch", "reason")), how]


def _modes_rows(folder: Path) -> list[dict]:
    """The modal table (``modes.csv``) as rows for the page."""
    rows = read_modal_csv(folder / "modes.csv")
    out = []
    for i, r in enumerate(rows):
        def f(k):
            try:
                return float(r[k]) if r.get(k) not in (None, "") else None
            except ValueError:
                return None
        out.append({"mode": int(r["mode"]) if r.get("mode") not in (None, "") else i + 1,
                    "frequency_hz": f("frequency_hz"),
                    "damping_pct": None if f("damping_ratio") is None else 100 * f("damping_ratio"),
                    "n": None if r.get("n") in (None, "") else int(r["n"]), "branch": r.get("branch", ""),
                    "n_confidence": f("n_confidence"), "mpc": f("mpc"),
                    "frequency_uncertainty_hz": f("frequency_uncertainty_hz")})
    return out
