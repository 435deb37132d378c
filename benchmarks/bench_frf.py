"""FRF stage benchmark (issue 3): the stage against its floor and a naive baseline.

A 34-point × 5-hit × 3-channel test of 32,768 samples per record (float32, simulated), and
in the same run:

* ``stage``  — ``compute_frf`` from arrays in memory (checks, windows, H1, coherence);
* ``floor``  — one batched ``numpy.fft.rfft`` over all the records (force and responses),
  and the same point by point (the stage's own access pattern: the issue's floor); and
  ``scipy.fft.rfft`` point by point — the fastest transform at hand, which the stage itself
  uses (2–3 × numpy's in single precision): the stage over it is what the checks, windows
  and products cost beyond the transform;
* ``csd``    — a straightforward loop: per point, hit and channel, ``scipy.signal.csd`` and
  ``scipy.signal.welch`` (one segment, the whole record), averaged over hits;
* ``command`` — ``tiremodal frf`` from file to file in a subprocess, with its peak RSS.

Prints medians of repeated runs and the ratios; targets: stage ≤ 1.3 × the numpy floor point by point (issue 19),
csd ≥ 20 × stage, command's peak memory ≤ 3 × the raw records' size.

Run: ``python benchmarks/bench_frf.py [--repeat 5]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import scipy.fft
import scipy.signal

from tiremodal_cli.frf.estimate import compute_frf
from tiremodal_cli.io.measurement import write_measurement
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate


def median_times(fns, repeat):
    """Median wall time of each function, the functions interleaved in every round (a
    noisy 2-core machine slows them alike, and the ratios stay honest)."""
    times = [[] for _ in fns]
    for _ in range(repeat):
        for i, fn in enumerate(fns):
            t = time.perf_counter()
            fn()
            times[i].append(time.perf_counter() - t)
    return [float(np.median(t)) for t in times]


def csd_loop(m):
    fs = m.sample_rate
    n = m.n_samples
    out = []
    for ip in range(m.n_points):
        for ic in range(m.n_channels):
            gfy = gff = gyy = 0
            for h in range(m.n_hits):
                f, y = m.force[ip, h], m.response[ip, h, ic]
                _, pfy = scipy.signal.csd(f, y, fs=fs, nperseg=n, window="boxcar", detrend=False)
                _, pff = scipy.signal.welch(f, fs=fs, nperseg=n, window="boxcar", detrend=False)
                _, pyy = scipy.signal.welch(y, fs=fs, nperseg=n, window="boxcar", detrend=False)
                gfy, gff, gyy = gfy + pfy, gff + pff, gyy + pyy
            out.append((gfy / gff, np.abs(gfy) ** 2 / (gff * gyy)))
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=15)
    ap.add_argument("--samples", type=int, default=32768)
    args = ap.parse_args()
    cfg = SimulationConfig(n_points=34, n_hits=5, n_samples=args.samples, sample_rate=8192.0, noise=0.01,
                           params=TyreParameters(m_w=1000.0), seed=1)
    m = simulate(cfg).measurement
    raw = m.force.nbytes + m.response.nbytes
    records = np.concatenate([m.force[:, :, None, :], m.response], axis=2)  # one array, as read
    # two floors: one batched rfft over every record (swings 0.09–1.5 s with memory
    # pressure: an 85 MiB input and its 170 MiB output at once), and the rfft point by
    # point — what the stage itself does (it reads and transforms one point at a time)
    t_floor, t_floor_pt, t_scipy_pt, t_stage = median_times(
        [lambda: np.fft.rfft(records, axis=-1),
         lambda: [np.fft.rfft(records[ip], axis=-1) for ip in range(records.shape[0])],
         lambda: [scipy.fft.rfft(records[ip], axis=-1) for ip in range(records.shape[0])],
         lambda: compute_frf(m)], args.repeat)
    (t_csd,) = median_times([lambda: csd_loop(m)], max(1, args.repeat // 3))
    with tempfile.TemporaryDirectory() as d:
        src = Path(d) / "m.h5"
        write_measurement(src, m)
        exe = [sys.executable, "-c", "import sys; from tiremodal_cli.cli.main import cli; sys.exit(cli())"]
        cmd_times, rss = [], []
        for i in range(max(1, args.repeat // 2)):
            code = ("import resource, subprocess, sys; p = subprocess.run(sys.argv[1:]); "
                    "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")
            t = time.perf_counter()
            out = subprocess.run([sys.executable, "-c", code, *exe, "frf", str(src), "-o", str(Path(d) / f"o{i}.h5")],
                                 capture_output=True, text=True, check=True)
            cmd_times.append(time.perf_counter() - t)
            rss.append(int(out.stdout.strip().splitlines()[-1]) * 1024)
        base = subprocess.run([sys.executable, "-c", code, *exe, "--version"], capture_output=True, text=True,
                              check=True)
        rss_base = int(base.stdout.strip().splitlines()[-1]) * 1024
    t_cmd = float(np.median(cmd_times))
    peak = float(np.median(rss))
    res = {
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
                   f"numpy {np.__version__}",
        "records": f"34 points × 5 hits × (1 force + 3 channels) × {args.samples} samples, float32 "
                   f"({raw / 2**20:.0f} MiB)",
        "floor_rfft_s": t_floor, "floor_rfft_by_point_s": t_floor_pt, "floor_scipy_fft_by_point_s": t_scipy_pt,
        "stage_s": t_stage, "stage_over_floor_by_point": t_stage / t_floor_pt,
        "stage_over_scipy_floor_by_point": t_stage / t_scipy_pt, "csd_loop_s": t_csd, "command_s": t_cmd,
        "stage_over_floor": t_stage / t_floor, "csd_over_stage": t_csd / t_stage,
        "command_peak_rss_mib": peak / 2**20, "idle_rss_mib": rss_base / 2**20,
        "peak_rss_over_raw": peak / raw, "peak_above_idle_over_raw": (peak - rss_base) / raw,
    }
    print(json.dumps(res, indent=2))
    print(f"stage / rfft floor: {res['stage_over_floor']:.2f} batched, {res['stage_over_floor_by_point']:.2f} "
          f"point by point (target ≤ 1.3 point by point); over scipy.fft.rfft point by point: "
          f"{res['stage_over_scipy_floor_by_point']:.2f}", file=sys.stderr)
    print(f"csd loop / stage:   {res['csd_over_stage']:.1f} (target ≥ 20)", file=sys.stderr)
    print(f"command peak RSS / raw records: {res['peak_rss_over_raw']:.2f} "
          f"({res['peak_above_idle_over_raw']:.2f} above the idle interpreter; target ≤ 3)", file=sys.stderr)


if __name__ == "__main__":
    main()
