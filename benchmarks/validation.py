"""The validation matrix: `run` on tests from two generators, scored against their truth.

    python benchmarks/validation.py                 # the full matrix → docs/validation.md
    python benchmarks/validation.py --jobs 2 --out results.jsonl
    python benchmarks/validation.py --only ring:reference --only paper:reference --no-docs
    python benchmarks/validation.py --jobs 2 --seed-offset 1000 --out held.jsonl   # other noise
    python benchmarks/validation.py --jobs 2 --noise-scale 0.02 --out quiet.jsonl  # 50 × less noise

Cases: tiremodal_cli/workflow/validation.py; scoring rules: workflow/validation_scoring.py
(and docs/validation.md). Every case is seeded; the same commit on the same machine gives the same scorecard (timings aside).
Prints one scorecard table (stdout), writes every record as JSON lines (``--out``), and
rewrites docs/validation.md with the table, the datasheet, the machine and the date.
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tiremodal_cli.modal.merge import SAME_POLE_FLOOR_BW  # noqa: E402
from tiremodal_cli.workflow.validation import (FACTORS, REFERENCE, TYRES, Case, held_out_levels, matrix,  # noqa: E402
                                               run_case)


def _one(case_dict: dict, keep: str | None) -> dict:
    case = Case(**case_dict)
    with threadpool_limits(1):
        if keep:
            d = Path(keep) / case.name.replace(":", "_").replace("=", "-").replace(" ", "").replace(",", "_")
            return run_case(case, d)
        with tempfile.TemporaryDirectory(prefix="tmval-") as tmp:
            return run_case(case, tmp)


def _machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem = ""
    try:
        kb = int(next(x for x in Path("/proc/meminfo").read_text().splitlines() if x.startswith("MemTotal")).split()[1])
        mem = f", {kb / 2**20:.0f} GiB"
    except (OSError, StopIteration, ValueError):
        pass
    return f"{platform.system()} {platform.release()}, {cpu}, {os.cpu_count()} cores{mem}, Python {platform.python_version()}, numpy {np.__version__}"


def _commit() -> str:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True)
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        return out.stdout.strip() + (" (with uncommitted changes)" if dirty else "")
    except OSError:
        return "unknown"


def _fmt(x, spec=".2f"):
    return "–" if x is None else format(x, spec)


def table(records: list[dict]) -> str:
    """The scorecard as a Markdown table, one row a case."""
    head = ("| case | status | found / expected | mislabelled | missed | spurious / adopted | "
            "base RMS % | noise % | adopted | diagnosis | run s |")
    lines = [head, "|" + "---|" * 11]
    for r in records:
        c = r["case"]
        diag = "right" if r.get("diagnosis_right") else ("wrong" if r["status"] == "ok" else "–")
        lines.append(
            f"| {r['name']} | {r['status'] if r['status'] == 'ok' else 'ERROR: ' + r.get('error', '')[:90]} "
            f"| {r['found']} / {r['expected']} | {r['mislabelled']} | {r['missed']} "
            f"| {r['spurious']} / {r['adopted']} | {_fmt(r.get('base_rms_pct'))} | {100 * c['noise']:.1f} "
            f"| {', '.join(r.get('adopted_effects', [])) or '–'} | {diag} | {_fmt(r.get('run_s'), '.1f')} |")
    return "\n".join(lines)


def totals(records: list[dict]) -> str:
    lines = ["| generator | cases | run errors | found / expected | mislabelled | missed | spurious / adopted "
             "| surplus | aliased found: order and branch read right | no-effect cases adopting nothing "
             "| no-effect cases with a mode set aside | effect cases diagnosed right |", "|" + "---|" * 12]
    for g in sorted({r["case"]["generator"] for r in records}):
        rs = [r for r in records if r["case"]["generator"] == g]
        ok = [r for r in rs if r["status"] == "ok"]
        s = lambda k: sum(r[k] for r in rs)  # noqa: E731
        none = [r for r in ok if r["case"]["physics"] == "none"]
        eff = [r for r in ok if r["case"]["physics"] != "none"]
        lines.append(
            f"| {g} | {len(rs)} | {len(rs) - len(ok)} | {s('found')} / {s('expected')} "
            f"({100 * s('found') / max(1, s('expected')):.0f} %) | {s('mislabelled')} | {s('missed')} "
            f"| {s('spurious')} / {s('adopted')} ({100 * s('spurious') / max(1, s('adopted')):.1f} %) "
            f"| {sum(r.get('surplus', 0) for r in rs)} "
            f"| {sum(r.get('aliased_read', 0) for r in rs)} / {sum(r.get('aliased_found', 0) for r in rs)} "
            f"| {sum(1 for r in none if r['diagnosis_right'])} / {len(none)} "
            f"| {sum(1 for r in none if r.get('set_aside'))} / {len(none)} "
            f"| {sum(1 for r in eff if r['diagnosis_right'])} / {len(eff)} |")
    return "\n".join(lines)


def datasheet(records: list[dict]) -> str:
    """What the tool resolves and how well, from the matrix (numbers, not claims)."""
    ok = [r for r in records if r["status"] == "ok"]
    out = []

    def one_factor(factor):
        return [r for r in ok if all(r["case"][f] == REFERENCE[f] for f in REFERENCE if f != factor)
                and not r["case"]["label"].startswith("combo")]

    out.append("### Highest order found, by point count (one factor at a time)\n")
    out.append("| generator | points N | N/2 | highest n found (right n and branch) | found / expected |")
    out.append("|---|---|---|---|---|")
    for r in sorted(one_factor("n_points"), key=lambda r: (r["case"]["generator"], r["case"]["n_points"])):
        ns = [d["n"] for d in r["detail"] if d["status"] == "found" and d["branch"] in ("same", "opposite")]
        out.append(f"| {r['case']['generator']} | {r['case']['n_points']} | {r['case']['n_points'] // 2} "
                   f"| {max(ns) if ns else '–'} | {r['found']} / {r['expected']} |")
    for factor, title in (("noise", "noise (std relative to each channel's RMS)"), ("n_hits", "hits per point"),
                          ("sample_rate", "sample rate (Hz)"), ("form", "FRF form")):
        out.append(f"\n### Frequency and damping error of the modes found, by {title}\n")
        out.append("| generator | level | found / expected | median abs. frequency error % "
                   "| median abs. damping error % | spurious / adopted |")
        out.append("|---|---|---|---|---|---|")
        for r in sorted(one_factor(factor), key=lambda r: (r["case"]["generator"], str(r["case"][factor]))):
            out.append(f"| {r['case']['generator']} | {r['case'][factor]} | {r['found']} / {r['expected']} "
                       f"| {_fmt(r.get('freq_err_median_pct'), '.4f')} | {_fmt(r.get('damping_err_median_pct'), '.2f')} "
                       f"| {r['spurious']} / {r['adopted']} |")
    out.append("\n### The estimator's frequency bias, in half-power bandwidths\n")
    out.append("|f̂ − f| / 2ζf of every mode found (all cases): what two estimates of one pole differ by, "
               "and the floor under which `lsce` takes two order groups' poles for one "
               "(`merge.SAME_POLE_FLOOR_BW`).\n")
    out.append("| generator | modes found | median | 99th percentile | largest | share above the floor |")
    out.append("|---|---|---|---|---|---|")
    for g in sorted({r["case"]["generator"] for r in ok}):
        e = np.array([x for r in ok if r["case"]["generator"] == g for x in r.get("freq_err_bw", [])])
        if e.size:
            out.append(f"| {g} | {e.size} | {np.median(e):.5f} | {np.percentile(e, 99):.4f} | {e.max():.4f} "
                       f"| {100 * np.mean(e > SAME_POLE_FLOOR_BW):.2f} % |")
    out.append("\n### Diagnosis: the physics in the test against what was adopted\n")
    out.append("| case | physics in the test | detectable (base model on the truth: RMS %) | modes set aside "
               "| adopted | base RMS % → final RMS % | right |")
    out.append("|---|---|---|---|---|---|---|")
    for r in ok:
        if r["case"]["physics"] != "none" or r["case"]["label"] == "reference":
            det = "–" if r["case"]["physics"] == "none" else (
                f"{'yes' if r.get('detectable') else 'no'} ({_fmt(r.get('truth_base_rms_pct'))})")
            out.append(f"| {r['name']} | {r['case']['physics']} | {det} | {r.get('set_aside', '–')} "
                       f"| {', '.join(r['adopted_effects']) or 'nothing'} "
                       f"| {_fmt(r['base_rms_pct'])} → {_fmt(r['final_rms_pct'])} "
                       f"| {'yes' if r['diagnosis_right'] else 'no'} |")
    return "\n".join(out)


def failures(records: list[dict]) -> str:
    """Each case's modes that were not found, in one line (what to fix)."""
    out = []
    for r in records:
        bad = [d for d in r.get("detail", []) if d["status"] != "found"]
        if r["status"] != "ok":
            out.append(f"- **{r['name']}**: run failed — {r.get('error', '')}")
        elif bad or r["spurious"]:
            items = "; ".join(f"{d['frequency_hz']:.1f} Hz n={d['n']} {d['branch']}: {d['status']}" for d in bad[:12])
            more = f" (+{len(bad) - 12} more)" if len(bad) > 12 else ""
            sp = f" Spurious at {', '.join(map(str, r['spurious_hz'][:8]))} Hz." if r["spurious"] else ""
            out.append(f"- **{r['name']}**: {items}{more}.{sp}")
    return "\n".join(out)


DOC_HEAD = """# Validation: the tool on tests it did not generate

`benchmarks/validation.py` simulates every case below, takes it through `tiremodal run`
with its defaults (only the FRF form varies, as `RunOptions.form`), and scores the result
against the generator's truth. Two generators: **paper** — the paper's model and its
effects (`tiremodal simulate`), the model the estimator and the diagnosis are built on;
**ring** — the independent finite-element tyre (`tiremodal simulate --model ring`,
`tiremodal_cli/tyre/ring.py`), which shares no code with them. The **reference** test: 2,048 Hz,
2 s records, 34 points, 3 hits, 0.5 % noise, accelerance, no faults, no extra physics (the
ring's default is the paper's model as a limit of the ring; a clamped rim). Every other case
changes one factor, or a seeded random combination of them.

**Scoring** (`tiremodal_cli/workflow/validation_scoring.py`): a truth mode is *expected* when its half-power
band lies in the usable band (f (1 + ζ) ≤ fs/2.56 — a mode with a flank cut off by the band's
top is fitted to one flank, and `lsce` rejects it — and the hammer's force within 20 dB of its
low-frequency level),
its peak accelerance at its best channel and point is at least 3 × the H1 noise floor, and
no alias of its order (n' ≡ ±n mod N) on its branch lies within one half-power bandwidth
— since session 29 also an alias above the paper generator's n ≤ 60, by its own model (a tyre
has every order and no test knows where a generator stopped: the same-direction branch's
orders converge on 167.8 Hz, so the 34-point n = 34 at 167.3 Hz and its alias n = 68 are
one crowd whether or not n = 68 is simulated; 30 paper modes of the matrix leave "expected",
25 of them found, 3 mislabelled, 2 missed)
(a degenerate cos/sin pair is one mode; so is a pair of one order and branch split by less than
ζ f, at its members' mean). It is *found* when the modal table has a mode
within 0.3 % — of the mean or, since session 21, of one of the pair's members (an added mass
splits a pair by 0.5–0.6 % at ζ = 2 %: a row at one member, 0.3 % off the mean, had been
counted missed although no row was off any mode) — with the right n and branch (orders above N/2: flagged aliased, in the order
group the order aliases onto, n mod N folded to 0 … N/2 — since session 15; before, any
aliased row counted, and in 14 paper cases a crowd row of another group stood for the
n = N same mode at 167.3 Hz; cavity and
tangential modes, which the tool has no label for: any label; a free rim's "rim" mode: n = 1, not aliased,
either branch — the generators' "rim" label is the rim's share of the kinetic energy, which a test
cannot measure without the masses), *mislabelled* when only the
frequency matches, *missed* otherwise. Of the aliased modes found, the totals also count how
many rows read the truth's order (as their n or among their crowd candidates) and its branch
("aliased found: order and branch read right", since session 20): the flag alone, which the
issue asks for, accepts a row that names a far alias or the other branch. A table mode with no truth mode of any kind within
0.3 % is *spurious*; table modes within 0.3 % of a truth mode that a one-to-one matching of
table to truth leaves over are *surplus* (one mode reported twice). The diagnosis is *right*
when every effect of the case has one of its
required names adopted and nothing else is adopted but names the case's physics allows
(`EXPECTED_DIAGNOSIS` in `tiremodal_cli/workflow/validation_scoring.py`: e.g. the ring's tangential belt
also stretches, so a hoop stiffness on n = 0 may be adopted beside the tangential
coupling); nothing for "none". An effect is *detectable* when the paper's model, fitted
robustly to the case's expected truth modes as the test shows them (a pair split by less
than ζ f one mode, at its members' mean; a pair split by more its two members) with the
diagnosis's 0.1 % uncertainty, leaves a residual above the noise (χ² p < 0.01 or a mode set
aside); for an effect that is not, the diagnosis is right adopting nothing (or the right
effect). Of two effects in one case, each is judged alone (the same test with that effect
only): one the test cannot show alone is not required beside the other (its names stay
allowed).

**How far the misses are from what any estimator could do** (`benchmarks/crlb.py`, session
10): for each expected truth mode, the Cramér–Rao bound σ_f of its frequency given the
test's H1 noise per line (the generator's sensor noise over each hit's force spectrum) and
its neighbours (every recorded truth mode whose half-power band overlaps the window, a free
constant per FRF), with the residues one order per mode (u cos nθ + v sin nθ per channel,
as the tool assumes) and unstructured (every residue free). A mode with 3 σ_f > 0.3 % is
beyond the ruler's tolerance for any unbiased estimator. This is a diagnostic, not part of
the ruler: "expected" stays as above (a few marginal bounds move by × 2 with the window's
width). The bound is checked by a Monte-Carlo least-squares fit (`tests/test_crlb.py`: the
scatter over 200 draws within 20 % of it). On the found modes whose shapes hold one order,
the tool's frequency error is a median 0.75 σ (paper) and 0.58 σ (ring) — an efficient
estimator gives 0.67 σ. On the session-15 run (76eda77, all 55 cases): of the paper's 34
expected modes not found (28 missed, 6 mislabelled), 10 lie beyond the ruler's tolerance for
any unbiased estimator even with one order per mode (3 σ_f > 0.3 %: the sidewall membrane's
same n = 46, 48, 54–56 in both membrane cases, the added mass's n = 34) and 24 within it; of
the ring's 33 (28 + 5), 6 beyond (sidewall coupling's n = 47, 60; with the mass n = 31, 41, 47;
the mass's opposite n = 0) and 27 within — most of them the sidewall coupling + mass's weak
same-direction modes, whose shapes the mass mixes (purity 0.4–1.0), so the one-order bound is
optimistic there. 18 modes were found although beyond (17 of them the ring's).
Session 19 added a third model, **poly-reference** (`benchmarks/crlb_polyref.py`, `sigma_r`):
each mode's residues rank one — one participation vector over the channels, as the
estimator's order groups assume, shared by tread and sidewall — with the shape free on the
points' circumferential harmonics that show above the noise (so a shape the mass mixes is
bounded as mixed, not as one order); checked by two seeded Monte-Carlo maximum-likelihood
fits (`tests/test_crlb_polyref.py`: the spread within 15 % of the bound) and by the limits
that orders are told apart by the points and aliases are not. On the session-18 run
(8c046bd, `--misses-only`): of the paper's 32 expected modes not found, 6 are beyond 3 σ_f >
0.3 % under it (one-order model: 10: the membrane cases' same n = 54, 55 and the membrane +
cavity's n = 46, σ_f 0.10–0.11 %, and the added mass's mixed n = 2 opposite, 0.27 %); of the
ring's 38, 6 (one-order: 6: the mass's n = 0 opposite, and the sidewall coupling + mass's
mixed same n = 31, 41, 58, 61, 62, 0.16–5.4 %). The rest, 58 of 70, are within reach of an
efficient estimator: the ring's sidewall coupling's same n = 59, 61, 64 (σ_f 0.03–0.04 %;
LSCE has poles at 669.9, 688.9 and 721.5 Hz, the first two failing the pin rule — they
scatter 1.0–1.1 Hz over the model orders, more than a line, beside a stronger mode's
overlapping band — the third the noise test at ΔE < 0), the membrane's same n = 45–56
(0.02–0.10 %) and most mixed same-direction modes of the sidewall coupling + mass
(0.01–0.08 %).

Reproduce: `python benchmarks/validation.py` (about {minutes:.0f} minutes with {jobs} workers on
the machine below). The test suite runs a seeded subset (`tests/test_validation.py`).
Two runs (`--out`) compared case by case, the fits as well as the counts (a change can keep
every count and move a diagnosis): `python benchmarks/compare_runs.py BEFORE.jsonl AFTER.jsonl`.
"""


