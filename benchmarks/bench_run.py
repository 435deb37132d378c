"""Whole-test benchmark (issue 19): ``run`` per stage, ``diagnose`` on Table A1 and start-up,
against the implementation before issue 19 in the same run.

Baseline ``before``: the package as it was at commit BASELINE (5c57b5d: one solve_modes per
DE member and call, scipy.stats, every command imported at start-up), extracted with
``git archive`` into a temporary folder and imported as ``tiremodal_before`` next to the
present ``tiremodal_cli``. Both run in this process, interleaved round by round (the
machine is shared; medians of ``--repeat`` rounds), each as a user runs it: no thread limit
from outside (the present modal stage holds BLAS to one thread itself and solves the
poly-reference sweeps' orders in as many threads as the BLAS pool has — two here; a batch
job runs under a limit of one). ``tiremodal run`` on the sample is also timed from the
shell (a fresh interpreter: start-up and imports included), and so is the package at
``--previous`` (default PREVIOUS, the end of the previous session) beside the present one,
both started the same way (``python -S``, the package's folder first on the path).

Prints, for each case, the median wall time of each implementation and their ratio, and
the model evaluations of each: for ``before`` the calls of model_frequencies (one
parameter set each); for the present code the array calls and the parameter sets they
held. Targets: run on the sample ≤ 2 s, diagnose on Table A1 ≤ 1 s, ``--help`` ≤ 0.2 s, and
``run`` on the issue's large test (40 points, 3 hits, 5,120 Hz, 16,384 samples, simulated
here with a seed; the band from the data) ≤ 3 s. The baseline's band was a fixed fraction
of the sample rate: on that test it may fail, and the failure is printed.

Run: ``python benchmarks/bench_run.py [--repeat 3]`` (needs git and the repository's history).
"""

from __future__ import annotations

import argparse
import csv
import importlib
import io
import os
import platform
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]
BASELINE = "5c57b5d"
#: the end of the previous session (its shell run is timed beside the present one)
PREVIOUS = "2ea4cf1"
SAMPLE = ROOT / "sample_data" / "gl073a_sim.h5"
TABLE_A1 = ROOT / "sample_data" / "paper_table_a1.csv"


