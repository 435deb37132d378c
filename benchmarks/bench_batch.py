"""Batch benchmark (issue 7): a campaign of simulated 34-point tests, three ways in one run.

* ``direct`` — the baseline: ``pipeline.run`` on each file in a plain loop, in this process
  (no discovery, no checksums, no private folders, no summary);
* ``jobs 1`` — ``run_batch(..., jobs=1)``: the batch machinery, tests one after another;
* ``jobs 2`` — ``run_batch(..., jobs=2)``: two worker processes (forkserver; their start-up
  is counted).

Prints wall times, the speed-up jobs 1 → jobs 2 (target ≥ 1.7 × on 2 cores) and the batch
machinery's overhead per test: (jobs-1 wall − Σ the pipeline's own time in each test) / the
number of tests, as a percentage of the median test (target < 5 %); the direct loop gives
the same figure against an independent baseline. Every mode in each configuration runs on
fresh output folders.

Run: ``python benchmarks/bench_batch.py [--tests 16] [--max-effects 2]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from tiremodal_cli.workflow.batch import load_config, run_batch
from tiremodal_cli.workflow.pipeline import run
from tiremodal_cli.tyre.simulate import simulate_campaign


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tests", type=int, default=16)
    ap.add_argument("--max-effects", type=int, default=2, help="diagnose's effects (0: residual only, faster)")
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    a = ap.parse_args()
    cfg = load_config(None, run_overrides={"max_effects": a.max_effects})
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        pressures = np.linspace(6e5, 9e5, 4)
        files = simulate_campaign(tmp / "tree", pressures, repeats=int(np.ceil(a.tests / len(pressures))), seed=1)
        for f in files[a.tests:]:
            f.unlink()
        files = files[:a.tests]

        t = time.perf_counter()
        direct = [run(f, tmp / "direct" / f.stem, cfg.run, params=cfg.params)["seconds"] for f in files]
        t_direct = time.perf_counter() - t

        walls, recs = {}, {}
        for jobs in (1, 2):
            t = time.perf_counter()
            recs[jobs] = run_batch([tmp / "tree"], tmp / f"jobs{jobs}", cfg, jobs=jobs)
            walls[jobs] = time.perf_counter() - t
            assert all(r["status"] == "done" for r in recs[jobs]), [r["reason"] for r in recs[jobs]]

    inner = [r["pipeline_seconds"] for r in recs[1]]
    med = float(np.median(inner))
    over_batch = (walls[1] - sum(inner)) / a.tests
    over_direct = (walls[1] - t_direct) / a.tests
    res = {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
                   f"{platform.system()} {platform.release()}",
        "tests": a.tests, "max_effects": a.max_effects,
        "direct_s": t_direct, "jobs1_s": walls[1], "jobs2_s": walls[2],
        "median_test_s": med, "median_direct_test_s": float(np.median(direct)),
        "speedup_jobs2": walls[1] / walls[2],
        "overhead_per_test_s": over_batch, "overhead_pct": 100 * over_batch / med,
        "overhead_vs_direct_per_test_s": over_direct, "overhead_vs_direct_pct": 100 * over_direct / med,
    }
    if a.json:
        print(json.dumps(res, indent=2))
        return
    print(f"machine: {res['machine']}")
    print(f"{a.tests} tests, max_effects = {a.max_effects}; median test {med:.2f} s (pipeline's own time)")
    print(f"direct loop   {t_direct:8.1f} s")
    print(f"batch jobs 1  {walls[1]:8.1f} s   = {walls[1] / t_direct:.3f} × direct")
    print(f"batch jobs 2  {walls[2]:8.1f} s   speed-up jobs 1 → 2: {res['speedup_jobs2']:.2f} × (target ≥ 1.7)")
    print(f"overhead per test: {over_batch:.3f} s = {res['overhead_pct']:.2f} % of the median test (target < 5 %); "
          f"against the direct loop {over_direct:.3f} s = {res['overhead_vs_direct_pct']:.2f} %")


if __name__ == "__main__":
    main()