HELD_OUT = """## Held out: the same tests on noise the rules were never measured on

Every threshold measured on this matrix was measured on its seeds. `--seed-offset N` runs
the same 55 tests with every case's seed moved by N — other noise, other double hits and
overloads, other failed points — and is the check on how far the scorecard above
generalises. Sessions 14 and 15 (records not kept; `--jobs 2`, same machine; + 3000 with `--jobs 1`, both codes in the same run; scored by the ruler before its alias-class rule of session 15 — which on the matrix's seeds moves paper 16 and ring 4 found modes to mislabelled — but for the two rows so marked):

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % spurious | effect cases right | run errors |
|---|---|---|---|---|---|---|---|---|
| seeds + 1000 | 9f5ae0a (end of session 13) | paper | 1168 / 1212 (96 %) | 11 | 26 / 1438 (1.8 %) | 3: added mass 5 / 48, tangential + added mass 3 / 46, failed-points combination 11 / 69 | 12 / 13 (added mass: air_cavity) | 0 |
| | | ring | 1283 / 1334 (96 %) | 8 | 12 / 1603 (0.7 %) | 1: mass 4 / 68 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 1000 | b1ce266 (end of session 14) | paper | 1168 / 1212 (96 %) | 8 | 17 / 1406 (1.2 %) | 1: failed-points combination 11 / 69 | 13 / 13 | 0 |
| | | ring | 1284 / 1334 (96 %) | 7 | 11 / 1584 (0.7 %) | 1: mass 4 / 65 | 13 / 14 (mass) | 0 |
| seeds + 2000 | b1ce266 | paper | 1161 / 1212 (96 %) | 15 | 11 / 1418 (0.8 %) | 1: failed-points combination 4 / 66 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1285 / 1334 (96 %) | 8 | 6 / 1581 (0.4 %) | 0 | 12 / 14 (mass: air_cavity beside added_mass; 5,120 Hz Timoshenko + rim: m_w alone, the Timoshenko fit ending on rhoI's bound) | 0 |
| seeds + 1000 | 76eda77 (end of session 15) | paper | 1175 / 1212 (97 %) | 7 | 18 / 1414 (1.3 %) | 1: failed-points combination 11 / 69 | 13 / 13 | 0 |
| | | ring | 1287 / 1334 (96 %) | 7 | 12 / 1590 (0.8 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000 | 76eda77 | paper | 1167 / 1212 (96 %) | 14 | 13 / 1426 (0.9 %) | 1: failed-points combination 4 / 66 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1286 / 1334 (96 %) | 8 | 6 / 1582 (0.4 %) | 0 | 12 / 14 (as on b1ce266) | 0 |
| seeds + 3000 | ec5e4f1 (end of session 14) | paper | 1168 / 1212 (96 %) | 8 | 25 / 1421 (1.8 %) | 2: added mass 6 / 53, failed-points combination 11 / 72 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1291 / 1334 (97 %) | 7 | 9 / 1600 (0.6 %) | 0 | 12 / 14 (sidewall coupling: nothing adopted; mass: air_cavity beside added_mass) | 0 |
| seeds + 3000 | 76eda77 | paper | 1173 / 1212 (97 %) | 6 | 27 / 1428 (1.9 %) | 3: the two above and the sidewall membrane 4 / 79 (its weak same n = 60 found 0.44 % high) | 12 / 13 (as above) | 0 |
| | | ring | 1292 / 1334 (97 %) | 7 | 9 / 1602 (0.6 %) | 0 | 12 / 14 (as above) | 0 |
| seeds + 1000, the ruler's alias-class rule | 76eda77 | paper | 1157 / 1212 (95 %) | 25 | 18 / 1414 (1.3 %) | as above | 13 / 13 | 0 |
| | | ring | 1285 / 1334 (96 %) | 9 | 12 / 1590 (0.8 %) | as above | 13 / 14 | 0 |
| seeds + 2000, the ruler's alias-class rule | 76eda77 | paper | 1152 / 1212 (95 %) | 29 | 13 / 1426 (0.9 %) | as above | 12 / 13 | 0 |
| | | ring | 1284 / 1334 (96 %) | 10 | 6 / 1582 (0.4 %) | as above | 12 / 14 | 0 |
| seeds + 1000, session 16 (two orders at one frequency kept apart on a mirror-symmetric complete grid; alias-class ruler) | 5591f3a | paper | 1176 / 1212 (97 %) | 9 | 18 / 1623 (1.1 %) | 1: failed-points combination 11 / 69 | 13 / 13 | 0 |
| | | ring | 1286 / 1334 (96 %) | 8 | 12 / 1823 (0.7 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000, session 16 | 5591f3a | paper | 1168 / 1212 (96 %) | 16 | 15 / 1625 (0.9 %) | **2**: failed-points combination 4 / 66, **added mass 3 / 50** (two rows of the mass-mixed crowd between truth modes: the mass sits at the sensor's angle, which the symmetry test cannot see) | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1284 / 1334 (96 %) | 10 | 6 / 1798 (0.3 %) | 0 | **13 / 14** (the mass now right; 5,120 Hz Timoshenko + rim: m_w alone) | 0 |
| seeds + 3000, session 16 | 5591f3a | paper | 1174 / 1212 (97 %) | 8 | 27 / 1613 (1.7 %) | 2: added mass 6 / 55, failed-points combination 11 / 72 (the membrane 4 / 80, exactly at the bar: under it only because its table is one row longer; the same 27 spurious rows as 76eda77 case by case) | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1290 / 1334 (97 %) | 9 | 9 / 1812 (0.5 %) | 0 | **13 / 14** (the mass now right; the sidewall coupling adopts nothing) | 0 |
| seeds + 1000, session 18 (run's band from the force autospectrum of the accepted hits) | c2f85df | paper | 1176 / 1212 (97 %) | 9 | 18 / 1623 (1.1 %) | 1: failed-points combination 11 / 69 | 13 / 13 | 0 |
| | | ring | 1286 / 1334 (96 %) | 8 | 12 / 1824 (0.7 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000, session 18 | c2f85df | paper | 1168 / 1212 (96 %) | 16 | 15 / 1625 (0.9 %) | 2: failed-points combination 4 / 66, added mass 3 / 50 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1284 / 1334 (96 %) | 10 | 6 / 1800 (0.3 %) | 0 | **14 / 14** (the 5,120 Hz Timoshenko + rim now right: its band's top 4 Hz higher without the rejected hits) | 0 |
| seeds + 3000, session 18 | c2f85df | paper | 1174 / 1212 (97 %) | 8 | 27 / 1613 (1.7 %) | 2: added mass 6 / 55, failed-points combination 11 / 72 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1290 / 1334 (97 %) | 9 | 8 / 1812 (0.4 %) | 0 | 13 / 14 (the sidewall coupling adopts nothing) | 0 |
| seeds + 1000, session 20 (a peak no group's pole stands for re-swept at twice the order; a clear mode below every alias of a rising branch keeps its order) | 9f4d18a | paper | 1176 / 1212 (97 %) | 9 | 18 / 1623 (1.1 %) | 1: failed-points combination 11 / 69 | 13 / 13 | 0 |
| | | ring | **1290** / 1334 (97 %) | 7 | 11 / 1826 (0.6 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000, session 20 | 9f4d18a | paper | 1168 / 1212 (96 %) | 16 | 15 / 1625 (0.9 %) | 2: failed-points combination 4 / 66, added mass 3 / 50 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | **1287** / 1334 (96 %) | 9 | 6 / 1802 (0.3 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, session 20 | 9f4d18a | paper | 1174 / 1212 (97 %) | 8 | 27 / 1613 (1.7 %) | 2: added mass 6 / 55, failed-points combination 11 / 72 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | **1293** / 1334 (97 %) | 8 | 8 / 1814 (0.4 %) | 0 | 13 / 14 (the sidewall coupling adopts nothing) | 0 |
| seeds + 1000, session 21 (the ruler's split pairs found at either member; a gappy grid's reading that disagrees with its order group read at the group) | 4385365 | paper | **1179** / 1212 (97 %) | 7 | 19 / 1625 (1.2 %) | 1: failed-points combination 12 / 71 | 13 / 13 | 0 |
| | | ring | **1291** / 1334 (97 %) | 7 | 11 / 1826 (0.6 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000, session 21 | 4385365 | paper | **1169** / 1212 (96 %) | 16 | 15 / 1625 (0.9 %) | 2: failed-points combination 4 / 66, added mass 3 / 50 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | **1289** / 1334 (97 %) | 9 | 6 / 1802 (0.3 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, session 21 | 4385365 | paper | **1176** / 1212 (97 %) | 8 | 27 / 1613 (1.7 %) | 2: added mass 6 / 55, failed-points combination 11 / 72 | 12 / 13 (failed-points combination: rhoA) | 0 |
| | | ring | 1293 / 1334 (97 %) | 8 | 8 / 1814 (0.4 %) | 0 | 13 / 14 (the sidewall coupling adopts nothing) | 0 |
| seeds + 1000, session 22 (a point whose only hits bounced keeps them; a missing point read from its mirror image when the test shows the symmetry) | 10bb736 | paper | **1183** / 1212 (98 %) | 7 | 11 / 1626 (0.7 %) | 1: failed-points combination 4 / 72 (its missing point is the driving point: no mirror) | 13 / 13 | 0 |
| seeds + 1000, session 22 (and, on the gaps no image fills, a pole above the leak bound a mode of its own) | 44ad905 | paper | **1184** / 1212 (98 %) | 8 | 10 / 1626 (0.6 %) | **0** | 13 / 13 | 0 |
| | | ring | 1291 / 1334 (97 %) | 7 | 11 / 1839 (0.6 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000, session 22 | 10bb736 | paper | **1183** / 1212 (98 %) | 7 | 14 / 1643 (0.9 %) | 1: added mass 3 / 50 | **13 / 13** | 0 |
| | | ring | 1289 / 1334 (97 %) | 9 | 4 / 1801 (0.2 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, session 22 | 10bb736 | paper | **1182** / 1212 (98 %) | 7 | 17 / 1626 (1.0 %) | 1: added mass 6 / 55 | **13 / 13** | 0 |
| | | ring | **1295** / 1334 (97 %) | 6 | 8 / 1830 (0.4 %) | 0 | 13 / 14 (the sidewall coupling adopts nothing) | 0 |
| seeds + 1000, session 23 (a lumped mass on the sensors' plane seen by the clear modes' symmetric copies in other order groups: the merge no longer treats the groups as orthogonal) | 3abcd29 | paper | 1184 / 1212 (98 %) | 8 | 10 / 1620 (0.6 %) | **0** | 13 / 13 | 0 |
| | | ring | 1291 / 1334 (97 %) | 7 | 11 / 1839 (0.6 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000, session 23 | 3abcd29 | paper | 1183 / 1212 (98 %) | 7 | 12 / 1637 (0.7 %) | **0** (added mass 1 / 46) | 13 / 13 | 0 |
| | | ring | 1289 / 1334 (97 %) | 9 | 4 / 1801 (0.2 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, session 23 | 3abcd29 | paper | 1182 / 1212 (98 %) | 7 | 13 / 1618 (0.8 %) | **0** (added mass 2 / 49) | 13 / 13 | 0 |
| | | ring | 1295 / 1334 (97 %) | 6 | 8 / 1830 (0.4 %) | 0 | 13 / 14 (the sidewall coupling adopts nothing) | 0 |
| the matrix's seeds, every sensor's noise × 0.2 (0.1 % for the reference; `--noise-scale 0.2`), session 24 | 1ac395c | paper | 1191 / 1213 (98 %) | 5 | 14 / 1666 (0.8 %) | 1: tangential + added mass 4 / 49 | 13 / 13 | 0 |
| | | ring | 1298 / 1337 (97 %) | 11 | 9 / 1884 (0.5 %) | 0 | **13 / 14** (sidewall shear: m_s for tangential); no-effect cases **13 / 14** (24 points: sidewall_membrane) | 0 |
| the matrix's seeds, noise × 0.02 (0.01 %), session 24 | 1ac395c | paper | 1190 / 1213 (98 %) | 6 | 16 / 1682 (1.0 %) | 1: tangential + added mass 3 / 58 | **11 / 13** (added mass: rhoA; tangential + added mass: rhoA beside tangential); no-effect cases **13 / 14** (1,024 Hz: air_cavity) | 0 |
| | | ring | 1299 / 1337 (97 %) | 12 | 18 / 1970 (0.9 %) | 1: reference 4 / 71 | 14 / 14 | 0 |
| noise × 0.2, session 24 (the crowd test's dispersion ends at a gap of more than an alias span) | this session's | paper | 1191 / 1213 (98 %) | 5 | 14 / 1666 (0.8 %) | 1: tangential + added mass 4 / 49 | 13 / 13 | 0 |
| | | ring | 1298 / 1337 (97 %) | 11 | 9 / 1884 (0.5 %) | 0 | 13 / 14 (sidewall shear: m_s for tangential); no-effect cases **14 / 14** (the 24 points now right) | 0 |
| noise × 0.02, session 24 (as above) | this session's | paper | 1189 / 1213 (98 %) | 7 | 16 / 1682 (1.0 %) | 1: tangential + added mass 3 / 58 | 11 / 13 (as before); no-effect cases 13 / 14 (1,024 Hz: air_cavity) | 0 |
| | | ring | 1299 / 1337 (97 %) | 12 | 18 / 1970 (0.9 %) | 1: reference 4 / 71 | 14 / 14 | 0 |
| seeds + 1000, session 25 (a crowd's candidates one alias span above the branch's top; a pinned mode kept apart from a crowd's unpinned blend; a row on the wrong side of the other branch left out of the crowd test's dispersion) | c8600ad | paper | 1184 / 1212 (98 %) | 8 | 10 / 1621 (0.6 %) | 0 | 13 / 13 | 0 |
| | | ring | 1291 / 1334 (97 %) | 7 | 11 / 1840 (0.6 %) | 1: mass 4 / 65 | 13 / 14 (mass: air_cavity beside added_mass) | 0 |
| seeds + 2000, session 25 | c8600ad | paper | **1184** / 1212 (98 %) | 7 | 12 / 1642 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | **1290** / 1334 (97 %) | 8 | 4 / 1822 (0.2 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, session 25 | c8600ad | paper | **1186** / 1212 (98 %) | 5 | 13 / 1635 (0.8 %) | 0 | 13 / 13 | 0 |
| | | ring | **1297** / 1334 (97 %) | 6 | 8 / 1835 (0.4 %) | 0 | 13 / 14 (the sidewall coupling adopts nothing) | 0 |
| seeds + 1000, session 25 (and in the diagnosis: an aliased order re-read only where the model tells the class's orders apart by more than its own misfit; a row that is no normal mode no evidence of a cavity) | 4920feb | paper | 1184 / 1212 (98 %) | 8 | 10 / 1621 (0.6 %) | 0 | 13 / 13 | 0 |
| | | ring | 1291 / 1334 (97 %) | 7 | 11 / 1840 (0.6 %) | 1: mass 4 / 65 | **14 / 14** (mass: added_mass alone) | 0 |
| seeds + 2000, session 25 (as above) | 4920feb | paper | 1184 / 1212 (98 %) | 7 | 12 / 1642 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1290 / 1334 (97 %) | 8 | 4 / 1822 (0.2 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, session 25 (as above) | 4920feb | paper | 1186 / 1212 (98 %) | 5 | 13 / 1635 (0.8 %) | 0 | 13 / 13 | 0 |
| | | ring | 1297 / 1334 (97 %) | 6 | 8 / 1835 (0.4 %) | 0 | **14 / 14** (sidewall coupling: sidewall_membrane, 9.45 → 0.004 %) | 0 |
| noise × 0.2, session 25 | c8600ad (4920feb alike) | paper | 1192 / 1213 (98 %) | 4 | 14 / 1671 (0.8 %) | 1: tangential + added mass 4 / 49 | 13 / 13 | 0 |
| | | ring | 1298 / 1337 (97 %) | 11 | 10 / 1887 (0.5 %) | 0 | 13 / 14 (sidewall shear: m_s for tangential); no-effect cases 14 / 14 | 0 |
| noise × 0.02, session 25 | c8600ad (4920feb alike) | paper | 1192 / 1213 (98 %) | 6 | 17 / 1688 (1.0 %) | 1: tangential + added mass 3 / 58 | 11 / 13 (as before); no-effect cases 13 / 14 (1,024 Hz: air_cavity) | 0 |
| | | ring | 1299 / 1337 (97 %) | 12 | 18 / 1974 (0.9 %) | 1: reference 4 / 71 | 14 / 14 | 0 |
| seeds + 1000, session 26 (the package as at session 25's end, run again) | fed11f3 | paper | 1184 / 1212 (98 %) | 8 | 10 / 1621 (0.6 %) | 0 | 13 / 13 | 0 |
| | | ring | 1291 / 1334 (97 %) | 7 | 11 / 1840 (0.6 %) | 1: mass 4 / 65 | 14 / 14 | 0 |
| seeds + 1000, session 26's refinement judged by the groups' rows on complete symmetric grids (measured, not adopted: docs/lsce.md, "Session 26") | e364797 | paper | 1183 / 1212 (98 %) | 8 | 11 / 1621 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1290 / 1334 (97 %) | 7 | 12 / 1840 (0.7 %) | 1: mass 4 / 65 | 14 / 14 | 0 |
| seeds + 2000, the same (not adopted) | e364797 | paper | 1184 / 1212 (98 %) | 8 | 11 / 1642 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1290 / 1334 (97 %) | 8 | 4 / 1822 (0.2 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, the same (not adopted) | e364797 | paper | 1186 / 1212 (98 %) | 5 | 13 / 1635 (0.8 %) | 0 | 13 / 13 | 0 |
| | | ring | 1297 / 1334 (97 %) | 6 | 8 / 1835 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 28 (modal.beside: a weak mode beside a strong one of its group, fitted by nested fits; a weaker pole on a complete grid located 3 × its scatter from the stronger) | a81e46a | paper | 1187 / 1212 (98 %) | 5 | 10 / 1624 (0.6 %) | 0 | 13 / 13 | 0 |
| | | ring | 1294 / 1334 (97 %) | 6 | 12 / 1843 (0.7 %) | 1: mass 4 / 65 | 14 / 14 | 0 |
| seeds + 2000, session 28 (as above) | a81e46a | paper | 1186 / 1212 (98 %) | 7 | 12 / 1645 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1292 / 1334 (97 %) | 8 | 9 / 1829 (0.5 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 29: session 28's code (892ee88) scored by session 29's ruler (an alias above the paper generator's n ≤ 60 counts in the crowd test: paper expected 1212 → 1182) | 892ee88 | paper | 1163 / 1182 (98 %) | 2 | 10 / 1624 (0.6 %) | 0 | 13 / 13 | 0 |
| | | ring | 1294 / 1334 (97 %) | 6 | 12 / 1843 (0.7 %) | 1: mass 4 / 65 | 14 / 14 | 0 |
| seeds + 1000, session 29 (a pole of another group that moves the channels otherwise, visible, pinned and a normal mode, is another mode: modal.merge) | 3fd76d9 | paper | 1163 / 1182 (98 %) | 2 | 11 / 1628 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | **1299** / 1334 (97 %) | 4 | 12 / 1848 (0.6 %) | 1: mass 4 / 65 | 14 / 14 | 0 |
| seeds + 2000, session 30: session 29's code (934e993) run again, on an Intel Xeon (AVX-512) where sessions 26–29 ran on an AMD EPYC | 934e993 | paper | 1162 / 1182 (98 %) | 3 | 14 / 1647 (0.9 %) | **1: added mass 3 / 47** (158.83, 161.68 Hz: the same-direction crowd's blends, kept apart by session 29's channel rule; 1 / 47 without it) | 13 / 13 | 0 |
| | | ring | 1297 / 1334 (97 %) | 7 | 8 / 1835 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, the same | 934e993 | paper | 1167 / 1182 (99 %) | 3 | 13 / 1648 (0.8 %) | **1: added mass 3 / 50** (161.66, 161.76, 257.69 Hz) | 13 / 13 | 0 |
| | | ring | 1305 / 1334 (98 %) | 4 | 14 / 1849 (0.8 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, session 30 (a pole kept apart by its channel shape alone, in a crowd of its alias class, is a blend: dropped; modal.misreads) | 6d57eb6 | paper | 1162 / 1182 (98 %) | 3 | **12** / 1644 (0.7 %) | **0** | 13 / 13 | 0 |
| | | ring | 1297 / 1334 (97 %) | 7 | 8 / 1835 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, the same | 6d57eb6 | paper | 1167 / 1182 (99 %) | 3 | 13 / 1647 (0.8 %) | 1: added mass 3 / 50 (161.66 Hz is read n = 11 opposite, out of the crowd, so no crowd's blend; 161.76 Hz was never kept apart by the channel rule) | 13 / 13 | 0 |
| | | ring | 1305 / 1334 (98 %) | 4 | 14 / 1849 (0.8 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 30 (as above; on this machine session 29's code was run again on the six mass and coupling cases only: unchanged there but the added mass and tangential + added mass's adopted rows 46 → 43, 45 → 43, crowd rows on truth modes) | 6d57eb6 | paper | 1163 / 1182 (98 %) | 2 | 11 / 1622 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1299 / 1334 (97 %) | 4 | 13 / 1850 (0.7 %) | 1: mass 4 / 65 | 14 / 14 | 0 |
| seeds + 1000, session 31 (a pole of another order group neither on a peak of its own nor pinned by its data is the stronger mode's copy: modal.merge) | 79ad8b0 | paper | 1163 / 1182 (98 %) | 2 | 11 / 1622 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1299 / 1334 (97 %) | 4 | **10** / 1847 (0.5 %) | **0** (mass 3 / 64: its copy of the opposite n = 20 at 505.66 Hz merged) | 14 / 14 | 0 |
| seeds + 2000, session 31 (as above) | 79ad8b0 | paper | 1162 / 1182 (98 %) | 3 | 12 / 1644 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1297 / 1334 (97 %) | 7 | 8 / 1834 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, session 31 (as above) | 79ad8b0 | paper | 1167 / 1182 (99 %) | 3 | **12** / 1646 (0.7 %) | **0** (added mass 2 / 49: its row at 257.69 Hz, a copy of the opposite n = 10, merged) | 13 / 13 | 0 |
| | | ring | 1305 / 1334 (98 %) | 4 | 14 / 1849 (0.8 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 31 (and the channel rule's normal-mode check on the weaker pole's part that the stronger mode's copy cannot hold) | 4f37560 | paper | 1163 / 1182 (98 %) | 2 | 11 / 1622 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | **1300** / 1334 (97 %) | 4 | 10 / 1848 (0.5 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, the same: only the seven mass, coupling and membrane cases run (the others as on 79ad8b0) | 4f37560 | paper | 1162 / 1182 (98 %) | 3 | 12 / 1644 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1296 / 1334 (97 %) | 7 | 8 / 1833 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 3000, the same (seven cases run) | 4f37560 | paper | **1168** / 1182 (99 %) | 3 | 12 / 1648 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | **1306** / 1334 (98 %) | 4 | 14 / 1850 (0.8 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 33 (the band's top: modal.refine) | 30cb58c | paper | 1163 / 1182 (98 %) | 2 | 12 / 1621 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1302 / 1334 (98 %) | 4 | 11 / 1852 (0.6 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, session 33 | 30cb58c | paper | 1163 / 1182 (98 %) | 3 | 9 / 1643 (0.5 %) | 0 | 13 / 13 | 0 |
| | | ring | 1297 / 1334 (97 %) | 7 | 7 / 1832 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 34 (a weak mode out of its branch's order read on the other branch: modal.classify) | 5585dee | paper | 1163 / 1182 (98 %) | 2 | 12 / 1659 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1302 / 1334 (98 %) | 4 | 11 / 1870 (0.6 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, session 34 | 5585dee | paper | **1165** / 1182 (99 %) | 3 | 9 / 1683 (0.5 %) | 0 | 13 / 13 | 0 |
| | | ring | 1297 / 1334 (97 %) | 7 | 7 / 1848 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 35, on an AMD EPYC (sessions 30–34: an Intel Xeon): session 34's end | d2003f2 | paper | 1163 / 1182 (98 %) | 2 | 11 / 1657 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1302 / 1334 (98 %) | 4 | 10 / 1867 (0.5 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 35 (a weak pole refined in every order group: modal.refine) | 01f9ada | paper | 1163 / 1182 (98 %) | 2 | 11 / 1657 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | 1302 / 1334 (98 %) | 4 | **11** / 1867 (0.6 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, session 35, the same machine: session 34's end | d2003f2 | paper | 1165 / 1182 (99 %) | 3 | 9 / 1681 (0.5 %) | 0 | 13 / 13 | 0 |
| | | ring | 1299 / 1334 (97 %) | 6 | 7 / 1849 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, session 35 (as above) | 01f9ada | paper | **1166** / 1182 (99 %) | 2 | **8** / 1681 (0.5 %) | 0 | 13 / 13 | 0 |
| | | ring | 1299 / 1334 (97 %) | 6 | 7 / 1849 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 36 (a leak under the copy bound on unmixed orders; a single-reference pole split by its drifting shape joined) | 17562b1 | paper | **1165** / 1182 (99 %) | 2 | **12** / 1660 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | **1303** / 1334 (98 %) | 4 | **12** / 1869 (0.6 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 37 (on mixed orders a pinned pole of its own group, moving the channels otherwise, is no copy: modal.own_mode; read at its group where the symmetry is broken: classify) | 27080b6 | paper | 1165 / 1182 (99 %) | 2 | 12 / 1664 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | **1305** / 1334 (98 %) | 4 | 12 / 1873 (0.6 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, session 37, the same machine: session 36's end | f31fe9d | paper | 1166 / 1182 (99 %) | 3 | 9 / 1682 (0.5 %) | 0 | 13 / 13 | 0 |
| | | ring | 1301 / 1334 (98 %) | 6 | 7 / 1852 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 2000, session 37 (as above) | 27080b6 | paper | 1166 / 1182 (99 %) | 3 | 9 / 1684 (0.5 %) | 0 | 13 / 13 | 0 |
| | | ring | **1304** / 1334 (98 %) | 6 | 7 / 1856 (0.4 %) | 0 | 14 / 14 | 0 |
| seeds + 1000, session 38 on an Intel Xeon (a weak mode of another family keeps its spatial order and is no misread on a symmetric test; the walk's step from the branch's two highest orders) | 73c6563 | paper | 1165 / 1182 (99 %) | 2 | 12 / 1668 (0.7 %) | 0 | 13 / 13 | 0 |
| | | ring | **1306** / 1334 (98 %) | 3 | 12 / 1878 (0.6 %) | 0 | 14 / 14 | 0 |

Session 31's rows, case by case against session 30's (6d57eb6) at the same seeds on the same
machine: at + 1000 the ring's noise case loses a spurious row (224.82 Hz), its sidewall coupling
finds its same n = 61 and the coupling + mass loses its n = 42 (489.52 Hz) and a spurious row
(426.39 Hz), the mass its copy at 505.66 Hz; at + 2000 one ring row fewer, none spurious or
found; at + 3000 the added mass's 257.69 Hz. At the matrix's seeds (below) the ring's
5,120 Hz mobility combination loses a spurious row (1,311.55 Hz) and the sidewall coupling +
mass its weak same n = 64 (721.12 Hz: a pole 2.1 × its row's residual, scattered 1.8 Hz over
the model orders, 6.6 Hz from the opposite n = 27 of group 7). For the first time no
case is over 5 % spurious at any of the four seeds; every diagnosis is right at all four.
The channel rule's check on the part of the weaker pole that the stronger mode's copy cannot
hold (4f37560) moves only the sidewall coupling + mass and, at + 3000, the membrane + cavity:
found + 1 at the matrix's seeds (the same n = 49 at 562.26 Hz), + 1 at + 1000 (n = 21 at
283.44 Hz), − 1 at + 2000 (that n = 21), + 2 at + 3000 (n = 21; the membrane + cavity's same
n = 37 at 262.79 Hz); no spurious row added or lost at any seed.

Session 24's quieter runs: the same tests with every sensor's noise (force and responses) 5 ×
and 50 × lower. Nothing the matrix misses is the noise's: the same weak same-direction modes
are missed at 0.1 % and 0.01 % (paper missed 19 → 17 → 17, ring 24 → 28 → 26; the membrane's
same n = 45, 46, 51, 54–56 and the sidewall coupling's n = 47, 59, 60, 64 at every level), and a quieter test is worse
elsewhere — more rows adopted (ring 1835 → 1884 → 1970), spurious up (paper 7 → 14 → 16, ring
8 → 9 → 18: copies of strong modes in other order groups at 0.1–0.5 half-widths, a crowd's
strong modes placed 0.3 % off), and diagnoses go wrong (at 0.1 % the ring's 24 points adopt a
false sidewall_membrane and its sidewall shear m_s for tangential; at 0.01 % the paper's added
mass is read as rhoA, its 1,024 Hz case adopts a false air_cavity). The thresholds were measured
at the matrix's noise (0.5–5 %); what scales with the noise in them, and what does not (a
record's truncated decay, the points' gain errors, the model's own misfit), is the next thing to
measure (docs/lsce.md, "Session 24"). One chain is fixed: the crowd test's dispersion no longer
runs through an order the alias walk read beyond a gap of more than N/2 orders (a weak copy read
as the same n = 51 had taken the 24-point crowd's flags): at 0.1 % the ring's 24 points are
right again (base RMS 0.083 → 0.020 %); at 0.01 % three base fits come down (the references
0.073 → 0.002 % and 0.012 → 0.001 %, the ring's rim 0.049 → 0.001 %) and the paper's 48-point
combination reads its same n = 24 at 170.13 Hz as a crowd with n = 72 — which lies, by the
branch's saturation, within its bandwidth, but beyond the generator's n ≤ 60, so the ruler
scores it mislabelled. The matrix and the seeds + 1000, + 2000, + 3000 are unchanged to the
count (one base RMS at + 2000, 20.8 → 22.3 %, same diagnosis).

Session 25's rows, against session 24's at the same seeds: found paper + 0, + 1, + 4 and ring
+ 0, + 1, + 2 at + 1000, + 2000, + 3000 (pinned modes of other order groups kept apart from a
crowd's unpinned blend: the membrane's weak same-direction n = 31, 34, 38, a 48-point crowd's
n = 48, the ring's 48-point opposite n = 29 and its sidewall coupling's same n = 51), spurious
unchanged at every seed, every diagnosis as before (the ring's mass at + 1000 and its sidewall
coupling at + 3000 still wrong; the latter is no search failure — the full evolutionary search
of every refit, `benchmarks/search_equivalence.py`, ends where the local one does, at 9.4 % RMS
with the same-direction n = 22–25 set aside). Both are right since 4920feb (docs/diagnose.md):
the sidewall coupling's in-phase n = 19 at 265.6 Hz had been re-read as n = 87 by the base
model, which puts every order of that class on its flat top alike — a model now re-reads an
order only when the class's other orders lie a whole outlier limit farther from the mode —
and the label, protected in every candidate's fit, had kept the membrane out; the mass's
air cavity had taken a mass-mixed pair member at 189.8 Hz (MPC 0.21) for its mode — a row that
is no normal mode is no longer evidence of an extra one. Every diagnosis at the matrix's seeds
and at + 1000, + 2000, + 3000 is right; counts unchanged. At 0.1 % noise paper + 1 found, ring one crowd blend
more reported (161.86 Hz in the 24-point case's group 11, between n = 11 and 13 within a
bandwidth: the ruler's crowd, counted spurious).At 0.01 % paper found 1189 → 1192, spurious
16 → 17, the same three diagnoses wrong; the crowd limit brings the 24-point cases' base fits
0.080 → 0.003 % (ring) and 0.013 → 0.001 % (paper). The 1,024 Hz case's false air_cavity is a
copy of its n = 4 at 98.20 Hz in group 1 (0.2 % of the response), which the copy rule tried in
session 25 removed while losing the matrix's weak modes (docs/lsce.md, "Session 25").

Session 23's held-out runs, case by case against session 22's: only the paper's two added-mass
cases move (the order-mixing test, docs/lsce.md "Session 23", finds their mass on the sensors'
plane at every seed; no other case reaches it). The added mass: + 1000 adopted 46 → 44 (spurious
0 → 0), + 2000 spurious 3 → 1 of 46 (the two rows of the mass-mixed crowd at 158.8 and 161.7 Hz
merged into their modes), + 3000 6 → 2 of 49 (the copies of the opposite n = 0 … 5 at 178–183 Hz
merged); tangential + added mass: rows 47 → 43, 50 → 48, 48 → 46, found unchanged. Found totals
unchanged at every seed; every diagnosis as before. The one case left over 5 % is the ring's
mass at + 1000 (4 / 65: two biased members of split pairs, a row between two modes and a copy;
its mass is off the sensors' plane, where the mirror test already sets the merge).

Session 22's held-out runs, case by case against session 21's: only the two one-hit
combinations with bounces and overloads move (every other record is the same). Their bounced
points are kept (docs/frf.md), so each loses only its overloaded point, and that point is read
from its mirror image (docs/lsce.md, "Session 22") unless it lies on the sensors' plane. The
paper's failed-points combination: + 1000 found 57 → 61, spurious 12 → 4 of 72 (its overloaded
point is the driving point, its own mirror: the gappy path, still 5.6 % spurious); + 2000 49 →
63, 4 → 3 of 84, rhoA → right; + 3000 58 → 64, 11 → 1 of 85, rhoA → right. The ring's 1,024 Hz
combination: 32 / 32 at every seed, spurious 0. With the leak bound on the gaps no image
fills (44ad905), + 1000 rerun whole: only the failed-points combination moves (61 → 62 found,
spurious 4 → 3 of 72: no paper case over 5 % left); at + 2000 and + 3000 the two gappy
combinations were rerun and give the same records (their lost points are filled).

Session 21's held-out runs: at + 1000, case by case against session 20's code (63fac93, rerun),
two cases move — the ring's sidewall coupling + mass (found 67 → 68: its n = 29 opposite, a row
at one member of the mass's pair, now found by the ruler's split-pair rule) and the paper's
failed-points combination (found 54 → 57, spurious 11 → 12 of 71: the gappy-grid reading). At
+ 2000 and + 3000 the totals are against session 20's table (paper + 1 and + 2, ring + 2 and 0
found); the two failed-points combinations were run with both codes there and give the same
records. At + 2000 and + 3000 the paper's failed-points combination
collapses before the walk (base fit 84 and 96 % RMS, rhoA adopted): the opposite crowd n = 0 … 4
at 184–190 Hz is found in none of its own order groups, only as leaks in groups 6 and 9 with
clear readings (docs/lsce.md, "Session 21").

Session 20's held-out runs, case by case against session 18's (c2f85df): only three ring
cases move, at every seed — the 5,120 Hz tangential combination (+1 found, −1 mislabelled: its
n = 1 opposite read as n = 1), the 5,120 Hz Timoshenko + rim combination (+1: the rim's n = 1 at
24.45 Hz) and the 40-point 5,120 Hz rim combination (+2, +1, +1: its low modes, re-swept); the
paper's records are the same. Aliased modes found whose order and branch are read right:
paper 398 / 414, 376 / 413, 366 / 411; ring 410 / 422, 399 / 419, 413 / 426.

What does not hold on other seeds: (1) **the paper's failed-points combination** (2,560 Hz,
24 points, one hit, 2 % noise, double hits and overloads: 5 points fail) — at seven seeds
besides the matrix's it adopted 4–11 modes more than 0.3 % from any truth mode (found 49–58
of 65), mostly biased estimates (0.3–0.5 %) of the crowd's low orders and of the opposite
branch at 550–900 Hz, and at one seed three poles fitted to the noise below the band's top
(972–988 Hz, ζ 0.5–0.9 % among modes at 3 %); until session 14 two of those seeds ended in
"no stable mode" (the order-held fit's rank, docs/lsce.md); (2) **the ring's mass**: biased
split-pair members (the pairs split by 0.6 % at ζ = 2 %) and an air cavity adopted on a stray
row read at spatial order 1 in the cavity band, its coupling γ insignificant (|t| 0.2–0.5);
(3) **the weak sidewall modes** of the ring's sidewall coupling (with and without the mass):
3–10 fewer found at other seeds — modes at the noise's edge, stable at few model orders;
(4) since session 15, **the paper membrane's weak same-direction modes**, now found where
their best channel shows them, are at times estimated 0.3–0.6 % off (crowded neighbours): at
+ 3000 the membrane goes over the bar, 4 of 79.

What the held-out spurious rows are (session 18, `benchmarks/spurious.py` on the kept runs at
c2f85df; classes by the distance to the nearest truth mode in its half-power half-widths): at
+ 1000, 19 biased (within half a half-width of a truth mode no other row reports, but over
0.3 % off), 4 copies, 7 between truth modes, none far; at + 2000, 13, 5, 1 and 2 far; at + 3000,
19, 10, 6, none far. Most are real modes estimated 0.3–1 % off (at ζ ≈ 3–4 %, a tenth of a
half-width), which the ruler counts twice — missed and spurious. The rest (7, 3 and 6) lie
between truth modes or far from them: the paper's failed-points combination's three poles under
the band's top (972–988 Hz, + 1000), the ring's 1,024 Hz failed-points combination's two rows at
34 and 49 Hz (+ 2000), the paper's added mass's three rows between the crowd and its n = 0
(178–182 Hz, + 3000), and single rows of the ring's noise, mass and 5,120 Hz cases.
"""