def load_before(tmp: Path):
    """The package at BASELINE as ``tiremodal_before`` (relative imports keep it whole)."""
    data = subprocess.run(["git", "archive", BASELINE, "tiremodal_cli"], cwd=ROOT, capture_output=True,
                          check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        tar.extractall(tmp, filter="data")
    (tmp / "tiremodal_cli").rename(tmp / "tiremodal_before")
    sys.path.insert(0, str(tmp))
    return importlib.import_module("tiremodal_before")


#: where each implementation keeps what the benchmark calls (the present package is laid out
#: by stage; the baseline is flat)
MODULES = {
    "tiremodal_cli": {"evaluate": "tyre.evaluate", "pipeline": "workflow.pipeline", "run_options": "workflow.run_options", "diagnose": "diagnose",
                      "model": "tyre.model"},
    "tiremodal_before": {"evaluate": "identify", "pipeline": "pipeline", "run_options": "pipeline", "diagnose": "diagnose", "model": "model"},
}


def module(pkg, what):
    return importlib.import_module(f"{pkg}.{MODULES[pkg][what]}")


class Counter:
    """Counts model evaluations of one implementation while a case runs."""

    def __init__(self, pkg, present: bool):
        self.ident = module(pkg, "evaluate")
        self.present = present
        self.calls = self.sets = 0
        if present:
            orig = self.ident.Evaluator.frequencies

            def counted(ev, logX, _orig=orig):
                self.calls += 1
                self.sets += logX.shape[1]
                return _orig(ev, logX)
            self.ident.Evaluator.frequencies = counted
        else:
            orig = self.ident.model_frequencies

            def counted(*a, _orig=orig, **k):
                self.calls += 1
                self.sets += 1
                return _orig(*a, **k)
            self.ident.model_frequencies = counted

    def reset(self):
        self.calls = self.sets = 0

    def text(self):
        return f"{self.sets:,} sets in {self.calls:,} calls" if self.present else f"{self.sets:,} sets"


def run_case(pkg, out: Path, measurement: Path = SAMPLE):
    """``run`` on ``measurement``: per-stage times (s), and what it found (modes, effects)."""
    pipeline = module(pkg, "pipeline")
    marks = []
    t0 = time.perf_counter()
    summary = pipeline.run(measurement, out, module(pkg, "run_options").RunOptions(),
                           progress=lambda s: marks.append((s, time.perf_counter())))
    t_end = time.perf_counter()
    stages = {}
    for (name, t), nxt in zip(marks, marks[1:] + [("end", t_end)]):
        stages[name] = nxt[1] - t
    stages["total"] = t_end - t0
    found = f"{summary['modes_found']} modes, adopted {', '.join(summary['adopted_effects']) or 'none'}"
    return stages, found


def make_test40(path: Path) -> Path:
    """The issue's large test: 40 points, 3 hits, 5,120 Hz, 16,384 samples (seeded, 1 % noise)."""
    from tiremodal_cli.io.measurement import write_measurement
    from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

    cfg = SimulationConfig(n_points=40, n_hits=3, sample_rate=5120.0, n_samples=16384, noise=0.01, seed=1)
    write_measurement(path, simulate(cfg).measurement, overwrite=True)
    return path


def a1_case(pkg):
    diagnose = module(pkg, "diagnose")
    model = module(pkg, "model")
    with TABLE_A1.open() as fh:
        rows = list(csv.DictReader(fh))
    t = time.perf_counter()
    d = diagnose.diagnose(rows, model.TyreParameters())
    return time.perf_counter() - t, d.adopted


def cli_run_time(out: Path) -> float:
    """``tiremodal run`` on the sample from the shell (a fresh interpreter), s."""
    t = time.perf_counter()
    subprocess.run([sys.executable, "-m", "tiremodal_cli", "run", str(SAMPLE), "-o", str(out), "--overwrite"],
                   capture_output=True, check=True)
    return time.perf_counter() - t


def isolated_run_time(src: Path, out: Path) -> float:
    """``run`` on the sample from the shell with the package found in ``src`` (a fresh
    interpreter, ``-S``: no site processing, so that the editable install cannot redirect
    the import; site-packages put on the path by hand), s. Both the present package and
    the previous commit's are timed this way, for the same start-up."""
    import site

    code = (f"import sys; sys.path[:0] = [{str(src)!r}, {site.getsitepackages()[0]!r}]; "
            f"from tiremodal_cli.cli.main import cli; "
            f"cli(['run', {str(SAMPLE)!r}, '-o', {str(out)!r}, '--overwrite'])")
    t = time.perf_counter()
    subprocess.run([sys.executable, "-S", "-c", code], capture_output=True, check=True)
    return time.perf_counter() - t


def load_previous(tmp: Path, commit: str) -> Path:
    """The package at ``commit`` extracted into ``tmp/previous`` (it imports itself as
    ``tiremodal_cli``: absolute imports, so it runs in its own interpreter)."""
    dest = tmp / "previous"
    dest.mkdir()
    data = subprocess.run(["git", "archive", commit, "tiremodal_cli"], cwd=ROOT, capture_output=True,
                          check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        tar.extractall(dest, filter="data")
    return dest


def help_time(pkg, tmp):
    env = dict(os.environ, PYTHONPATH=f"{tmp}{os.pathsep}{ROOT}")
    code = f"from {pkg}.cli.main import cli; cli(['--help'])"
    t = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, check=True)
    return time.perf_counter() - t


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--previous", default=PREVIOUS, help="a commit whose shell run is timed beside the present one")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        load_before(tmp)
        previous = load_previous(tmp, args.previous)
        shell = {"present": [], "previous": []}
        impls = {"present": "tiremodal_cli", "before": "tiremodal_before"}
        test40 = make_test40(tmp / "test40.h5")
        counters = {k: Counter(p, k == "present") for k, p in impls.items()}
        times = {k: {"help": [], "a1": []} for k in impls}
        evals = {}
        for rnd in range(args.repeat):
            for k, pkg in (impls.items() if rnd % 2 == 0 else reversed(impls.items())):
                times[k]["help"].append(help_time(pkg, tmp))
                if k == "present":
                    times[k].setdefault("cli", []).append(cli_run_time(tmp / "cli_out"))
                    for which, src in (("present", ROOT), ("previous", previous))[::1 if rnd % 2 == 0 else -1]:
                        shell[which].append(isolated_run_time(src, tmp / f"iso_{which}"))
                counters[k].reset()
                st, found = run_case(pkg, tmp / f"out_{k}")
                evals[(k, "run")] = counters[k].text() + f"; {found}"
                for s, v in st.items():
                    times[k].setdefault(f"run:{s}", []).append(v)
                try:  # the baseline's band was a fixed fraction of the sample rate: it may fail here
                    st40, found40 = run_case(pkg, tmp / f"out40_{k}", test40)
                    evals[(k, "run40")] = found40
                    for s, v in st40.items():
                        times[k].setdefault(f"run40:{s}", []).append(v)
                except Exception as exc:  # noqa: BLE001 — a benchmark reports the baseline's failure
                    evals[(k, "run40")] = f"failed: {type(exc).__name__}: {str(exc)[:120]}"
                counters[k].reset()
                t, adopted = a1_case(pkg)
                times[k]["a1"].append(t)
                evals[(k, "a1")] = counters[k].text() + f"; adopted {', '.join(adopted) or 'none'}"
                print(f"round {rnd + 1}: {k} run {st['total']:.2f} s, A1 diagnose {t:.2f} s", file=sys.stderr)
    print(f"# bench_run: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, {args.repeat} interleaved rounds, no outside thread limit; medians")
    print(f"{'case':<22}{'present s':>11}{'before s':>11}{'ratio':>8}")
    cases = [k for k in times["present"] if k.startswith(("run:", "run40:"))] + ["cli", "a1", "help"]
    label = {"a1": "diagnose Table A1", "help": "tiremodal --help", "cli": "tiremodal run (shell)"}
    for c in cases:
        a = statistics.median(times["present"][c])
        if times["before"].get(c):
            b = statistics.median(times["before"][c])
            print(f"{label.get(c, c):<22}{a:>11.3f}{b:>11.3f}{b / a:>7.1f}x")
        else:
            print(f"{label.get(c, c):<22}{a:>11.3f}{'–':>11}{'–':>8}")
    a, b = statistics.median(shell["present"]), statistics.median(shell["previous"])
    print(f"tiremodal run (shell, -S): present {a:.3f} s, previous ({args.previous}) {b:.3f} s, ratio {b / a:.2f}x")
    print("model evaluations and what was found:")
    names = {"run": "run (sample)", "run40": "run (40 points)", "a1": "diagnose Table A1"}
    for (k, c), v in evals.items():
        print(f"  {k:<8} {names[c]:<18} {v}")


if __name__ == "__main__":
    main()
