"""pLSCF (ours, :mod:`tiremodal_cli.modal.plscf`) against sdypy-EMA's LSCF on the real beam.

    python benchmarks/bench_plscf.py [--repeat 3]

Both get the same FRFs (tests/data/beam: 3 accelerances, 0–1,000 Hz at 1 Hz) and compute
the poles of every model order 1 … 60 (no selection), BLAS on one thread for both
(threadpoolctl). Ours on the 20–990 Hz band; sdypy on 0–990 Hz (its zoomed band, lower > 0,
shifts its poles in 0.31). Printed: median time of each and the ratio, and for each of the
six reference modes (51.52 … 958.53 Hz) the median over orders ≥ 20 of the nearest pole's
frequency error. sdypy 0.31 returns LSCF poles with the sign of σ reversed (its damping
ratios come out negative): we take abs() of its frequencies and damping ratios.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tiremodal_cli.modal.plscf import sweep_plscf  # noqa: E402

BEAM = ROOT / "tests" / "data" / "beam"
REF = np.array([51.52, 142.18, 278.66, 460.40, 687.16, 958.53])
ORDERS = range(1, 61)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    from sdypy import EMA

    H = np.array([np.genfromtxt(BEAM / f"meas_point_{i}.txt", dtype=complex) for i in (1, 2, 3)])
    f = np.arange(1001.0)
    sel = (f >= 20) & (f <= 990)
    ours_t, theirs_t = [], []
    with threadpool_limits(limits=1, user_api="blas"):
        for _ in range(a.repeat):
            t = time.perf_counter()
            ours = sweep_plscf(f[sel], H[:, None, sel], ORDERS)
            ours_t.append(time.perf_counter() - t)
            model = EMA.Model(frf=H, freq=f, lower=0, upper=990, pol_order_high=max(ORDERS), frf_form="accelerance")
            t = time.perf_counter()
            model.get_poles(method="lscf", show_progress=False)
            theirs_t.append(time.perf_counter() - t)
    # sdypy 0.31: LSCF poles with the wrong sign of σ (negative damping ratios): abs()
    theirs = [(np.abs(np.asarray(fn, float)), np.abs(np.asarray(xi, float)))
              for fn, xi in zip(model.pole_freq, model.pole_xi)]

    def err(per_order):
        e = []
        for fr in REF:
            d = [np.min(np.abs(fn / fr - 1)) for fn, _ in per_order if len(fn)]
            e.append(100 * np.median(d))
        return np.array(e)

    e_ours = err([(op.freq_hz, op.damping_ratio) for op in ours if op.order >= 20])
    e_theirs = err([x for x in theirs[19:]])
    to, tt = np.median(ours_t), np.median(theirs_t)
    print(f"orders 1–{max(ORDERS)}, 3 FRFs × {sel.sum()} lines; BLAS 1 thread; median of {a.repeat}")
    print(f"ours pLSCF {to:.3f} s; sdypy LSCF {tt:.3f} s; sdypy / ours = {tt / to:.2f}")
    print("median frequency error over orders ≥ 20, % (ours | sdypy):")
    for fr, x, y in zip(REF, e_ours, e_theirs):
        print(f"  {fr:8.2f} Hz  {x:.4f} | {y:.4f}")


if __name__ == "__main__":
    main()