HELD_OUT_LEVELS_TEXT = """## Held out: set-ups the matrix never had (session 32)

`--held-out-levels 12` runs 12 seeded random tests per generator at levels no rule was
measured on (`validation.HELD_OUT_LEVELS`): sample rates 1,600, 3,200 and 4,096 Hz; 20, 30,
36 and 60 points; 2 and 4 hits; 1 % and 3 % noise; 1 s and 4 s records (1 and 0.25 Hz
lines: the matrix has 0.5 Hz only); every form; faults or none; none, one or two physical
effects (seeds 5000 …; `tests/test_validation.py` checks that no level is a matrix level).
The first run (4c728f0, the code of session 31) and the same 24 tests after this session's
two estimator changes (a678815: the band's top where one channel measures coherently, the
rescue's one-group excuse dropped on orthogonal grids), `--jobs 1` and `--jobs 2`:

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % | diagnoses right |
|---|---|---|---|---|---|---|---|
| held-out levels | 4c728f0 | paper | 625 / 685 (91 %) | 3 | 14 / 822 (1.7 %) | 0 | 11 / 12 |
| | | ring | 682 / 704 (97 %) | 5 | 8 / 876 (0.9 %) | 0 | 10 / 12 |
| held-out levels | a678815 | paper | **671** / 685 (98 %) | 2 | 20 / 877 (2.3 %) | 0 (most: 3 / 64) | **12** / 12 |
| | | ring | 682 / 704 (97 %) | 5 | 8 / 876 (0.9 %) | 0 | 10 / 12 |

The matrix at its own seeds is unchanged case by case by the two changes; at seeds + 1000
(a678815 against 4f37560) the paper is unchanged and the ring finds 1300 → 1302 (the 5,120 Hz
rim combination's n = 41 and 42 opposite at 1,211 and 1,252 Hz, above the old band's top),
spurious 10 → 11 of 1,853 (one row of that case at 1,194.54 Hz, between truth modes); at seeds +
2000 (against 4f37560 on the seven mass, coupling and membrane cases, 79ad8b0 on the rest) the
paper is unchanged and the ring finds 1296 → 1298 (the same two modes of that case), spurious
8 of 1,835.

What the first run found, by cause:

* **The band's top in receptance** (four paper tests, 45 modes): the median coherence over
  every FRF ended the band where the rim and sidewall channels, far below the tread in
  receptance at high frequency, fell under the noise threshold (60 points, 4,096 Hz: 714 Hz,
  the tread coherent to 1,100 Hz and 22 ruler-visible modes above the band). Fixed: above
  the last run the median over every FRF supports, the band goes on while one channel's
  median over its points does (docs/lsce.md, "Band"). The matrix's receptance test (2,048 Hz)
  never reached that point.
* **A low mode beside another group's** (the 20-point tangential + viscoelastic test): the n =
  1 same, 0.57 Hz below the n = 0, got no stable pole in its group's sweep, and the rescue
  excused its band by the n = 0 of group 0. On an orthogonal grid one other group's pole is
  no excuse now (docs/lsce.md, "A peak no sweep found"). Its diagnosis (m_s and the belt's
  hoop stiffness for the tangential stiffness the missing n = 1 carried) is now right.
* **Not fixed: a second family on one branch** (the two ring diagnoses). The ring's sidewall
  shear (with the coupling, 36 points) and its extensible belt (with the coupling, 20
  points) hold a second family of in-phase modes (n = 1–3 at 96–98 Hz beside the branch's
  own n = 1–4 at 43–91 Hz; a second n = 1 same at 166.9 Hz beside the first at 45.4 Hz).
  The alias walk takes each order once per branch, so the second family's weak rows are
  read as aliases (n = 33–35, n = 19). The shear test's diagnosis then needs three effects
  (the membrane, the belt's hoop stiffness that brings back its breathing mode, and the
  tangential stiffness, refused in round 2 as compensation): it stops at `max_effects` = 2,
  and its verdict now says so. The belt test's n = 19 row, unexplained in the cavity band,
  is taken for an air cavity (its coupling γ vanishes). Treating weak rows the walk aliased
  before the branch reached N/2 as contradicted (as clear rows are) keeps their spatial
  orders, but then the misread-order rule drops the n = 1 row and a later order is lost (−1
  found): not adopted.
* **Still missed**: the ring's sidewall coupling's weak same-direction aliases on 20 points
  (n = 38–53, 10 of them), the paper membrane's weak aliases (as on the matrix), and the
  band's highest mode where the band ends at fs / 2.56 (n = 41 opposite at 1,211 Hz at
  3,200 Hz, estimated 0.4–1.9 % high from one flank: three spurious rows with it).

**Session 33: the band's top** (30cb58c; docs/lsce.md, "Session 33: the band's top"). The
edge refinement runs before the edge check, fits a pole beyond the band's top where its
window reaches it, drops the edge poles the FRFs do not locate, holds copies, and on complete
symmetric grids judges a move by the group's rows alone:

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % | diagnoses right |
|---|---|---|---|---|---|---|---|
| held-out levels | 30cb58c | paper | **672** / 685 (98 %) | 2 | **18** / 875 (2.1 %) | 0 (most: 4 / 88) | 12 / 12 |
| | | ring | 682 / 704 (97 %) | 5 | **7** / 875 (0.8 %) | 0 | 10 / 12 |

The 20-point 3,200 Hz tests find n = 41 in two of three and lose their three rows by the
top; the 36-point 3,200 Hz test with 1 s records loses its n = 41 (refined in its group from
1,209.78 to 1,217.27 Hz, its half-power band then across the top) and the 60-point 4,096 Hz
receptance test gains a row at 1,304.43 Hz. The matrix: paper 1168 → 1170 found, mislabelled
1 → 0, spurious 9 → 7; ring spurious 9 → 6; at seeds + 1000 (e8cd2b2, before the pole beyond
was damped as its group's modes) paper 1163 found, spurious 11 → 12, ring 1302, 11.

**Session 34: a weak mode's branch reading** (5585dee; docs/lsce.md, "Session 34"). A mode
under 15 % of its band's response, out of its branch's order, is read on the other branch
whatever its branch confidence when exactly one order of its alias class fits there (a
weak row's branch reading is wrong 100 × as often as a strong one's). The held-out levels
are unchanged in found and spurious (paper 672 / 685, 18 spurious; ring 682 / 704, 7): four
more rows, each within 0.3 % of a truth mode. The 36-point 1 s test's n = 41 stays missed
(a change that finds it, measured and not adopted: docs/lsce.md).

And (d2003f2) on a test whose FRFs show a symmetric structure with unmixed orders, a split
pair's weaker member is dropped when it is also the broader: cos and sin modes of one order
share one frequency there, and the weaker pole is a blend of what its group's fit leaves
beside the mode.

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % | diagnoses right |
|---|---|---|---|---|---|---|---|
| held-out levels | d2003f2 | paper | 672 / 685 (98 %) | 2 | **8** / 867 (0.9 %) | 0 | 12 / 12 |
| | | ring | 682 / 704 (97 %) | 5 | **5** / 873 (0.6 %) | 0 | **11** / 12 |

Eight of the ten rows the 20-point paper tests had near 150 and 156 Hz go (the 4,096 Hz
receptance test keeps 150.59 Hz); the ring's 20-point extensible + sidewall-coupling test no
longer adopts air_cavity beside its two effects. Left: the ring's sidewall shear + coupling
(a second family on one branch), the 36-point 1 s test's n = 41.

**Session 35: a weak pole refined in every order group** (01f9ada; docs/lsce.md, "Session
35"), not only in one whose fit dropped a pole. Both codes run on this session's machine (an
AMD EPYC; sessions 30–34 ran on an Intel Xeon, where d2003f2's ring diagnoses were 11 / 12:
here the 20-point extensible + coupling test still adopts air_cavity beside its two effects):

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % | diagnoses right |
|---|---|---|---|---|---|---|---|
| held-out levels | d2003f2 (this machine) | paper | 672 / 685 (98 %) | 2 | 8 / 870 (0.9 %) | 0 | 12 / 12 |
| | | ring | 682 / 704 (97 %) | 5 | 5 / 873 (0.6 %) | 0 | 10 / 12 |
| held-out levels | 01f9ada | paper | 672 / 685 (98 %) | 2 | 8 / 870 (0.9 %) | 0 | 12 / 12 |
| | | ring | 682 / 704 (97 %) | 5 | **6** / 873 (0.7 %) | 0 | 10 / 12 |
| held-out levels, session 36 (a leak under the copy bound on unmixed orders: modal.leaks; a single-reference pole split by its drifting shape joined: modal.stabilization) | 17562b1 | paper | **673** / 685 (98 %) | 2 | 8 / 873 (0.9 %) | 0 | 12 / 12 |
| | | ring | **686** / 704 (97 %) | 5 | 6 / 878 (0.7 %) | 0 | **11** / 12 |
| held-out levels, session 37 (on mixed orders a pinned pole of its own group, moving the channels otherwise, is no copy: modal.own_mode; read at its group where the symmetry is broken: classify) | 27080b6 | paper | 673 / 685 (98 %) | 2 | 8 / 873 (0.9 %) | 0 | 12 / 12 |
| | | ring | 686 / 704 (97 %) | 5 | 6 / 877 (0.7 %) | 0 | 11 / 12 |

The paper's 36-point 1 s membrane test trades a row at 367.34 Hz for one at 338.05 Hz; the
ring's 20-point extensible + coupling test gains one at 723.12 Hz. Nothing else moves.
Session 37: nothing moves but the ring's 36-point extensible + mass test, one surplus row
fewer (64 → 63 adopted, every count the same).

Session 38 (73c6563) on the same 24 tests, against session 37's code run again here (2da7664 on
an Intel Xeon; session 37's rows above are the EPYC's): ring 686 → **688** / 704 found,
mislabelled 5 → 3 (the shear + coupling's and the extensible + coupling's second-family
n = 1 same), spurious 5 / 877 unchanged; paper 673 / 685, 8 / 870 unchanged; diagnoses 12 / 12
and 10 / 12 with both codes on this machine.

**A fresh draw** (`--held-out-seed 7000`, session 38: 24 other level combinations, looked at
by no earlier session), session 37's code (2da7664) against session 38's (73c6563):

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % | aliased read right | diagnoses right |
|---|---|---|---|---|---|---|---|---|
| held-out draw 7000 | 2da7664 | paper | 555 / 610 (91 %) | 7 | 9 / 751 (1.2 %) | 0 | 256 / 256 | 8 / 8 |
| | | ring | 625 / 640 (98 %) | 5 | 18 / 830 (2.2 %) | 2 (5 / 73, 4 / 62) | 223 / 246 | 7 / 8 |
| held-out draw 7000 | 73c6563 | paper | 555 / 610 (91 %) | 7 | 9 / 751 (1.2 %) | 0 | 256 / 256 | 8 / 8 |
| | | ring | **626** / 640 (98 %) | **4** | 18 / 830 (2.2 %) | 2 (5 / 73, 4 / 62) | **245** / 246 | **8** / 8 |

The ring's 36-point sidewall shear + Timoshenko finds its second family's n = 1; the 20-point
cavity + mass reads its opposite orders 20 … 41 right (they were one or two alias spans too
high) and its diagnosis turns right (`rhoA` at 98 % base RMS → `extensible_belt`,
`air_cavity` at 0.33 → 0.29 %). The paper's 48 misses are its two 30-point sidewall membrane +
mass tests (36 and 18 same-direction modes: docs/lsce.md, "Known limit"). The two ring tests
over 5 % spurious have 1 s records, 2 hits and 3 % noise: every spurious row of the draw lies
within 1.6 % of a truth mode, most within 2 σ of their own reported frequency uncertainty
(docs/lsce.md, "Session 38").

**Session 39** (docs/lsce.md, "Session 39": a blend the sweep's top resolves; a crowd's
bandwidth from one mode's damping). The fresh draw (seed 7000), e84e7d0 against 38dbdcf:
ring 626 → **630** / 640 found, mislabelled 4 → **1**, spurious 18 → 17 / 832; paper
unchanged at 555 / 610, 7 mislabelled, spurious 9 → 8 / 751; aliased read right 245 / 246;
the same three ring tests over 5 % spurious (4 / 74, 4 / 62, 4 / 77) with both codes. The
held-out levels (seed 5000), the same two codes: ring 688 → **689** / 704, spurious 6 → 5;
paper unchanged at 673 / 685, 8 / 873; diagnoses 12 / 12 and 11 / 12 with both. The last two
conditions of the blend test (7f32514: the parts' half-power bands overlap the blend's; no
blend test on a grid with points missing) change no matrix count and none at seeds + 1000;
the draw 7000 at d77c049 gives the same counts (ring 630 / 640, 1, 17 / 831; paper 555 / 610,
7, 8 / 751; aliased 245 / 246 and 256 / 256).

**Session 42** (347d378, the code of 7f32514; an Intel Xeon). The held-out levels (seed 5000),
not run at this code before: paper 673 / 685, 2 mislabelled, 8 / 870 spurious, diagnoses
12 / 12; ring **691** / 704, 1 mislabelled, **4** / 878, diagnoses **10** / 12 (38dbdcf on
the EPYC: 689, 5, 11 / 12). The two wrong ring diagnoses are the 36-point sidewall shear +
coupling (sidewall_membrane and extensible_belt adopted) and the 20-point extensible +
coupling (air_cavity beside its two effects, as d2003f2 and 01f9ada read it on the EPYC in
session 35). Cases over 5 % spurious: none. Tests at levels outside both draws (odd point
counts, 0.5 s and 8 s records, 10 % noise, 8 hits, 8,192 Hz): docs/lsce.md, "Session 42".
The draw 7000's three ring tests with 1 s records, 2 hits and 3 % noise, at five noise
realisations each: spurious 19 / 363, 2 / 325 and 23 / 313 rows. The errors repeat from
realisation to realisation (LSCE's noise bias on modes of 1–2 lines per half-width, which
the FRFs' least-squares refinement removes), so they are not the tests' information limit
that session 38 read. Refining every strong pole was measured and not adopted: matrix paper
1173 → 1171 found, spurious 6 → 14; ring 1311 → 1310, 5 → 6 (docs/lsce.md, "Session 42").
Adopted instead: a strong pole refined when alone in its window, on complete symmetric
grids with unmixed orders. The matrix is unchanged in every count. The draw 7000 gives ring
630 → 632 / 640 found and 17 → 15 / 831 spurious, with two ring tests still over 5 % (4 / 62,
4 / 76); the paper is unchanged (555 / 610, 8 / 751).

**Session 45: a third draw** (`--held-out-seed 9000`: 24 level combinations no session had
seen, run once at e88c279 — the modal stage of session 44's last code — and not looked at
before the run):

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % | aliased read right | diagnoses right |
|---|---|---|---|---|---|---|---|---|
| held-out draw 9000 | e88c279 | paper | 566 / 577 (98 %) | 2 | 10 / 761 (1.3 %) | 2 (3 / 40, 4 / 59) | 224 / 224 | 8 / 12 |
| | | ring | 669 / 688 (97 %) | 6 | 18 / 847 (2.1 %) | 2 (7 / 71, 6 / 70) | 337 / 340 | 12 / 12 |

Every case over 5 % has a mass, and three of the four wrong diagnoses. The ring's 20-point mass test
(receptance, 2 hits) reads its opposite n = 11 … 16 (284–404 Hz) as n = 9 … 4, unflagged: three
rows at 152.5, 155.0 and 158.8 Hz — the in-phase n = 9 and 11 (153.2, 159.4 Hz), fitted as three
poles whose shares of the response sum to 2.9 (residues that cancel) — read as anti-phase n = 9,
and the alias walk then takes the true n = 9 at 243.9 Hz for a mode off its branch. Three of
the paper's four wrong diagnoses are added-mass tests (`rhoA`, `m_w` or the membrane adopted);
the 30-point air cavity adopted `tangential`, its n = 1 cavity mode missed (docs/lsce.md,
"Session 45").

The alias walk's rule for clear rows below their branch's lower orders (3bd92e2, made after
this draw was looked at, so not out-of-sample for it): ring 669 → **674** / 688 found,
mislabelled 6 → **1**, aliased read right 337 → **342** / 345, spurious 18 / 847 unchanged
(the 20-point mass test 47 → 52 / 53, `added_mass` now adopted; still 7 / 71 spurious, its
three cancelling rows at 152–159 Hz among them); paper unchanged. The matrix, the car's
matrix and the draw 7000: unchanged case by case.

**Session 46: a fourth draw** (`--held-out-seed 11000`, never seen, run once at 06c91f1 —
session 45's last code — before anything was looked at, then at 51e9b92):

| run | code | generator | found / expected | mislabelled | spurious / adopted | cases over 5 % | aliased read right | diagnoses right |
|---|---|---|---|---|---|---|---|---|
| held-out draw 11000 | 06c91f1 | paper | 612 / 661 (93 %) | 8 | 8 / 788 (1.0 %) | 1 (4 / 64) | 251 / 251 | 8 / 8 |
| | | ring | 601 / 607 (99 %) | 2 | 13 / 809 (1.6 %) | 1 (5 / 66) | 189 / 190 | 6 / 8 |
| | 51e9b92 | paper | 612 / 661 (93 %) | 8 | 8 / 788 (1.0 %) | 1 (4 / 64) | 251 / 251 | 8 / 8 |
| | | ring | 601 / 607 (99 %) | 2 | 13 / 809 (1.6 %) | 1 (5 / 66) | **190** / 190 | 6 / 8 |

The paper's misses are the 60-point membrane + mass (1,600 Hz, receptance, faults: 44 / 72,
7 mislabelled) and the 20-point membrane + cavity (4,096 Hz, 1 s, faults: 56 / 72, the case
over 5 %); the ring's case over 5 % is the 20-point rim + mass, whose diagnosis is wrong with
either code (`m_w` and `tangential`, then `added_mass` and `tangential`; the rim fixture
missed), as is the 60-point extensible belt + rim's (`tangential` adopted beside the belt).
The session's re-reading of unreadable split partners changed no count here; the orders-mix
note fired in both tests with a mass and in none of the other 22.

"""


