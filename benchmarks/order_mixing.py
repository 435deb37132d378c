"""The order-mixing test's share on the validation matrix: with a lumped mass and without.

    python benchmarks/validation.py --no-docs --out /tmp/m0.jsonl --keep /tmp/m0 [--seed-offset N]
    python benchmarks/order_mixing.py /tmp/m0 [/tmp/m1000 ...]

For every kept case (``KEEP/<case>/run/modal.h5``) the share of the clear modes' tests that
found the mode's pole in another order group (``meta.order_mixing``, ``modal.mixing``),
grouped by whether the case's physics holds a lumped mass (``added_mass``, ``mass``), and
whether the test ran (it does not on grids with gaps no mirror image filled, nor where the
mirror test already shows the asymmetry). Prints each group's range, and the cases on the
wrong side of :data:`~tiremodal_cli.modal.mixing.MIXED_FRACTION` (false alarms: no mass,
mixed; misses: a mass the test ran on, not mixed).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tiremodal_cli.io.modalfile import read_modal  # noqa: E402
from tiremodal_cli.modal.mixing import MIXED_FRACTION  # noqa: E402


def _has_mass(case_dir: str) -> bool:
    physics = case_dir.split("physics-")[-1] if "physics-" in case_dir else ""
    return any(p in ("added_mass", "mass") for p in physics.split("+"))


def main(keeps: list[str]) -> int:
    rows = []
    for keep in keeps:
        for f in sorted(Path(keep).glob("*/run/modal.h5")):
            mix = (read_modal(f).meta or {}).get("order_mixing")
            rows.append((f.parts[-3], keep, _has_mass(f.parts[-3]), mix))
    for mass in (False, True):
        ran = sorted((m["fraction"], c, k) for c, k, ms, m in rows if ms is mass and m and m["fraction"] is not None)
        off = sum(1 for _, _, ms, m in rows if ms is mass and not (m and m["fraction"] is not None))
        label = "with a lumped mass" if mass else "without a mass"
        if ran:
            print(f"{label}: {len(ran)} tests ran, share {ran[0][0]:.2f}–{ran[-1][0]:.2f} "
                  f"(median {ran[len(ran) // 2][0]:.2f}); not run: {off}")
        else:
            print(f"{label}: no test ran; not run: {off}")
        wrong = [r for r in ran if (r[0] > MIXED_FRACTION) is not mass]
        for fr, c, k in wrong:
            print(f"    {'miss' if mass else 'false alarm'}: {c} ({k}) {fr:.2f}")
    return 0


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1:]))
