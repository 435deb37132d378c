"""What the validation matrix's spurious modes are: each one classified against the truth.

    python benchmarks/validation.py --jobs 1 --keep /tmp/K --out /tmp/K.jsonl --no-docs
    python benchmarks/spurious.py /tmp/K.jsonl /tmp/K            # every case with a spurious mode
    python benchmarks/spurious.py /tmp/K.jsonl /tmp/K --only paper:physics=added_mass

A table mode is *spurious* when no truth mode lies within 0.3 % of it (the ruler,
``workflow/validation_scoring.py``). Each is put in one class by its distance d to the
nearest truth mode t in half-power half-widths, d = |f − f_t| / (ζ_t f_t) — the scale on
which two poles can be told apart at all — and by whether another row of the table already
reports t (within 0.3 %):

* ``biased`` — d ≤ 0.5 and no other row reports t: an estimate of t off by more than
  0.3 % (biased by a neighbour, a leak or the noise) but inside half its half-power band;
* ``copy`` — d ≤ 0.5 and another row reports t: t estimated a second time (a pole seen in
  another order group that the merge did not join, or a split pair's member read twice);
* ``between`` — 0.5 < d ≤ 2: a pole fitted between truth modes (several modes' flanks or
  leaks, e.g. the same-direction crowd under the sidewall resonance);
* ``far`` — d > 2: far from every truth mode (a noise pole, a band-edge pole, or physics
  the truth does not hold).

The case is re-simulated from its seed (the generator's truth), the table is the kept
``run/modes.csv``; the group and the physical and in-group significance of each spurious
mode come from ``run/modal.h5``. Prints one line per spurious mode and a count per class.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import h5py
import numpy as np

from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.validation import Case, config_for
from tiremodal_cli.workflow.validation_scoring import TOLERANCE

#: the classes' edges, in half-power half-widths of the nearest truth mode
NEAR_HW, BETWEEN_HW = 0.5, 2.0


def folder_of(name: str) -> str:
    """The folder ``benchmarks/validation.py --keep`` gives a case."""
    return name.replace(": ", "_").replace(":", "_").replace(", ", "_").replace("=", "-").replace(" ", "_")


def classify_spurious(rows: list[dict], truth: list[dict]) -> list[dict]:
    """Each spurious row (no truth mode within :data:`TOLERANCE`) with its class.

    Parameters
    ----------
    rows : list of dict with ``frequency_hz`` (Hz) — the modal table
    truth : list of dict with ``frequency_hz`` (Hz), ``damping_ratio``, ``n``, ``branch``

    Returns
    -------
    list of dict: the row's index and frequency, the nearest truth mode, d (half-power
    half-widths), ``reported`` (another row within 0.3 % of it) and ``class``.
    """
    tf = np.array([t["frequency_hz"] for t in truth])
    hw = np.array([t["damping_ratio"] * t["frequency_hz"] for t in truth])
    rf = np.array([r["frequency_hz"] for r in rows])
    out = []
    for i, f in enumerate(rf):
        if np.any(np.abs(tf / f - 1) <= TOLERANCE):
            continue
        d = np.abs(f - tf) / hw
        k = int(np.argmin(d))
        others = np.delete(rf, i)
        reported = bool(np.any(np.abs(others / tf[k] - 1) <= TOLERANCE))
        cls = ("copy" if reported else "biased") if d[k] <= NEAR_HW else ("between" if d[k] <= BETWEEN_HW else "far")
        out.append({"row": i, "frequency_hz": float(f), "truth_hz": float(tf[k]), "truth_n": truth[k]["n"],
                    "truth_branch": truth[k]["branch"], "d_hw": float(d[k]), "reported": reported, "class": cls})
    return out


def matrix_parser(doc: str) -> argparse.ArgumentParser:
    """The arguments of a script over a kept validation run: its records, its folder, --only."""
    ap = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    ap.add_argument("records", help="the JSON lines of benchmarks/validation.py --out")
    ap.add_argument("keep", help="the folder of benchmarks/validation.py --keep")
    ap.add_argument("--only", action="append", default=[], help="only the cases of this name (repeatable)")
    return ap


def kept_cases(records, keep, only=()):
    """Each case of a kept validation run that ran: (record, its case, its simulation
    config, the simulation, the modal table's rows as read from ``modes.csv``, strings)."""
    for line in Path(records).read_text(encoding="utf-8").splitlines():
        rec = json.loads(line)
        if rec.get("status") != "ok" or (only and rec["name"] not in only):
            continue
        case = Case(**{k: v for k, v in rec["case"].items() if k in Case.__dataclass_fields__})
        cfg = config_for(case)
        with open(Path(keep) / folder_of(rec["name"]) / "run" / "modes.csv", newline="", encoding="utf-8") as fh:
            rows = list(csv.DictReader(fh))
        yield rec, case, cfg, simulate(cfg), rows


def spurious_cases(records, keep, only=()):
    """Each kept case with spurious modes: (record, its run folder, the generator's truth
    modes, the modal table's rows)."""
    for line in Path(records).read_text(encoding="utf-8").splitlines():
        rec = json.loads(line)
        if (only and rec["name"] not in only) or not rec.get("spurious"):
            continue
        run = Path(keep) / folder_of(rec["name"]) / "run"
        case = Case(**{k: v for k, v in rec["case"].items() if k in Case.__dataclass_fields__})
        truth = simulate(config_for(case)).truth["modes"]
        with open(run / "modes.csv", newline="", encoding="utf-8") as fh:
            rows = [dict(r, frequency_hz=float(r["frequency_hz"])) for r in csv.DictReader(fh)]
        yield rec, run, truth, rows


def main(argv=None) -> int:
    a = matrix_parser(__doc__).parse_args(argv)
    counts: dict[str, int] = {}
    for rec, run, truth, rows in spurious_cases(a.records, a.keep, a.only):
        with h5py.File(run / "modal.h5") as f:
            sig_group = json.loads(f.attrs["meta"]).get("significance_in_group", [None] * len(rows))
        print(f"{rec['name']}: {rec['spurious']} spurious of {rec['adopted']}")
        for s in classify_spurious(rows, truth):
            r = rows[s["row"]]
            counts[s["class"]] = counts.get(s["class"], 0) + 1
            print(f"  {s['frequency_hz']:8.2f} Hz  {s['class']:8s} group {r.get('group', ''):>3} "
                  f"n={r.get('n', '')} {r.get('branch', '')}  significance {float(r['significance']):.3f} "
                  f"(in group {sig_group[s['row']]:.3f})  nearest truth {s['truth_hz']:.2f} Hz "
                  f"n={s['truth_n']} {s['truth_branch']}, {s['d_hw']:.2f} half-widths"
                  f"{', reported' if s['reported'] else ''}")
    print("classes:", ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) or "no spurious mode")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