ANOTHER_TYRE = """## Another tyre: the matrix on a passenger-car tyre (session 44)

Every rule of the modal stage was measured on one tyre, the paper's GL073A truck tyre (R =
0.65 m, 19.6 kg/m of tread, its in-phase branch crowding at 168 Hz). `--tyre car` runs the
same 55 cases (levels, physics, seeds) made of a 205/55 R16 passenger-car tyre at 2.2 bar
(`validation.TYRES["car"]`: R = 0.30 m, b = 0.16 m, 2.39 kg/m of tread, 1.38 kg/m of
sidewall, EI = 5 N·m², k_r1 = 3·10⁶ and k_r2 = 2·10⁶ N/m²; its breathing mode at 101 Hz, the
in-phase crowd at 303 Hz, the anti-phase branch from 336 Hz at 17–73 Hz per order). The
values are plausible magnitudes for that size, not a measured tyre; each physics variant
keeps the truck variant's proportion to its tyre (a sidewall tension of 11 % of the hoop
tension, a 50 g sensor as 1 % of the tread's mass, a 10 kg rim). `run` is given what a user
knows of the tyre — R, b, P0, the tread's and sidewall's masses per length — and starts its
stiffnesses at GL073A's (`validation.nominal_params`).

| run | code | generator | found / expected | mislabelled | missed | spurious / adopted | cases over 5 % | diagnoses right |
|---|---|---|---|---|---|---|---|---|
| car matrix, first run | 1c06bc0 | paper | 725 / 745 (97 %) | 6 | 14 | 10 / 1152 (0.9 %) | 2 | 25 / 27 |
| | | ring | 812 / 831 (98 %) | 11 | 8 | 16 / 1353 (1.2 %) | 2 | 28 / 28 |
| car matrix | 58e33f5 | paper | **729** / 745 (98 %) | 2 | 14 | 9 / 1151 (0.8 %) | 1 | 25 / 27 |
| | | ring | **817** / 831 (98 %) | 6 | 8 | 16 / 1353 (1.2 %) | 2 | 28 / 28 |
| car, held-out levels (seed 5000) | 58e33f5 | paper | 411 / 413 (100 %) | 0 | 2 | 8 / 573 (1.4 %) | 0 | 11 / 12 |
| | | ring | 397 / 413 (96 %) | 7 | 9 | 8 / 574 (1.4 %) | 1 | 9 / 12 |
| car matrix | 64687fb (the cavity's flat-branch evidence) | paper | 729 / 745 (98 %) | 2 | 14 | 9 / 1151 (0.8 %) | 1 | 25 / 27 |
| | | ring | 817 / 831 (98 %) | 6 | 8 | 16 / 1353 (1.2 %) | 2 | 28 / 28 |
| car, held-out levels (seed 5000) | 64687fb | paper | 411 / 413 (100 %) | 0 | 2 | 8 / 573 (1.4 %) | 0 | 11 / 12 |
| | | ring | 397 / 413 (96 %) | 7 | 9 | 8 / 574 (1.4 %) | 1 | **10** / 12 |
| car matrix | the band's top rule, measured and not adopted | paper | 729 / 745 (98 %) | 2 | 14 | **8** / 1150 (0.7 %) | 1 | 25 / 27 |
| | | ring | 817 / 831 (98 %) | 6 | 8 | **12** / 1349 (0.9 %) | **1** | 28 / 28 |
| car, held-out levels (seed 5000) | the band's top rule, not adopted | paper | 411 / 413 (100 %) | 0 | 2 | **7** / 572 (1.2 %) | 0 | 11 / 12 |
| | | ring | 397 / 413 (96 %) | 7 | 9 | **3** / 568 (0.5 %) | **0** | 10 / 12 |
| car matrix | session 48 (the noise test's variance follows the hammer's spectrum) | paper | 729 / 745 (98 %) | 2 | 14 | **8** / 1150 (0.7 %) | 1 | 25 / 27 |
| | | ring | 817 / 831 (98 %) | 6 | 8 | **14** / 1352 (1.0 %) | **1** | 28 / 28 |
| car, held-out levels (seed 5000) | session 48 | paper | 411 / 413 (100 %) | 0 | 2 | 8 / 573 (1.4 %) | **1** | 11 / 12 |
| | | ring | 397 / 413 (96 %) | 7 | 9 | 9 / 574 (1.6 %) | **2** | 10 / 12 |
| car matrix | session 48, and each pole's threshold times the window's noise gain | paper | 729 / 745 (98 %) | 2 | 14 | **5** / 1146 (0.4 %) | 1 | 25 / 27 |
| | | ring | 816 / 831 (98 %) | 6 | 9 | **11** / 1345 (0.8 %) | **0** | 28 / 28 |
| car, held-out levels (seed 5000) | the same | paper | 411 / 413 (100 %) | 0 | 2 | **7** / 572 (1.2 %) | 1 | 11 / 12 |
| | | ring | 397 / 413 (96 %) | 7 | 9 | **4** / 572 (0.7 %) | **0** | 10 / 12 |
| car matrix | session 49 (the window's gain in the other noise tests; diagnose rule 6) | paper | 729 / 745 (98 %) | 2 | 14 | 5 / 1146 (0.4 %) | 1 | 25 / 27 |
| | | ring | 816 / 831 (98 %) | 6 | 9 | 11 / 1345 (0.8 %) | 0 | 28 / 28 |
| car, held-out levels (seed 5000) | the same | paper | 411 / 413 (100 %) | 0 | 2 | 7 / 572 (1.2 %) | 1 | 11 / 12 |
| | | ring | 397 / 413 (96 %) | 7 | 9 | 4 / 572 (0.7 %) | 0 | 10 / 12 |
| car matrix | session 50 (a pair split beyond a lumped mass's fraction loses its blended member): unchanged case by case (its mass tests' anti-phase pairs of n ≥ 2 all within 2 × their median) | paper | 729 / 745 (98 %) | 2 | 14 | 5 / 1146 (0.4 %) | 1 | 25 / 27 |
| | | ring | 816 / 831 (98 %) | 6 | 9 | 11 / 1345 (0.8 %) | 0 | 28 / 28 |
| car, held-out levels (seed 5000) | the same: unchanged | paper | 411 / 413 (100 %) | 0 | 2 | 7 / 572 (1.2 %) | 1 | 11 / 12 |
| | | ring | 397 / 413 (96 %) | 7 | 9 | 4 / 572 (0.7 %) | 0 | 10 / 12 |
| car matrix | session 51 (one order's blends in a group refitted with the other orders' modes as real-mode copies, modal.group_blends): unchanged case by case (no refit kept in its tests) | paper | 729 / 745 (98 %) | 2 | 14 | 5 / 1146 (0.4 %) | 1 | 25 / 27 |
| | | ring | 816 / 831 (98 %) | 6 | 9 | 11 / 1345 (0.8 %) | 0 | 28 / 28 |
| car matrix | session 52 (weak aliases read by the branch's dispersion; a cavity mode's alias both branches contradict; one-reference order groups without the shape test): the paper membrane + cavity's in-phase n = 19, 22 … 25 no longer dropped as misreads; the ring coupling + mass loses its added-mass diagnosis (its breathing mode now 100.94 Hz against the truth's 100.93, was 101.06: docs/lsce.md, "Session 52") | paper | **734** / 745 (99 %) | 3 | **8** | 5 / 1158 (0.4 %) | 1 | 25 / 27 |
| | | ring | **818** / 831 (98 %) | 5 | **8** | 11 / 1349 (0.8 %) | 0 | **27** / 28 |
| car, held-out levels (seed 5000) | session 52: the 60-point ring's in-phase n = 25, 27, 28 read on their branch, n = 30 found; the 20-point ring's extensible + coupling loses its extensible belt (two more aliased rows reach identify: docs/lsce.md, "Session 52") | paper | 411 / 413 (100 %) | 0 | 2 | 7 / 572 (1.2 %) | 1 | 11 / 12 |
| | | ring | **401** / 413 (97 %) | **4** | **8** | 4 / 577 (0.7 %) | 0 | **9** / 12 |

*What the first run found.* Nine of the 17 mislabelled modes were one defect, on tests with
nothing the truck's matrix lacks (1,024 Hz, 40 points, receptance, faults, the cavity): a
clear mode at the top of the anti-phase branch (n = 7 at the 1,024 Hz band's top, n = 14 at
728.6 Hz) flagged an aliased crowd. One row read at a high order under or barely above the
branch — a copy of n = 7 one line above it read n = 16; rows at 506.7 and 449.0 Hz read
n = 20 and n = 15 — was taken as a point of the branch's dispersion, and the running
maximum flattened the branch from there: its aliases fell inside the mode's bandwidth. The
truck's anti-phase branch is never that steep at the band's top, so no matrix case showed
it. Fixed in the crowd test (`modal.crowds._off_the_rising_steps`: the anti-phase branch's
step grows with n, so a point whose rise over its gap falls short of half the last step,
by more than its half-power half-width, is left out of the dispersion; docs/lsce.md,
"Session 44"). The truck's matrix is unchanged by it case by case.

*Still bad on the car tyre.* The added mass (ring and paper): the anti-phase n = 0 … 4 lie
within 8 Hz at 336–344 Hz, and the mass splits and mixes them (paper added mass 21 / 25
found, 3 missed, 2 / 33 spurious — over 5 %; ring mass 24 / 27; with the sidewall coupling
46 / 57) — the truck's known limit, at another tyre. The paper's added-mass cases are
**diagnosed wrong** (rhoA adopted for added_mass, alone and beside tangential): the 50 g
mass's lowering of the cos members is read as a heavier tread, as docs/lsce.md notes for a
mass whose split pairs are not resolved. The sidewall membrane's weak in-phase orders
n = 19 … 34 (with the cavity 8 missed). Two ring combinations were over 5 % spurious: the
5,120 Hz tangential in receptance (3 / 54, at the band's top, 1,227–1,317 Hz) and the 1,024 Hz rim + cavity with 5 % noise,
1 hit, faults and mobility (4 / 35).

*The held-out draw on the car* (`--tyre car --held-out-levels 12`, the draw of seed 5000):
the ring's in-phase orders with the sidewall coupling (n = 14 … 34 at 20, 36 and 60 points:
16 of the 18 not found); a ring test with nothing added (3,200 Hz, 36 points, mobility)
adopted air_cavity — fixed (64687fb: the in-phase crowd at 303 Hz lies in the car's cavity
band, and crowd rows now testify that an n = 1 row beside them is a flat branch's member,
docs/diagnose.md); still wrong: the paper's tangential + rim adopting rhoA, the ring's
extensible + mass without the mass, its sidewall shear + coupling without the shear.
Spurious rows at the band's top: 8 of the 16 lie at 1,238–1,312 Hz on the 3,200 and
4,096 Hz tests, within 3 of their own half-power half-widths of the top the hammer's
spectrum sets (1,318 Hz on the 4,096 Hz tests); with the matrix's, about 15 of the car's
41 spurious rows. They are narrow (ζ 0.2–0.8 % against the structure's 2 %) and weak (under
11 % of the physical response, kept by their order group's own-peak rule); the edge
refinement (modal.refine) moves them by under a half-width and finds them above the noise
even with a pole beyond the top. The truck's matrix hides this class: its modes are so dense
at the top that such a row lands within 0.3 % of some truth mode. A rule that a mode whose own
window (4 half-widths) reaches past the top must hold 5 % of the physical response gave the
last two rows of the table, left the GL073A matrix unchanged, and was **not adopted**: it
dropped five true weak in-phase modes (n = 27 … 30) at the bundled sample's 400 Hz top
(docs/lsce.md, "Session 44").

*Session 48: the noise over the lines.* The noise test now weighs each line by the FRFs' noise
there, from the force autospectrum (docs/lsce.md, "Session 48"): at those rows the hammer's
spectrum had fallen so far that the noise was 26–74 × the band's median. The car matrix drops
three spurious rows and adds none (1,227.06, 1,311.67, 449.05 Hz): the 5,120 Hz tangential
receptance test goes to 2 / 53, and two cases stay over 5 % (the 1,024 Hz rim + cavity, 4 / 35;
the paper's added mass, 2 / 34). The GL073A matrix is unchanged in every count. The car's held-out
draw keeps its totals, but one row comes and one goes in each generator, and three cases now sit
just over 5 % (3 / 51, 3 / 53, 3 / 57) where one did: 1,242.07 Hz at the 3,200 Hz top, which the
old test had dropped on a negative ΔE (an ill-conditioned fit with the pole, not the noise), and
474.85 Hz on the paper's 4,096 Hz membrane test. The session's second change — each pole's
threshold times what the exponential window's noise gives a pole (3–6; without it the test passed
noise poles on windowed FRFs in 20 of 20 trials) — takes the matrix to 5 + 11 spurious rows
(from 9 + 16), the 1,024 Hz rim + cavity to 1 / 32, one case over 5 % (the paper's added mass,
2 / 33), and costs the ring's coupling + mass its in-phase n = 39 (816 / 831); the held-out draw
to 7 + 4 (from 8 + 9), one case over 5 % (the paper's 4,096 Hz membrane, 3 / 57).
"""

