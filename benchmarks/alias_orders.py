"""What the modal table says of the aliased truth modes it finds: the order, not only the flag.

    python benchmarks/validation.py --jobs 2 --keep /tmp/K --out /tmp/K.jsonl --no-docs
    python benchmarks/alias_orders.py /tmp/K.jsonl /tmp/K            # every case
    python benchmarks/alias_orders.py /tmp/K.jsonl /tmp/K --only paper:physics=sidewall_membrane --list

The ruler (``workflow/validation_scoring.py``) counts a truth mode of order n > N/2 as found
by any row flagged aliased within 0.3 % of its frequency. The issue asks more of such a row:
its candidate true orders. Here each found aliased truth mode (the nearest aliased row within
0.3 %) is sorted by what the row claims:

* **n right** — the row's n is the truth's;
* **n in candidates** — not its n, but one of its ``n_candidates`` (a crowd's list);
* **right class** — neither, but the row's spatial order is the truth's alias class
  (n mod N folded to 0 … N/2): the decomposition put it in the right group and the
  classifier chose another member of the class (from the dispersion it read);
* **other class** — the row belongs to another order group: it is another mode at that
  frequency (a crowd member of another class), which the ruler's frequency match took.

and by whether its branch is the truth's. ``--list`` prints every row of the last two kinds.
"""

from __future__ import annotations

from collections import Counter

from crowds import _alias
from spurious import kept_cases, matrix_parser

from tiremodal_cli.workflow.validation_scoring import TOLERANCE, expected_groups


def alias_claims(groups: list[dict], rows: list[dict], n_points: int) -> list[tuple]:
    """(kind, branch right, truth group, row) for each expected aliased truth group of a tyre
    branch that an aliased row within :data:`TOLERANCE` finds (the nearest such row).
    ``rows``: the modal table (``modes.csv``, strings)."""
    out = []
    for g in groups:
        if not (g["expected"] and g["aliased"]) or g["branch"] not in ("same", "opposite"):
            continue
        near = [r for r in rows if str(r.get("n_aliased", "")).lower() == "true"
                and abs(float(r["frequency_hz"]) / g["frequency_hz"] - 1) <= TOLERANCE]
        if not near:
            continue
        r = min(near, key=lambda r: abs(float(r["frequency_hz"]) / g["frequency_hz"] - 1))
        cands = [int(x) for x in r.get("n_candidates", "").split()] if r.get("n_candidates") else []
        if int(r["n"]) == g["n"]:
            kind = "n right"
        elif g["n"] in cands:
            kind = "n in candidates"
        elif int(r["n_spatial"]) == _alias(g["n"], n_points):
            kind = "right class"
        else:
            kind = "other class"
        out.append((kind, r["branch"] == g["branch"], g, r))
    return out


def main(argv=None) -> int:
    ap = matrix_parser(__doc__)
    ap.add_argument("--list", action="store_true", help="print every row of the right class or another class")
    a = ap.parse_args(argv)
    total: dict[str, Counter] = {}
    for rec, case, cfg, sim, rows in kept_cases(a.records, a.keep, a.only):
        t = total.setdefault(case.generator, Counter())
        for kind, branch_ok, g, r in alias_claims(expected_groups(sim, cfg), rows, len(sim.truth["point_angle_rad"])):
            t[kind, branch_ok] += 1
            if a.list and kind in ("right class", "other class"):
                print(f"{rec['name']}: {kind}: truth n={g['n']} {g['branch']} at {g['frequency_hz']:.2f} Hz, "
                      f"row {float(r['frequency_hz']):.2f} Hz n={r['n']} {r['branch']} (spatial {r['n_spatial']})")
    for gen, t in sorted(total.items()):
        n = sum(t.values())
        parts = ", ".join(f"{kind} {t[kind, True] + t[kind, False]} (branch wrong {t[kind, False]})"
                          for kind in ("n right", "n in candidates", "right class", "other class"))
        print(f"{gen}: {n} aliased truth modes found — {parts}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
