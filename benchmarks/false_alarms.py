"""False alarms of the modal stage's support rules, measured on seeded data of known truth.

    python benchmarks/false_alarms.py [--trials 20]

1. **Noise only**: FRFs that are complex white Gaussian noise (no mode at all), 1 and 3
   FRFs of 2,001 lines: every adopted mode is a false alarm.
2. **Four known modes + noise**: one FRF (single reference and response: every MAC is 1)
   of four modes with ζ = 0.05 %, two of them 1.5 half-power bandwidths apart, 0.5 % and
   2 % noise: adopted modes not within 0.1 % of a true one are false alarms, true modes not
   found are misses.
3. **Broad modes**: a strong mode at 100 Hz and a weak one at 400 Hz (ζ = 2 %, 32 lines in
   its half-power half-width) on its mass line, its peak 0, 4 or 8 × the noise RMS per line
   (the weak modes the scatter rule scaled by the bandwidth judges, `groupfit.pin_limit`):
   modes more than 0.3 % from a true one are false alarms, true modes without one are misses.
4. **A quiet channel**: the broad setting on two channels of one point, each with its own
   noise floor (0.5 % of its RMS, as a sensor's), the second 4 × quieter than the first and
   alone holding the weak mode, its peak 0, 4 or 10 × that channel's noise (the per-row
   visibility of the own-peak rule, `groupfit.row_visibility`, session 15).

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


def broad_modes(seed, weak_over_noise):
    """A strong mode at 100 Hz and a broad weak one at 400 Hz on its mass line (ζ = 2 %:
    a half-power half-width of 8 Hz = 32 lines of 0.25 Hz), the weak one's peak
    ``weak_over_noise`` × the complex white noise RMS per line (0: absent). Modes more
    than 0.3 % (the validation matrix's tolerance) from a true one are false alarms."""
    rng = np.random.default_rng(seed)
    zeta, fn = 0.02, np.array([100.0, 400.0])
    s = -zeta * 2 * np.pi * fn + 1j * 2 * np.pi * fn * np.sqrt(1 - zeta**2)
    f, noise = np.arange(0, 600, 0.25), 1e-3
    peak_unit = np.abs(s) ** 2 / np.abs(s.real)  # a unit residue's peak in accelerance
    H = synthesize(f, np.array([[5 * noise * 200 / peak_unit[0], weak_over_noise * noise / peak_unit[1]]]), s,
                   form="accelerance")
    H = H + noise / np.sqrt(2) * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    res = estimate_modes(f, H[:, None, :], form="accelerance", opt=ModalOptions(band_hz=(20, 580), max_order=30))
    true = fn if weak_over_noise > 0 else fn[:1]
    false = sum(np.min(np.abs(true / x - 1)) > 3e-3 for x in res.freq_hz)
    missed = sum(res.freq_hz.size == 0 or np.min(np.abs(res.freq_hz / x - 1)) > 3e-3 for x in true)
    return false, missed


def quiet_channel(seed, weak_over_own_noise, loud=4.0):
    """The broad setting's modes on two channels of one point: a loud one (the strong mode)
    and one ``loud`` × quieter holding the strong mode too and the weak one, whose peak is
    ``weak_over_own_noise`` × that channel's noise RMS per line; each channel's noise is
    complex white, 0.5 % of its own RMS. Scored as :func:`broad_modes`."""
    rng = np.random.default_rng(seed)
    zeta, fn = 0.02, np.array([100.0, 400.0])
    s = -zeta * 2 * np.pi * fn + 1j * 2 * np.pi * fn * np.sqrt(1 - zeta**2)
    f = np.arange(0, 600, 0.25)
    peak_unit = np.abs(s) ** 2 / np.abs(s.real)
    quiet = synthesize(f, np.array([[1.0 / loud, 0.0]]), s, form="accelerance")[0]
    floor = 0.005 * np.sqrt(np.mean(np.abs(quiet) ** 2))
    quiet = quiet + synthesize(f, np.array([[0.0, weak_over_own_noise * floor / peak_unit[1]]]), s,
                               form="accelerance")[0]
    H = np.stack([synthesize(f, np.array([[1.0, 0.0]]), s, form="accelerance")[0], quiet])
    rms = np.sqrt(np.mean(np.abs(H) ** 2, axis=1, keepdims=True))
    H = H + 0.005 * rms / np.sqrt(2) * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    res = estimate_modes(f, H[:, None, :], form="accelerance", opt=ModalOptions(band_hz=(20, 580), max_order=30))
    true = fn if weak_over_own_noise > 0 else fn[:1]
    false = sum(np.min(np.abs(true / x - 1)) > 3e-3 for x in res.freq_hz)
    missed = sum(res.freq_hz.size == 0 or np.min(np.abs(res.freq_hz / x - 1)) > 3e-3 for x in true)
    return false, missed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--trials", type=int, default=20)
    a = ap.parse_args()
    settings = [("noise only, 1 FRF", lambda k: noise_only(k, 1)), ("noise only, 3 FRFs", lambda k: noise_only(k, 3)),
                ("4 modes, 1 FRF, 0.5 % noise", lambda k: four_modes(k, 0.005)),
                ("4 modes, 1 FRF, 2 % noise", lambda k: four_modes(k, 0.02)),
                ("broad mode (ζ = 2 %) and noise only", lambda k: broad_modes(k, 0.0)),
                ("broad mode and a broad weak one at 4 × the noise", lambda k: broad_modes(k, 4.0)),
                ("broad mode and a broad weak one at 8 × the noise", lambda k: broad_modes(k, 8.0)),
                ("two channels, the quiet one's noise only", lambda k: quiet_channel(k, 0.0)),
                ("two channels, a weak mode at 4 × the quiet one's noise", lambda k: quiet_channel(k, 4.0)),
                ("two channels, a weak mode at 10 × the quiet one's noise", lambda k: quiet_channel(k, 10.0))]
    print("| data | trials | false alarms / trial | trials with any | misses / trial |")
    print("|---|---|---|---|---|")
    for name, fn in settings:
        out = np.array([fn(k) for k in range(a.trials)])
        print(f"| {name} | {a.trials} | {out[:, 0].mean():.2f} | {np.sum(out[:, 0] > 0)} | {out[:, 1].mean():.2f} |",
              flush=True)


if __name__ == "__main__":
    main()