HISTORY = """## History

Earlier scorecards of the same matrix, totals only (their per-case records were not kept):

| when | code | generator | found / expected | spurious / adopted | run errors | no-effect cases adopting nothing | effect cases right | matrix time |
|---|---|---|---|---|---|---|---|---|
| 2026-11-23, first run | the ruler on the estimator before #14/#19 (run's band 0.04–0.293 fs) | paper | 789 / 1236 (64 %) | 34 / 1068 (3.2 %) | 0 | 13 / 14 | 3 / 13 | 56 min (machine loaded) |
| | | ring | 785 / 1342 (58 %) | 29 / 1033 (2.8 %) | 3 (NaN in sensitivity.json) | 13 / 14 | 3 / 11 | |
| 2026-11-23, after #14 and #19 | band from the data, duplicates by the poles, crowds named; vectorised fits | paper | 1076 / 1236 (87 %) | 33 / 1389 (2.4 %) | 0 | 0 / 14 (tangential adopted: run assumed a 1,000 kg rim on clamped-rim tests) | 2 / 13 | 3.5 min |
| | | ring | 1217 / 1342 (91 %) | 28 / 1557 (1.8 %) | 0 | 0 / 14 | 4 / 14 | |
| 2026-11-23, end of session 4 | rim from the data, the paper's comparison (main at 947963a; the ruler counting f ≤ fs/2.56) | paper | 1076 / 1236 (87 %) | 33 / 1389 (2.4 %) | 0 | 14 / 14 | 5 / 13 | 3.0 min |
| | | ring | 1194 / 1342 (89 %) | 32 / 1557 (2.1 %) | 0 | 14 / 14 | 5 / 14 | |
| 2026-11-23, end of session 5 | the merge by the poles' data, alias rules (#14); the robust base fit, set-aside modes as evidence, extensible belt, rim fixture, the ring terms of the tangential effect (#15) | paper | 1133 / 1212 (93 %) | 33 / 1440 (2.3 %) | 0 | 14 / 14 | 8 / 13 | 3.3 min |
| | | ring | 1252 / 1334 (94 %) | 30 / 1637 (1.8 %) | 0 | 14 / 14 | 6 / 14 | |
| 2026-11-23, end of session 6 | the layout by stage (#18: the same modes and fits, case by case); the rim mode: a measured n = 1 "same" may be the model's rim mode, and is kept in the fit below n = 0 (#15); the modal stage's orders in threads (#19) | paper | 1133 / 1212 (93 %) | 33 / 1440 (2.3 %) | 0 | 14 / 14 | 9 / 13 | 3.4 min |
| | | ring | 1252 / 1334 (94 %) | 30 / 1637 (1.8 %) | 0 | 14 / 14 | 7 / 14 | |
| 2026-11-23, end of session 7 | failed points keep the test's grid (#14); a spare second-round parameter refused as compensation, aliases relabelled after the candidates, the breathing mode in the fit (#15); the base fit from a closed-form start (#19) | paper | 1133 / 1212 (93 %) | 30 / 1429 (2.1 %) | 0 | 14 / 14 | 11 / 13 | 3.4 min |
| | | ring | 1268 / 1334 (95 %) | 21 / 1630 (1.3 %) | 0 | 14 / 14 | 11 / 14 | |
| 2026-11-23, end of session 8 | a weak mode on a peak of its own judged against the noise (#14); an unexplained cavity-band mode in the χ² and the cavity's own round, a mass's split must be reproduced, the rim mass's profile (#15); scipy.fft in the FRF stage (#19) | paper | 1135 / 1212 (94 %) | 30 / 1431 (2.1 %) | 0 | 14 / 14 | 11 / 13 | 3.1 min |
| | | ring | 1276 / 1334 (96 %) | 21 / 1639 (1.3 %) | 0 | 14 / 14 | 12 / 14 | |
| 2026-11-24, end of session 9 | a weak leak of a stronger mode of another order group dropped, weak pinned modes kept beside a stronger one, the points taken in the order of their angles, an unreadable mode read on the other branch (#14); detectability on the modes a test shows, aliased orders re-read in the base fit, a nested Timoshenko with a joint test, a free rim's n = 1 modes matched to the nearest, the rim mass on its ridge, vanishing parameters on their bound (#15, #19); new machine: the same f4b04e5 gave paper 29 / 1429, ring 23 / 1639 spurious here | paper | 1143 / 1212 (94 %) | 29 / 1435 (2.0 %) | 0 | 14 / 14 | 13 / 13 | 2.2 min |
| | | ring | 1277 / 1334 (96 %) | 18 / 1632 (1.1 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, end of session 10 | a free rim's second n = 1 read as n = 1, and the ruler's "rim" modes found by their order on either branch; a grid with failed points read a second time with the found modes' leaks taken out; a wandering leak dropped whatever its peak, leak twins; a broad weak mode's scatter judged against its Cramér–Rao bound (#14) | paper | 1153 / 1212 (95 %) | 24 / 1436 (1.7 %) | 0 | 14 / 14 | 13 / 13 | 2.3 min |
| | | ring | 1289 / 1334 (97 %) | 11 / 1627 (0.7 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, end of session 11 | a crowd candidate judged at its own pole when the estimator found it, and no misread alias in a branch's dispersion; with failed points a mode tested against the noise and leak copies within both half-power half-widths; pole refinement on near the band's edges (#14) | paper | 1155 / 1212 (95 %) | 22 / 1436 (1.5 %) | 0 | 14 / 14 | 13 / 13 | 2.4 min |
| | | ring | 1295 / 1334 (97 %) | 9 / 1626 (0.6 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, end of session 12 | the crowd test's same-direction branch continued by the model's saturating law; weak poles refined with their group's dropped poles in the basis; a pole biased by the band's wrap re-estimated with a guard band; with failed points, the unfound orders proposed from the dispersion and refined jointly in the physical FRFs with residues held to their orders (#14) | paper | 1170 / 1212 (97 %) | 18 / 1448 (1.2 %) | 0 | 14 / 14 | 13 / 13 | 2.9 min |
| | | ring | 1298 / 1334 (97 %) | 8 / 1626 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, end of session 13 | a clear mode whose alias would make its branch fall below a clear mode read at its own order keeps its spatial order, on complete grids (#14); measured and not adopted: model-free tests of the added mass's blends, the joint refinement on complete grids, group poles kept apart | paper | 1170 / 1212 (97 %) | 18 / 1448 (1.2 %) | 0 | 14 / 14 | 13 / 13 | 2.9 min |
| | | ring | 1301 / 1334 (98 %) | 8 / 1626 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, end of session 14 | a weak mode out of its branch's order at its spatial order, no narrower than its neighbours, dropped as a misread (the added mass's blends); with failed points the order-held fits solved at their numerical rank (#14); `--seed-offset` for held-out noise (above) | paper | 1170 / 1212 (97 %) | 6 / 1416 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 3.1 min |
| | | ring | 1301 / 1334 (98 %) | 7 / 1601 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, session 15 (76eda77, the ruler before its alias-class rule) | a weak mode's peak judged against the noise of the group's row that shows it best, not the rows' norm (the own-peak and pinned-apart rules; #14); measured and not adopted: a matched-filter reading of the norm, the sweep's channels whitened by their noise floor, a channel-pattern veto in the merge | paper | 1178 / 1212 (97 %) | 7 / 1424 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 3.2 min |
| | | ring | 1301 / 1334 (98 %) | 7 / 1600 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, end of session 15 | the same code; the ruler finds an aliased order only by a row of its alias class (the paper's n = N same at 167.3 Hz had been credited to a crowd row of another group in 14 cases: found → mislabelled) | paper | 1162 / 1212 (96 %) | 7 / 1424 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 3.2 min |
| | | ring | 1297 / 1334 (97 %) | 7 / 1600 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-24, end of session 16 | two orders at one frequency kept apart on a complete grid whose mirrored FRFs show a symmetric structure (the paper's n = N same found in every paper case; the ring's 0.05 noise case reads n = 11 as a crowd: −1); an n = 1 mode of a flat branch is no cavity evidence; an alias after missed orders read from the branch's step (d5827f5: found and spurious as at 5591f3a) | paper | 1180 / 1212 (97 %) | 7 / 1627 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 3.2 min |
| | | ring | 1296 / 1334 (97 %) | 7 / 1820 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-25, end of session 18 | the force autospectrum of each point's accepted hits kept in the FRFs and frf.h5; run's band from it (before: every record, rejected hits too, read a second time), as lsce's on the file (c2f85df; two 5,120 Hz ring combinations' band tops 4–10 Hz higher) | paper | 1180 / 1212 (97 %) | 7 / 1627 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 3.5 min |
| | | ring | 1296 / 1334 (97 %) | 8 / 1821 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-25, end of session 19 | no change to the package (2895079: benchmarks/crlb.py's poly-reference bound; three estimator changes measured and not adopted, docs/lsce.md "Session 19") — the same 55 records as session 18's | paper | 1180 / 1212 (97 %) | 7 / 1627 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 3.4 min |
| | | ring | 1296 / 1334 (97 %) | 8 / 1821 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-25, end of session 20 | a peak no order group's pole stands for (the residual over its local noise level) re-swept at twice the group's order (modal.rescue: the 5,120 Hz ring's rim n = 1 at 24.45 Hz); a clear mode more than its bandwidth below every alias a rising branch could hold keeps its spatial order (the 5,120 Hz tangential ring's n = 1 opposite, and the branch's n = 30 … 42 no longer read as n = 38, 65, 100 …); the ruler counts the aliased modes found whose order and branch are read right (above) | paper | 1180 / 1212 (97 %) | 7 / 1627 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 3.0 min |
| | | ring | 1298 / 1334 (97 %) | 8 / 1822 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-27, end of session 21 | the ruler finds a split pair (one order and branch, split by less than ζ f) by a row at either member as well as at the mean (ring mass n = 16, 29; sidewall coupling + mass n = 12; paper added mass n = 20; tangential + mass n = 1); on a grid with missing points a spatial reading that disagrees with the mode's order group read at the group's order (the failed-points combination's n = 8 same); measured, not adopted: the failed-points modes refined as sets in the physical FRFs, the paper model to 120 orders (docs/lsce.md, "Session 21") | paper | 1183 / 1212 (98 %) | 7 / 1627 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 3.0 min |
| | | ring | 1301 / 1334 (98 %) | 8 / 1822 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-27, end of session 22 | a point whose only hits bounced keeps them, the force window over every blow, while the notch stays within the 20 dB force rule (docs/frf.md); a missing point read from its mirror image about the sensors' plane when the test's mirrored points show the symmetry (modal.mirror); on the gaps no image fills, a pole above the leak bound a mode of its own; measured, not adopted: the noise tests in the poly-reference fit's norm (docs/lsce.md, "Session 22") | paper | 1188 / 1212 (98 %) | 7 / 1639 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 2.4 min |
| | | ring | 1301 / 1334 (98 %) | 8 / 1835 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-28, end of session 24 | the crowd test's dispersion ends at a branch's first gap of more than N/2 orders (a quieter test's 24-point crowd keeps its flags); `--noise-scale` (the matrix at 5 × and 50 × less noise, "Held out"); measured, not adopted: weak modes taken back by their symmetry about the sensors (docs/lsce.md, "Session 24") | paper | 1188 / 1212 (98 %) | 7 / 1635 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 2.3 min |
| | | ring | 1301 / 1334 (98 %) | 8 / 1835 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-28, end of session 23 | a lumped mass on the sensors' plane (the mirror test's blind spot) seen by the order mixing — the clear modes' copies in other order groups symmetric about that plane beyond their antisymmetric part (modal.mixing) — and the groups then not treated as orthogonal, a mixed mode read at its dominant group; held out, no paper case over 5 % spurious at any seed; measured, not adopted: poles of a symmetric grid kept apart when visible though not pinned (docs/lsce.md, "Session 23") | paper | 1188 / 1212 (98 %) | 7 / 1635 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 2.4 min |
| | | ring | 1301 / 1334 (98 %) | 8 / 1835 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-28, end of session 25 | a crowd's candidates run one alias span N above its branch's highest clear order (the 2,560 Hz 24-point tests' n = 47 a crowd with 49); on a symmetric complete grid a pinned pole of another order group is its own mode beside a crowd's unpinned blend (the opposite n = 48 at 843.6 Hz); the crowd test's dispersion leaves out a row on the wrong side of the other branch (an in-phase row above the anti-phase mode of its order); the diagnosis re-reads an aliased order only where the model tells the class's orders apart by more than its misfit, and takes no row that is no normal mode (MPC < 0.5) for a cavity's (held out: every diagnosis right at seeds + 1000 … + 3000); measured, not adopted: a quiet test's copies judged by the test's own leakage, every pole refined on a symmetric grid (docs/lsce.md, "Session 25") | paper | 1190 / 1212 (98 %) | 7 / 1646 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 2.3 min |
| | | ring | 1301 / 1334 (98 %) | 8 / 1836 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-28, end of session 26 | no change to the package (the code of fed11f3); measured, not adopted: a refined pole of a complete symmetric grid judged by its group's rows alone (matrix paper + 1 found, − 1 spurious; seeds + 1000 paper and ring − 1 found, + 1 spurious), the noise test's fits weighted as its sum (spurious paper 7 → 14, ring 8 → 12), a pin rule from each pole's own Cramér–Rao bound, a second sweep with the channels as references, the ruler's crowd test over the paper model's orders above n_max, the dispersion's proposals on complete grids (docs/lsce.md, "Session 26") | paper | 1190 / 1212 (98 %) | 7 / 1646 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 6.2 min (machine shared) |
| | | ring | 1301 / 1334 (98 %) | 8 / 1836 (0.4 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, end of session 28 | a weak mode beside a strong one of its order group fitted by variable projection where the group's residual holds a bandwidth-wide hump, kept on nested fits with its neighbours free, a shape unlike theirs and 3 σ from them (modal.beside; complete symmetric unmixed grids); on a complete grid a weaker pole 3 × its scatter from the stronger is located (the code of a81e46a) | paper | 1193 / 1212 (98 %) | 9 / 1655 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 7.9 min |
| | | ring | 1304 / 1334 (98 %) | 10 / 1841 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, session 29: the ruler | an alias above the paper generator's n ≤ 60 counts in the crowd test, by the generator's own model (session 28's code, 892ee88, scored again: 30 paper modes leave "expected", 25 of them found, 3 mislabelled, 2 missed) | paper | 1168 / 1182 (99 %) | 9 / 1655 (0.5 %) | 0 | 14 / 14 | 13 / 13 | |
| 2026-11-29, end of session 29 | a pole of another order group that moves the channels otherwise (channel-shape MAC < 1/2), visible, pinned and a normal mode, is another mode, never a copy (modal.merge; the code of 3fd76d9); measured, not adopted: the beside fit on mass-mixed grids, with and without the other groups' poles fixed in its basis (docs/lsce.md, "Channel shapes") | paper | 1168 / 1182 (99 %) | 10 / 1657 (0.6 %) | 0 | 14 / 14 | 13 / 13 | 7.3 min |
| | | ring | 1306 / 1334 (98 %) | 10 / 1843 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, end of session 30 | a pole kept apart by its channel shape alone that the classification finds in a crowd of its alias class is a blend, dropped (modal.misreads; the code of 6d57eb6). Run on an Intel Xeon (AVX-512), where sessions 26–29 ran on an AMD EPYC: session 29's code here gives ring 1307 / 1334, 10 / 1845 (on the EPYC 1306, 10 / 1843), paper as there | paper | 1168 / 1182 (99 %) | 9 / 1655 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 23 min (a clean-clone CI beside it) |
| | | ring | 1307 / 1334 (98 %) | 10 / 1845 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, session 31 | a pole of another order group within the stronger mode's half-power half-width, neither on a peak of its own (under 3 × its row's residual) nor pinned by its data (scatter over a line), is the stronger mode's copy (modal.merge; the code of 79ad8b0): held out, no case over 5 % spurious at any seed | paper | 1168 / 1182 (99 %) | 9 / 1655 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 19 min (`--jobs 1`, another matrix beside it) |
| | | ring | 1306 / 1334 (98 %) | 9 / 1842 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, end of session 31 | and the channel rule's normal-mode check on the weaker pole's part that the stronger mode's copy cannot hold, its residues with the stronger one's channel shape projected out (the code of 4f37560) | paper | 1168 / 1182 (99 %) | 9 / 1655 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 27 min (`--jobs 1`, a clean-clone CI beside it) |
| | | ring | 1307 / 1334 (98 %) | 9 / 1843 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, end of session 32 | the band's top where one channel's median coherence over its points passes; on an orthogonal grid only a crowd of other groups' poles excuses an unexplained band from the rescue (the code of a678815): the matrix unchanged case by case; the held-out levels (above) paper 625 → 671 / 685 found | paper | 1168 / 1182 (99 %) | 9 / 1655 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 11 min (`--jobs 2`, other work beside it) |
| | | ring | 1307 / 1334 (98 %) | 9 / 1843 (0.5 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, end of session 33 | the band's top: the edge refinement before the edge check, a pole beyond the top, edge poles the FRFs do not locate dropped, copies held, a move judged by the group's rows on complete symmetric grids (modal.refine; the code of 30cb58c) | paper | 1170 / 1182 (99 %) | 7 / 1654 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 27 min (`--jobs 2`, the held-out levels and a clean-clone CI beside it) |
| | | ring | 1307 / 1334 (98 %) | 6 / 1840 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, session 34 | a weak mode (under 15 % of its band's response) out of its branch's order read on the other branch whatever its branch confidence, where exactly one order of its alias class fits there (modal.classify; the code of 5585dee): the membrane's n = 55, the membrane + cavity's n = 54 found, the paper's same-direction crowd reported whole | paper | 1172 / 1182 (99 %) | 8 / 1697 (0.5 %) | 0 | 14 / 14 | 13 / 13 | 17 min (`--jobs 2`, two offline surveys beside it) |
| | | ring | 1307 / 1334 (98 %) | 6 / 1858 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-11-29, end of session 34 | and on a test whose FRFs show a symmetric structure with unmixed orders, a split pair's weaker, broader member dropped as a blend (modal.misreads; the code of d2003f2): held out, paper spurious 18 → 8, ring 7 → 5 | paper | 1172 / 1182 (99 %) | 7 / 1694 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 10 min (`--jobs 2`, tests beside it) |
| | | ring | 1307 / 1334 (98 %) | 5 / 1857 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-01, session 35, on an AMD EPYC (sessions 30–34 on an Intel Xeon): session 34's end run again | the code of d2003f2 (near ties: the ring finds one mode fewer, mislabelled instead) | paper | 1172 / 1182 (99 %) | 7 / 1694 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 6 min (`--jobs 1`, another matrix beside it) |
| | | ring | 1306 / 1334 (98 %) | 5 / 1855 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-01, end of session 35 | a weak pole refined in every order group, not only in one whose fit dropped a pole (modal.refine; the code of 01f9ada): the membrane's n = 45 and the membrane + cavity's n = 48 found, its n = 54 lost | paper | 1173 / 1182 (99 %) | 6 / 1694 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 6 min (`--jobs 2`) |
| | | ring | 1306 / 1334 (98 %) | 5 / 1855 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-02, end of session 37 | session 36's leak copy bound and joined clusters (the matrix unchanged by them), and on mixed orders a pinned pole of its own group that moves the channels otherwise is no copy of a stronger mode (modal.own_mode), read at its group where the symmetry is broken (classify; the code of 27080b6): the sidewall coupling + mass's same n = 41 and 42 found, its n = 36 no longer mislabelled | paper | 1173 / 1182 (99 %) | 6 / 1694 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 7 min (`--jobs 2`) |
| | | ring | **1309** / 1334 (98 %) | 5 / 1857 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-02, end of session 38 | a weak mode of another family, clear in its own group, keeps its spatial order and is no misread on a symmetric test (alias_walk, misreads); the alias walk's step from the branch's two highest marked orders (the code of 73c6563): the ring sidewall shear's n = 1 same at 98.32 Hz found | paper | 1173 / 1182 (99 %) | 6 / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 7 min (`--jobs 2`, other runs beside it) |
| | | ring | **1310** / 1334 (98 %) | 5 / 1865 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-02, session 39, on an AMD EPYC: session 38's end run again | the code of e84e7d0 | paper | 1173 / 1182 (99 %) | 6 / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 6 min (`--jobs 2`) |
| | | ring | 1310 / 1334 (98 %) | 5 / 1863 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-02, end of session 39 | a cluster the sweep's top order splits into two narrower tracks re-swept at twice the order and set aside where exactly two parts resolve it (modal.rescue); not on grids with points missing; the crowd test's bandwidth from the lesser of the mode's and its branch's damping (crowds; the code of 7f32514): the ring 5 % noise test's n = 11 same no longer a crowd | paper | 1173 / 1182 (99 %) | 6 / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 7 min (`--jobs 2`, counting beside it) |
| | | ring | **1311** / 1334 (98 %) | 5 / 1863 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-07, session 44, on an AMD EPYC | the crowd test leaves out of the anti-phase branch's dispersion a point its rise cannot hold (crowds); crowd rows testify that an n = 1 row beside them is a flat branch's, no cavity (diagnose.cavity) — both made for the car tyre ("Another tyre" above): unchanged case by case against a85d870, fits included | paper | 1173 / 1182 (99 %) | 6 / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 5.5 min (`--jobs 2`) |
| | | ring | 1311 / 1334 (98 %) | 5 / 1865 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-07, session 46, on an AMD EPYC | where the orders mix, a mode whose branch cannot be read, beside a clear mode of its order and branch, is read on the other branch where exactly one order fits (classify; the code of 656a5a7): the coupling + mass's in-phase n = 22 found | paper | 1173 / 1182 (99 %) | 6 / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 6.6 min (`--jobs 2`) |
| | | ring | **1312** / 1334 (98 %) | 5 / 1865 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-07, session 48, on an AMD EPYC | the noise test's variance per line follows the hammer's spectrum (1 / G_ff over the points), its two fits weighted least squares (groupfit, band.noise_shape): unchanged in every count; adopted 1697 → 1696 (paper reference), 1865 → 1866 (ring coupling + mass) | paper | 1173 / 1182 (99 %) | 6 / 1696 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 7.1 min (`--jobs 2`, other runs beside it) |
| | | ring | 1312 / 1334 (98 %) | 5 / 1866 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-07, end of session 48 | and each pole's threshold times what the exponential window's noise gives a pole (band.window_noise_gain, 3–6): the membrane + cavity's in-phase n = 54 found; spurious +169.90 Hz (5 % noise), +179.64 Hz (added mass), −338.40 Hz | paper | **1174** / 1182 (99 %) | 7 / 1698 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 8.6 min (`--jobs 2`, other runs beside it) |
| | | ring | 1312 / 1334 (98 %) | 5 / 1864 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-07, session 49, on an AMD EPYC | the window's gain κ_r also in the beside, gaps and joint noise tests; a set-aside mode alone asks for an effect that explains it (diagnose rule 6): spurious −169.90 Hz (5 % noise, a beside pole) | paper | 1174 / 1182 (99 %) | **6** / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 7.7 min (`--jobs 2`) |
| | | ring | 1312 / 1334 (98 %) | 5 / 1864 (0.3 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-07, session 50, on an AMD EPYC | where the orders mix, an anti-phase pair split over 2 × the median of the test's pairs loses its weaker member, a blend with another order's copy (modal.mass_splits): spurious −327.52 Hz (ring + mass); the other tests do not reach the rule; and the pairs it leaves refitted with the other groups' copies where their splitting comes nearer the others' (modal.pair_refine): unchanged case by case | paper | 1174 / 1182 (99 %) | 6 / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 8.6 min (`--jobs 2`, other runs beside it) |
| | | ring | 1312 / 1334 (98 %) | **4** / 1863 (0.2 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-08, session 51, on an Intel Xeon | where the orders mix, rows of one order in one group split beyond a lumped mass's fraction refitted in the group's rows with the other orders' modes as real-mode copies, a redundant pole dropped (modal.group_blends): spurious −160.56 Hz (ring + mass, refitted to 160.96 Hz beside its group's crowd row); the rest unchanged case by case (the held-out draws' mixed tests: docs/lsce.md, "Session 51") | paper | 1174 / 1182 (99 %) | 6 / 1697 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 11.8 min (`--jobs 2`, other runs beside it) |
| | | ring | 1312 / 1334 (98 %) | **3** / 1863 (0.2 %) | 0 | 14 / 14 | 14 / 14 | |
| 2026-12-08, session 52, on an AMD EPYC | an order group of one reference (orders 0 and N/2) clustered by frequency and damping without the shape test (stabilization `shapes`); weak aliases read on the other branch by its dispersion where several orders fit, and a surely read mode whose alias both branches contradict keeps its order (classify, alias_walk): the paper membrane's n = 51 and the ring coupling + mass's n = 34 found, the ring's aliased rows read right 430 → 443 of 443 (docs/lsce.md, "Session 52") | paper | **1175** / 1182 (99 %) | 6 / 1700 (0.4 %) | 0 | 14 / 14 | 13 / 13 | 6.2 min (`--jobs 2`) |
| | | ring | **1313** / 1334 (98 %) | 3 / 1865 (0.2 %) | 0 | 14 / 14 | 14 / 14 | |
"""


