"""What a test whose circumferential orders mix loses: the expected truth modes missed or
misread, by their peak's share of the test's strongest peak, in tests with a mass and
without (``modal.mixing.MIXED_LOSS``, the note ``run`` and ``lsce`` give such a test).

    python benchmarks/validation.py --jobs 2 --no-docs --out m.jsonl
    python benchmarks/validation.py --jobs 2 --held-out-levels 12 --held-out-seed 7000 --out h.jsonl
    python benchmarks/validation.py --jobs 2 --tyre car --out c.jsonl
    python benchmarks/validation.py --jobs 2 --tyre car --held-out-levels 12 --out ch.jsonl
    python benchmarks/mixed_completeness.py m.jsonl h.jsonl c.jsonl ch.jsonl
    python benchmarks/mixed_completeness.py --note-only m.jsonl ...   # whether the note fired only

Each case is simulated again (seeded: the same truth) for its truth modes' peaks: a mode's
peak is max over channels and points of |φ_tread φ_channel| / (2ζ), the receptance-like
peak the ruler's visibility uses, over the largest of the case's expected modes. Takes
about 7 minutes on 2 cores for the four runs (the ring's simulations).
"""

from __future__ import annotations

import json
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tiremodal_cli.modal.mixing import WEAK_PEAK_SHARE  # noqa: E402
from tiremodal_cli.tyre.simulate import simulate  # noqa: E402
from tiremodal_cli.workflow.validation import Case, config_for  # noqa: E402
from tiremodal_cli.workflow.validation_scoring import expected_groups  # noqa: E402

BINS = (0.0, 0.003, 0.01, 0.03, WEAK_PEAK_SHARE, 1.0 + 1e-9)


def peaks(case_dict: dict) -> list[tuple]:
    """(frequency, n, branch, peak) of each expected truth mode of a case."""
    cfg = config_for(Case(**case_dict))
    sim = simulate(cfg)
    tread = next(ch.name for ch in cfg.channels if ch.location == "tread")
    out = []
    for g in expected_groups(sim, cfg):
        if not g["expected"]:
            continue
        best = 0.0
        for m in sim.truth["modes"]:
            if m["n"] == g["n"] and m["branch"] == g["branch"] and min(abs(m["frequency_hz"] - f) for f in g["members"]) < 1e-6:
                pin = np.asarray(m["shape_at_points"][tread])
                for ch in cfg.channels:
                    phi = np.asarray(m["shape_at_points"][ch.name])[0]
                    best = max(best, float(np.max(np.abs(phi * pin))) / (2 * m["damping_ratio"]))
        out.append((g["frequency_hz"], g["n"], g["branch"], best))
    return out


def main(paths, note_only: bool = False) -> int:
    recs = [r for p in paths for r in map(json.loads, Path(p).read_text().splitlines()) if r.get("status") == "ok"]
    fired = [r for r in recs if "orders_mix" in r]  # (runs since session 45 record whether the note fired)
    if fired:
        mass = [r for r in fired if "mass" in r["case"]["physics"]]
        plain = [r for r in fired if "mass" not in r["case"]["physics"]]
        print(f"the note (orders_mix): fired in {sum(r['orders_mix'] for r in mass)} of {len(mass)} tests with a mass, "
              f"{sum(r['orders_mix'] for r in plain)} of {len(plain)} without")
        for r in fired:
            if r["orders_mix"] != ("mass" in r["case"]["physics"]):
                print(f"  {'false alarm' if r['orders_mix'] else 'silent'}: {r['name']}")
    if note_only:
        return 0
    with ProcessPoolExecutor(2) as ex:
        all_peaks = list(ex.map(peaks, [r["case"] for r in recs]))
    counts = {k: np.zeros((len(BINS) - 1, 2), int) for k in ("mass", "no mass")}
    cases = {"mass": 0, "no mass": 0}
    for r, pk in zip(recs, all_peaks):
        key = "mass" if "mass" in r["case"]["physics"] else "no mass"
        cases[key] += 1
        top = max((p[3] for p in pk), default=1.0)
        for d in r["detail"]:
            m = [p for p in pk if abs(p[0] - d["frequency_hz"]) < 0.01 and p[1] == d["n"] and p[2] == d["branch"]]
            if m:
                b = int(np.searchsorted(BINS, m[0][3] / top, side="right") - 1)
                counts[key][b] += (1, d["status"] != "found" and not d["status"].startswith("aliased"))
    for key, t in counts.items():
        print(f"{key} ({cases[key]} tests)")
        for i in range(len(BINS) - 1):
            print(f"  peak {BINS[i]:.3f}–{min(BINS[i + 1], 1):.3f} of the strongest: {t[i, 0]:5d} expected, "
                  f"{t[i, 1]:4d} missed or misread ({100 * t[i, 1] / max(1, t[i, 0]):.1f} %)")
        w = t[:-1].sum(axis=0)
        print(f"  under {WEAK_PEAK_SHARE:g}: {w[1]}/{w[0]} ({100 * w[1] / max(1, w[0]):.1f} %); "
              f"above: {t[-1, 1]}/{t[-1, 0]} ({100 * t[-1, 1] / max(1, t[-1, 0]):.1f} %)")
    return 0


if __name__ == "__main__":
    args = [a for a in sys.argv[1:] if a != "--note-only"]
    raise SystemExit(main(args, note_only="--note-only" in sys.argv[1:]))
