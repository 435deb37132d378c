"""The report's mode animations: one figure for every mode (blitting the moving rings)
against the baseline of a figure per mode (what ``mode_gif`` does for one mode).

    python benchmarks/bench_report.py [--repeats 3]

Runs the sample (sample_data/gl073a_sim.h5) through ``run`` once, then times, interleaved,
the animations of all its modes both ways and the whole ``report``; prints medians and the
ratio. Also prints the report's size.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    from tiremodal_cli.io.export import shape_set
    from tiremodal_cli.io.modalfile import read_modal
    from tiremodal_cli.workflow.pipeline import run
    from tiremodal_cli.plots import mode_gif, mode_gifs
    from tiremodal_cli.workflow.report import report_run

    with tempfile.TemporaryDirectory() as d:
        out = Path(d) / "run"
        run(ROOT / "sample_data" / "gl073a_sim.h5", out)
        s = shape_set(read_modal(out / "modal.h5"))
        k = s.frequency_hz.size
        t = {"one figure per mode (baseline)": [], "one figure for all (mode_gifs)": [], "whole report": []}
        for _ in range(a.repeats):
            t0 = time.perf_counter()
            base = [mode_gif(s, i) for i in range(k)]
            t1 = time.perf_counter()
            ours = mode_gifs(s)
            t2 = time.perf_counter()
            report_run(out)
            t3 = time.perf_counter()
            t["one figure per mode (baseline)"].append(t1 - t0)
            t["one figure for all (mode_gifs)"].append(t2 - t1)
            t["whole report"].append(t3 - t2)
        assert [len(b) for b in base] == [len(b) for b in ours]
        med = {key: statistics.median(v) for key, v in t.items()}
        print(f"{k} modes, {a.repeats} repeats, medians:")
        for key, v in med.items():
            print(f"  {key:34s} {v:6.2f} s")
        print(f"  ratio baseline / ours: {med['one figure per mode (baseline)'] / med['one figure for all (mode_gifs)']:.1f}")
        print(f"  report.html: {(out / 'report.html').stat().st_size / 1e6:.1f} MB, "
              f"GIFs {sum(map(len, ours)) / 1e6:.2f} MB")


if __name__ == "__main__":
    main()