def write_docs(records: list[dict], path: Path, elapsed_s: float, jobs: int) -> None:
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    text = [DOC_HEAD.format(minutes=elapsed_s / 60, jobs=jobs),
            f"Run {now}, commit {_commit()}, on {_machine()}; {len(records)} cases in "
            f"{elapsed_s / 60:.1f} min.\n",
            "## Totals\n", totals(records), "\n## Scorecard\n", table(records),
            "\n## Datasheet\n", datasheet(records),
            "\n## What was not found, case by case\n", failures(records), "", HELD_OUT, HELD_OUT_LEVELS_TEXT,
            ANOTHER_TYRE, HISTORY]
    path.write_text("\n".join(text), encoding="utf-8")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--only", action="append", default=[], help="run only cases with this name (repeatable)")
    ap.add_argument("--generator", choices=("ring", "paper"), action="append")
    ap.add_argument("--out", type=Path, default=Path(tempfile.gettempdir()) / "tiremodal-validation.jsonl")
    ap.add_argument("--keep", help="keep each case's files under this folder")
    ap.add_argument("--no-docs", action="store_true", help="do not rewrite docs/validation.md")
    ap.add_argument("--seed-offset", type=int, default=0,
                    help="add this to every case's seed: the same tests with noise, hits and faults the "
                         "matrix's own seeds never showed (a check on rules measured on the matrix; "
                         "docs/validation.md is not rewritten)")
    ap.add_argument("--noise-scale", type=float, default=1.0,
                    help="multiply every case's sensor noise by this (> 0): whether what the matrix misses is "
                         "the noise's (the ruler's visibility follows the noise; docs/validation.md is not "
                         "rewritten)")
    ap.add_argument("--held-out-levels", type=int, default=0, metavar="K",
                    help="instead of the matrix, K seeded random tests per generator at levels no rule was "
                         "measured on (other sample rates, point counts, hits, noise, record lengths; "
                         "validation.HELD_OUT_LEVELS; docs/validation.md is not rewritten)")
    ap.add_argument("--held-out-seed", type=int, default=5000, metavar="S",
                    help="the seed of --held-out-levels' draw (default 5000, the set the notes report): "
                         "another seed draws other level combinations, set-ups never looked at")
    ap.add_argument("--tyre", choices=tuple(TYRES), default="gl073a",
                    help="the tyre every case is made of (default gl073a, the paper's truck tyre, on which "
                         "every rule was measured; car: a passenger-car tyre no rule was measured on; "
                         "docs/validation.md is rewritten for gl073a only)")
    args = ap.parse_args(argv)
    if not args.noise_scale > 0:
        ap.error(f"--noise-scale {args.noise_scale:g}: must be > 0")
    gens = tuple(args.generator or ("ring", "paper"))
    cases = (held_out_levels(args.held_out_levels, seed=args.held_out_seed, generators=gens, tyre=args.tyre)
             if args.held_out_levels else matrix(generators=gens, tyre=args.tyre))
    if args.seed_offset:
        cases = [dataclasses.replace(c, seed=c.seed + args.seed_offset) for c in cases]
    if args.noise_scale != 1.0:
        cases = [dataclasses.replace(c, noise=c.noise * args.noise_scale) for c in cases]
    if args.only:
        cases = [c for c in cases if c.name in set(args.only)]
    print(f"{len(cases)} cases, {args.jobs} worker(s); records → {args.out}", file=sys.stderr)
    t0 = time.perf_counter()
    records = {}
    with ProcessPoolExecutor(max_workers=args.jobs) as ex, open(args.out, "w", encoding="utf-8") as fh:
        futs = {ex.submit(_one, c.to_dict(), args.keep): c for c in cases}
        for k, fut in enumerate(as_completed(futs), 1):
            c = futs[fut]
            try:
                r = fut.result()
            except Exception as exc:  # a crash of the simulation or scoring itself
                r = {"case": c.to_dict(), "name": c.name, "status": "error", "error": f"{type(exc).__name__}: {exc}",
                     "expected": 0, "found": 0, "mislabelled": 0, "missed": 0, "spurious": 0, "adopted": 0}
            records[c.name] = r
            fh.write(json.dumps(r) + "\n")
            fh.flush()
            print(f"[{k}/{len(cases)}] {c.name}: {r['status']} found {r['found']}/{r['expected']}, "
                  f"spurious {r['spurious']}/{r['adopted']}, diagnosis "
                  f"{'right' if r.get('diagnosis_right') else 'wrong'} ({time.perf_counter() - t0:.0f} s)",
                  file=sys.stderr)
    ordered = [records[c.name] for c in cases]
    elapsed = time.perf_counter() - t0
    print(totals(ordered))
    print()
    print(table(ordered))
    if (not args.no_docs and not args.only and not args.generator and not args.seed_offset and args.noise_scale == 1.0
            and not args.held_out_levels and args.tyre == "gl073a"):
        write_docs(ordered, ROOT / "docs" / "validation.md", elapsed, args.jobs)
        print(f"wrote {ROOT / 'docs' / 'validation.md'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
