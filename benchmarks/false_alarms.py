"""False alarms of the modal stage's support rules, measured on seeded data of known truth.

    python benchmarks/false_alarms.py [--trials 20]

1. **Noise only**: FRFs that are complex white Gaussian noise (no mode at all), 1 and 3
   FRFs of 2,001 lines: every adopted mode is a false alarm.
2. **Four known modes + noise**: one FRF (single reference and response: every MAC is 1)
   of four modes with ζ = 0.05 %, two of them 1.5 half-power bandwidths apart, 0.5 % and
   2 % noise: adopted modes not within 0.1 % of a true one are false alarms, true modes not
   found are misses.

Prints one line per setting: trials, false alarms per trial, trials with any false alarm,
misses. Seeds 0 … trials − 1.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tiremodal_cli.errors import DataFormatError  # noqa: E402
from tiremodal_cli.modal.lsfd import synthesize  # noqa: E402
from tiremodal_cli.modal.modes import ModalOptions, estimate_modes  # noqa: E402


def noise_only(seed, n_frf):
    rng = np.random.default_rng(seed)
    f = np.arange(0, 1000.5, 0.5)
    H = rng.standard_normal((n_frf, 1, f.size)) + 1j * rng.standard_normal((n_frf, 1, f.size))
    try:
        res = estimate_modes(f, H, form="accelerance", opt=ModalOptions(band_hz=(100, 900)))
        return res.freq_hz.size, 0
    except DataFormatError:
        return 0, 0


def four_modes(seed, noise):
    rng = np.random.default_rng(seed)
    zeta, f0 = 5e-4, 4000.0
    fn = np.array([3200.0, f0, f0 + 1.5 * 2 * zeta * f0, 4700.0])
    s = -zeta * 2 * np.pi * fn + 1j * 2 * np.pi * fn * np.sqrt(1 - zeta**2)
    f = np.arange(0, 6400, 0.5)
    H = synthesize(f, rng.uniform(0.5, 1.5, (1, 4)) * 1e3, s, form="accelerance")
    H = H + noise * np.abs(H).mean() * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    res = estimate_modes(f, H[:, None, :], form="accelerance", opt=ModalOptions(band_hz=(3000, 5000)))
    false = sum(np.min(np.abs(fn / x - 1)) > 1e-3 for x in res.freq_hz)
    missed = sum(np.min(np.abs(res.freq_hz / x - 1)) > 1e-3 for x in fn)
    return false, missed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=20)
    a = ap.parse_args()
    settings = [("noise only, 1 FRF", lambda k: noise_only(k, 1)), ("noise only, 3 FRFs", lambda k: noise_only(k, 3)),
                ("4 modes, 1 FRF, 0.5 % noise", lambda k: four_modes(k, 0.005)),
                ("4 modes, 1 FRF, 2 % noise", lambda k: four_modes(k, 0.02))]
    print("| data | trials | false alarms / trial | trials with any | misses / trial |")
    print("|---|---|---|---|---|")
    for name, fn in settings:
        out = np.array([fn(k) for k in range(a.trials)])
        print(f"| {name} | {a.trials} | {out[:, 0].mean():.2f} | {np.sum(out[:, 0] > 0)} | {out[:, 1].mean():.2f} |",
              flush=True)


if __name__ == "__main__":
    main()
