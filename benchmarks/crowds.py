"""How right the modal table's crowd flags are: each flag against the truth's crowds.

    python benchmarks/validation.py --jobs 1 --keep /tmp/K --out /tmp/K.jsonl --no-docs
    python benchmarks/crowds.py /tmp/K.jsonl /tmp/K            # every case
    python benchmarks/crowds.py /tmp/K.jsonl /tmp/K --only ring:noise=0.05 --list

The truth's crowd is the ruler's (``workflow/validation_scoring.py``): another truth mode of
the same branch whose order aliases onto this one's on the N points lies within the half-power
bandwidth 2ζf. Each row of ``run/modes.csv`` with an order is matched to the truth mode of
its branch whose order aliases onto the row's spatial order, nearest in frequency within
0.3 % (rows matching none are not counted: spurious, or read on the wrong branch or order),
and counted as a right flag (both crowds), a *false crowd* (flagged, the truth's order stands
alone), a *missed crowd* (not flagged, the truth's is a crowd) or right without a flag.
``--list`` prints every false and missed crowd.
"""

from __future__ import annotations


from spurious import kept_cases, matrix_parser

from tiremodal_cli.workflow.validation_scoring import TOLERANCE, expected_groups


def _alias(n: int, n_points: int) -> int:
    r = n % n_points
    return min(r, n_points - r)


def crowd_counts(groups: list[dict], rows: list[dict], n_points: int) -> tuple[dict, list]:
    """{"right", "right_alone", "false", "missed"} counts of the rows' crowd flags against
    the truth ``groups`` (:func:`expected_groups`), and the (row, truth group, kind) of each
    false or missed crowd. ``rows``: the modal table's rows (``modes.csv``, strings)."""
    counts = {"right": 0, "right_alone": 0, "false": 0, "missed": 0}
    wrong = []
    for r in rows:
        if r.get("n") in ("", None) or not r.get("branch"):
            continue
        f, ns = float(r["frequency_hz"]), int(r["n_spatial"])
        near = [g for g in groups if g["valid"] and g["branch"] == r["branch"] and _alias(g["n"], n_points) == ns
                and abs(g["frequency_hz"] / f - 1) <= TOLERANCE]
        if not near:
            continue
        g = min(near, key=lambda g: abs(g["frequency_hz"] - f))
        flagged = str(r.get("crowd", "")).lower() == "true"
        kind = {(True, True): "right", (False, False): "right_alone", (True, False): "false",
                (False, True): "missed"}[(flagged, bool(g["crowd"]))]
        counts[kind] += 1
        if kind in ("false", "missed"):
            wrong.append((r, g, kind))
    return counts, wrong


def main(argv=None) -> int:
    ap = matrix_parser(__doc__)
    ap.add_argument("--list", action="store_true", help="print every false and missed crowd")
    a = ap.parse_args(argv)
    total: dict[str, dict[str, int]] = {}
    for rec, case, cfg, sim, rows in kept_cases(a.records, a.keep, a.only):
        counts, wrong = crowd_counts(expected_groups(sim, cfg), rows, len(sim.truth["point_angle_rad"]))
        t = total.setdefault(case.generator, dict.fromkeys(counts, 0))
        for k, v in counts.items():
            t[k] += v
        if a.list:
            for r, g, kind in wrong:
                print(f"{rec['name']}: {kind} crowd {float(r['frequency_hz']):.2f} Hz n={r['n']} {r['branch']} "
                      f"(candidates {r.get('n_candidates') or '-'}; truth n={g['n']} at {g['frequency_hz']:.2f} Hz)")
    for gen, t in sorted(total.items()):
        flagged, crowds = t["right"] + t["false"], t["right"] + t["missed"]
        print(f"{gen}: {t['right']} crowds flagged right, {t['false']} false of {flagged} flagged "
              f"({100 * t['false'] / max(flagged, 1):.1f} %), {t['missed']} missed of {crowds} truth crowds "
              f"({100 * t['missed'] / max(crowds, 1):.1f} %); {t['right_alone']} right without a flag")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
