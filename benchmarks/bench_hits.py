"""Fault injection into the FRF stage's hit checks: double hits by bounce delay, overloads,
and the clean hits (none may be rejected), at 1,024 and 2,048 Hz.

A clean simulated test (``simulate``, seeded) gets, on chosen hits, a bounce: the hammer
strikes again ``dt`` later with ``a2`` of the first blow's amplitude, so the force record
and every response record of that hit become ``x(t) + a2 x(t − dt)`` (the structure is
linear; the second blow excites it as the first did), applied as ``X(f)(1 + a2 e^{−i2πf dt})``
to the records' spectra. ``dt`` is drawn uniformly in 1 … 8 ms and ``a2`` in 0.35 … 0.7
(``simulate``'s range). Other hits get an overload: the force or one response clipped
(``simulate``'s clipping). The rest stay clean. ``compute_frf`` with its default checks
then decides; the table counts what it rejected, by fault and delay.

Run: ``python benchmarks/bench_hits.py`` (prints the Markdown table for docs/frf.md).
"""

from __future__ import annotations

import dataclasses
import sys
import time

import numpy as np

from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.io.measurement import Measurement
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.simulate import SimulationConfig, _clip, simulate

BINS_MS = ((1.0, 2.0), (2.0, 3.0), (3.0, 5.0), (5.0, 8.0))
SETUPS = {
    1024: SimulationConfig(params=TyreParameters(m_w=1000.0), n_points=34, n_hits=3, sample_rate=1024.0,
                           n_samples=1024, pulse_width_s=0.002, noise=0.005),
    2048: SimulationConfig(params=TyreParameters(m_w=1000.0), n_points=34, n_hits=3, sample_rate=2048.0,
                           n_samples=2048, pulse_width_s=0.001, noise=0.005),
}


def _bounce(x, fs, dt, a2):
    X = np.fft.rfft(x, axis=-1)
    f = np.fft.rfftfreq(x.shape[-1], 1 / fs)
    return np.fft.irfft(X * (1 + a2 * np.exp(-2j * np.pi * f * dt)), n=x.shape[-1], axis=-1)


def inject(m: Measurement, rng, *, n_double: int, n_clip: int):
    """The test with faults; returns it and {(point, hit): fault description}."""
    force, resp = np.array(m.force, dtype=float), np.array(m.response, dtype=float)
    n_p, n_h = force.shape[:2]
    order = rng.permutation(n_p * n_h)
    faults = {}
    for k in order[:n_double]:
        p, h = divmod(int(k), n_h)
        dt, a2 = rng.uniform(1e-3, 8e-3), rng.uniform(0.35, 0.7)
        force[p, h] = _bounce(force[p, h], m.sample_rate, dt, a2)
        resp[p, h] = _bounce(resp[p, h], m.sample_rate, dt, a2)
        faults[(p, h)] = ("double", dt, a2)
    for j, k in enumerate(order[n_double:n_double + n_clip]):
        p, h = divmod(int(k), n_h)
        if j % 2 == 0:
            force[p, h] = _clip(force[p, h], 0.3)
            faults[(p, h)] = ("overload force", None, None)
        else:
            c = j % resp.shape[2]
            resp[p, h, c] = _clip(resp[p, h, c])
            faults[(p, h)] = ("overload response", None, None)
    out = dataclasses.replace(m, force=force.astype(m.force.dtype), response=resp.astype(m.response.dtype))
    return out, faults


def run(fs: int, seeds=range(4), n_double=48, n_clip=12):
    rows = {}
    t0 = time.perf_counter()
    for seed in seeds:
        cfg = dataclasses.replace(SETUPS[fs], seed=seed)
        m = simulate(cfg).measurement
        rng = np.random.default_rng(1000 + seed)
        bad, faults = inject(m, rng, n_double=n_double, n_clip=n_clip)
        r = compute_frf(bad, FRFOptions(band_hz=(0.0, 0.3125 * fs), exp_end=0.05))
        rejected = {(x.point, x.hit) for x in r.rejections if x.hit is not None}
        for p in range(m.n_points):
            for h in range(m.n_hits):
                kind, dt, _ = faults.get((p, h), ("clean", None, None))
                key = kind if kind != "double" else next(
                    f"double, bounce {lo:g}–{hi:g} ms" for lo, hi in BINS_MS if lo <= 1e3 * dt < hi)
                n, k = rows.get(key, (0, 0))
                rows[key] = (n + 1, k + ((p, h) in rejected))
    return rows, time.perf_counter() - t0


def false_alarms(seeds=range(20), noises=(0.005, 0.05)):
    """Clean tests (12 points × 3 hits) with any hit flagged by the bounce-in-pulse check."""
    from tiremodal_cli.frf.hits import bounce_in_pulse

    n = k = hits = 0
    for fs in (1024, 2048):
        for seed in seeds:
            for noise in noises:
                m = simulate(dataclasses.replace(SETUPS[fs], seed=seed, noise=noise, n_points=12)).measurement
                flags, _, _ = bounce_in_pulse(np.asarray(m.force, float).reshape(-1, m.n_samples), fs)
                n, k, hits = n + 1, k + bool(flags.any()), hits + flags.size
    return n, k, hits


def main():
    order = [f"double, bounce {lo:g}–{hi:g} ms" for lo, hi in BINS_MS] + ["overload force", "overload response",
                                                                          "clean"]
    results = {fs: run(fs) for fs in (1024, 2048)}
    print("| fault | 1,024 Hz: rejected / injected | 2,048 Hz: rejected / injected |")
    print("|---|---|---|")
    for key in order:
        cells = []
        for fs in (1024, 2048):
            n, k = results[fs][0].get(key, (0, 0))
            cells.append(f"{k} / {n}")
        print(f"| {key} | {' | '.join(cells)} |")
    n, k, hits = false_alarms()
    print(f"\nClean tests (12 points × 3 hits, noise 0.5 % and 5 %, 20 seeds, both rates): {k} of {n} "
          f"with a hit flagged by the notch check ({hits} clean hits).")
    for fs in (1024, 2048):
        print(f"# {fs} Hz: {results[fs][1]:.1f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
