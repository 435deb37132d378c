"""False-alarm and miss rates of the joint refinement's proposal rule (modal.joint), on seeded
modal sums of a grid with missing points (the setting of tests/test_joint.py: a branch of
opposite-phase modes f(n) = 300 + 15 n Hz, ζ = 3 %, n = 4 … 11, on 19 of 24 points, 2 %
noise).

Two settings per seed: (a) the FRFs hold order 8 and the modes found lack it — a proposal
there is right (miss if not kept, or kept more than 0.3 % off); (b) the FRFs lack order 8
too — a proposal there is a false alarm if kept. In both the extrapolated order 12, which
the FRFs never hold, is proposed as well (a false alarm if kept).

    python benchmarks/joint_false_alarms.py [N_SEEDS]
"""

from __future__ import annotations

import sys

import numpy as np
from threadpoolctl import threadpool_limits

sys.path.insert(0, "tests")
from test_joint import _branch, _f  # noqa: E402

from tiremodal_cli.modal.joint import add_missing_orders, aliased_group  # noqa: E402
from tiremodal_cli.modal.lsce import poles_to_modal  # noqa: E402


def _kept(out, n):
    g = aliased_group(n, 24)
    return [poles_to_modal(m.pole)[0] for m in out if m.group == g]


def main(n_seeds: int) -> None:
    miss = fa_8 = fa_12 = 0
    for seed in range(n_seeds):
        for present in (True, False):
            freq, Hb, th, modes, synth = _branch(seed, missing=8, drop_from_data=not present)
            with threadpool_limits(1):
                out = add_missing_orders(freq, Hb, th, ["tread", "sidewall"], modes, synth)[0]
            k8 = _kept(out, 8)
            if present:
                miss += not (len(k8) == 1 and abs(k8[0] / _f(8) - 1) < 0.003)
            else:
                fa_8 += bool(k8)
            fa_12 += bool(_kept(out, 12))
        print(f"seed {seed}: misses {miss}, false alarms at an absent interior order {fa_8}, "
              f"at the extrapolated order {fa_12}", flush=True)
    print(f"{n_seeds} seeds: order 8 missed {miss}/{n_seeds}; false alarms: interior {fa_8}/{n_seeds}, "
          f"extrapolated {fa_12}/{2 * n_seeds}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 20)
