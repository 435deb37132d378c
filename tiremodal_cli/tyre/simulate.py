"""Physics-true roving-hammer tests: the tyre model turned into time records.

Records are built in the frequency domain on the DFT grid of the record, so that each
response's spectrum is exactly the analytic FRF times the force's spectrum (a circular
convolution: the responses decay within the record, and whatever is left wraps into the
pre-trigger, as it would in a triggered acquisition). The hammer pulse is a half-sine of
continuous-time Fourier transform ``A π w (1 + e^{-iωw}) / (π² − ω² w²)``; an analog
Butterworth anti-alias filter acts identically on force and responses before sampling.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import scipy.signal

from tiremodal_cli import __version__
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.io.measurement import Measurement
from tiremodal_cli.tyre.model import NOMINAL_RIM_KG, TyreParameters, paper_damping
from tiremodal_cli.tyre.solve import ModalModel, frf, observation, solve_modes
from tiremodal_cli.tyre.ring import RingModes, elements_for, ring_frf, ring_modes, ring_observation
from tiremodal_cli.tyre.ring_parameters import RingParameters

__all__ = ["Channel", "Faults", "SimulationConfig", "Simulation", "simulate", "half_sine_spectrum",
           "DEFAULT_CHANNELS", "CAMPAIGN_CONFIG", "simulate_campaign", "MODELS", "RING_DAMPING"]

#: The generators: "paper" — the paper's model (:mod:`tiremodal_cli.tyre.model`, with the
#: effects of :mod:`tiremodal_cli.tyre.effects`); "ring" — the independent finite-element tyre
#: (:mod:`tiremodal_cli.tyre.ring`), which shares nothing with them but this acquisition path.
MODELS = ("paper", "ring")

#: The ring model's modal damping ratios when ``damping`` is not given: structural modes
#: 2 % (the middle of Table A1's 1.6–3.8 %), modes of the air cavity 0.5 % (a closed air
#: cavity is lightly damped, 0.5–1 % in tyre measurements).
RING_DAMPING = {"structural": 0.02, "cavity": 0.005}


@dataclass(frozen=True)
class Channel:
    name: str
    location: str
    angle_rad: float = 0.0


DEFAULT_CHANNELS = (Channel("tread", "tread", 0.0), Channel("sidewall", "sidewall", 0.0),
                    Channel("rim", "rim", 0.0))


@dataclass(frozen=True)
class Faults:
    """Faults to inject (all off by default).

    Attributes
    ----------
    double_hits : tuple of (point, hit)
        A second, weaker blow 3–8 ms after the first.
    clipped : tuple of (point, hit, channel)
        That record saturates at 60 % of its peak (30 % for channel ``"force"``), and
        low enough that at least three samples sit at the limit (a flat top to see).
    dead_channel : str or None
        That response channel records only a tiny noise in every hit (a broken cable).
    missing_point : int or None
        That impact point is not in the file (skipped by the operator).
    """

    double_hits: tuple[tuple[int, int], ...] = ()
    clipped: tuple[tuple[int, int, str], ...] = ()
    dead_channel: str | None = None
    missing_point: int | None = None


@dataclass(frozen=True)
class SimulationConfig:
    """Everything a simulated test depends on (units in the names or in docs/simulate.md)."""

    params: TyreParameters = TyreParameters()
    effects: dict = field(default_factory=dict)
    n_max: int = 30
    n_points: int = 34
    n_hits: int = 3
    sample_rate: float = 2048.0
    n_samples: int = 4096
    pretrigger_s: float = 0.02
    trigger_jitter_s: float = 0.5e-3
    pulse_width_s: float = 1.0e-3
    pulse_width_jitter: float = 0.1
    amplitude_n: float = 400.0
    amplitude_jitter: float = 0.2
    noise: float = 0.0  # std relative to each channel's RMS over the test
    damping: float | None = None
    anti_alias: bool = True
    channels: tuple[Channel, ...] = DEFAULT_CHANNELS
    faults: Faults = Faults()
    dtype: str = "float32"
    seed: int = 0
    model: str = "paper"
    ring: RingParameters = RingParameters()

    def check(self) -> None:
        def need(cond, msg):
            if not cond:
                raise ParameterError(msg)
        need(self.n_points >= 2, f"n_points={self.n_points} must be ≥ 2")
        need(1 <= self.n_hits <= 100, f"n_hits={self.n_hits} must be 1 … 100")
        need(self.sample_rate > 0, f"sample_rate={self.sample_rate} must be > 0 Hz")
        need(self.n_samples >= 64, f"n_samples={self.n_samples} must be ≥ 64")
        need(0 <= self.pretrigger_s < 0.5 * self.n_samples / self.sample_rate,
             f"pretrigger_s={self.pretrigger_s} must be in [0, half the record)")
        need(self.pulse_width_s > 0, f"pulse_width_s={self.pulse_width_s} must be > 0")
        need(self.noise >= 0, f"noise={self.noise} must be ≥ 0")
        need(self.damping is None or 0 < self.damping < 1, f"damping={self.damping} must be in (0, 1)")
        need(self.dtype in ("float32", "float64"), f"dtype={self.dtype!r}; allowed: float32, float64")
        need(self.model in MODELS, f"model={self.model!r}; allowed: {', '.join(MODELS)}")
        need(self.model == "paper" or not self.effects,
             "effects belong to the paper model; the ring model takes its physics from its own "
             "parameters ([ring] table, docs/simulate.md)")
        need(len(self.channels) >= 1 and any(c.location == "tread" for c in self.channels),
             "at least one tread channel is needed")
        names = [c.name for c in self.channels]
        for p, h in self.faults.double_hits:
            need(0 <= p < self.n_points and 0 <= h < self.n_hits, f"double hit ({p}, {h}) is out of range")
        for p, h, c in self.faults.clipped:
            need(0 <= p < self.n_points and 0 <= h < self.n_hits and (c in names or c == "force"),
                 f"clipped ({p}, {h}, {c!r}) is out of range or names no channel")
        need(self.faults.dead_channel is None or self.faults.dead_channel in names,
             f"dead channel {self.faults.dead_channel!r} is not one of {names}")
        need(self.faults.missing_point is None or 0 <= self.faults.missing_point < self.n_points,
             f"missing point {self.faults.missing_point} is out of range")

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["params"] = self.params.to_dict()
        if self.model == "ring":
            d["ring"] = self.ring.to_dict()
        else:  # (the ring's defaults are not what a paper-model test was made with: not written)
            d.pop("ring", None)
        return d


@dataclass(frozen=True)
class Simulation:
    """A simulated test: the measurement, its truth, and the analytic FRFs.

    Attributes
    ----------
    measurement : Measurement
    modes : ModalModel or RingModes   (the generator's modes: config ``model``)
    damping_ratio : (n_modes,) ndarray
    freq_hz : (n_freq,) ndarray        the records' DFT grid, Hz
    frf : (n_channels, n_points, n_freq) complex ndarray
        Analytic accelerance of each channel to a force at each point in the file
        (m/s²/N), including the anti-alias filter's effect on neither (it cancels).
    truth : dict                        what ``truth.json`` holds
    """

    measurement: Measurement
    modes: ModalModel | RingModes
    damping_ratio: np.ndarray
    freq_hz: np.ndarray
    frf: np.ndarray
    truth: dict


def half_sine_spectrum(freq_hz, width_s: float, amplitude: float = 1.0) -> np.ndarray:
    """Continuous-time Fourier transform of a half-sine pulse starting at t = 0.

    ``F(ω) = A π w (1 + e^{-iωw}) / (π² − ω² w²)`` (N·s), with its removable
    singularity at ωw = π replaced by the limit ``−i A w / 2``.
    """
    x = 2 * np.pi * np.asarray(freq_hz, dtype=float) * width_s
    num = amplitude * np.pi * width_s * (1 + np.exp(-1j * x))
    den = np.pi**2 - x**2
    near = np.abs(x - np.pi) < 1e-6
    safe = np.where(near, 1.0, den)
    return np.where(near, -0.5j * amplitude * width_s, num / safe)


def _anti_alias(freq_hz, fs):
    """Analog 8th-order Butterworth at 0.4 fs (what a front end puts before the ADC)."""
    z, p, k = scipy.signal.butter(8, 2 * np.pi * 0.4 * fs, analog=True, output="zpk")
    _, h = scipy.signal.freqs_zpk(z, p, k, worN=2 * np.pi * np.asarray(freq_hz))
    return h


def _clip(x, level_fraction=0.6):
    """Saturate at ``level_fraction`` of the peak, low enough that ≥ 3 samples hit the limit."""
    a = np.sort(np.abs(x))
    lim = min(level_fraction * a[-1], a[-3])
    return np.clip(x, -lim, lim)


def simulate(cfg: SimulationConfig, *, progress=None) -> Simulation:
    """Simulate a roving-hammer test.

    Parameters
    ----------
    cfg : SimulationConfig
    progress : callable(done, total), optional, keyword-only

    Returns
    -------
    Simulation
    """
    cfg.check()
    rng = np.random.default_rng(cfg.seed)
    fs, ns = cfg.sample_rate, cfg.n_samples
    freq = np.fft.rfftfreq(ns, 1 / fs)
    all_angles = 2 * np.pi * np.arange(cfg.n_points) / cfg.n_points
    keep = [i for i in range(cfg.n_points) if i != cfg.faults.missing_point]
    angles = all_angles[keep]
    locs = [c.location for c in cfg.channels]
    c_ang = np.array([c.angle_rad for c in cfg.channels])
    if cfg.model == "ring":
        modes, zeta, H, listed = _ring_source(cfg, freq, angles)
        p0 = cfg.ring.P0
    else:
        modes, zeta, H, listed = _paper_source(cfg, freq, angles)
        p0 = cfg.params.P0
    force, resp, hits = _acquire(cfg, H, freq, keep, rng, progress)
    names = [c.name for c in cfg.channels]
    meas = Measurement(
        force=force.astype(cfg.dtype), response=resp.astype(cfg.dtype), sample_rate=float(fs),
        point_angle=angles, channel_name=tuple(names), channel_location=tuple(locs),
        channel_angle=c_ang, inflation_pressure=p0,
        tire="simulated tyre (tiremodal simulate)" if cfg.model == "paper"
        else "simulated tyre (tiremodal simulate --model ring)",
        description=f"tiremodal {__version__} simulate, model {cfg.model}, seed {cfg.seed}")
    truth = _truth(cfg, listed, angles, keep, hits, modes)
    return Simulation(meas, modes, zeta, freq, H, truth)


def _paper_source(cfg, freq, angles):
    """Modes, damping, accelerances (n_ch, n_p, n_f) and truth list of the paper's model."""
    modes = solve_modes(cfg.params, n_max=cfg.n_max, effects=cfg.effects)
    zeta = np.array([cfg.damping if cfg.damping is not None else paper_damping(int(n), b)
                     for n, b in zip(modes.n, modes.branch)])
    locs = [c.location for c in cfg.channels]
    c_ang = np.array([c.angle_rad for c in cfg.channels])
    H = frf(modes, freq, zeta, locs, c_ang, angles, form="accelerance")
    listed = []
    for r in np.flatnonzero(modes.freq_hz < 0.5 * cfg.sample_rate):
        shape = {}
        for c in cfg.channels:
            obs = np.array([observation(modes.dofs, c.location, a) for a in angles])
            shape[c.name] = (obs @ modes.shapes[r]).tolist()
        listed.append({"frequency_hz": float(modes.freq_hz[r]), "damping_ratio": float(zeta[r]),
                       "n": int(modes.n[r]), "harmonic": modes.harmonic[r],
                       "branch": modes.branch[r], "shape_at_points": shape})
    return modes, zeta, H, listed


def _ring_source(cfg, freq, angles):
    """Modes, damping, accelerances and truth list of the finite-element ring.

    Modes are computed to 1.25 × the Nyquist frequency (the modal sum's truncation then
    leaves out only modes well above the band) on a mesh fine enough for every order of the
    tread below that frequency (:func:`tiremodal_cli.tyre.ring.elements_for`).
    """
    f_top = 1.25 * 0.5 * cfg.sample_rate
    rp = cfg.ring.replace(n_elements=max(cfg.ring.n_elements, elements_for(cfg.ring, f_top)))
    modes = ring_modes(rp, f_max_hz=f_top)
    if cfg.damping is not None:
        zeta = np.full(modes.freq_hz.size, cfg.damping)
    else:
        zeta = np.array([RING_DAMPING["cavity" if b == "cavity" else "structural"] for b in modes.branch])
    locs = [c.location for c in cfg.channels]
    c_ang = np.array([c.angle_rad for c in cfg.channels])
    H = ring_frf(modes, freq, zeta, locs, c_ang, angles, form="accelerance")
    below = np.flatnonzero(modes.freq_hz < 0.5 * cfg.sample_rate)
    at_points = {c.name: np.array([ring_observation(modes, c.location, a) for a in angles]) @ modes.shapes[below].T
                 for c in cfg.channels}  # (n_points, n_listed) per channel
    listed = []
    for k, r in enumerate(below):
        shape = {name: v[:, k].tolist() for name, v in at_points.items()}
        listed.append({"frequency_hz": float(modes.freq_hz[r]), "damping_ratio": float(zeta[r]),
                       "n": int(modes.n[r]), "harmonic": modes.harmonic[r], "branch": modes.branch[r],
                       "n_purity": float(modes.n_purity[r]),
                       "energy": dict(zip(("tread_radial", "tread_tangential", "sidewall", "rim", "cavity"),
                                          map(float, modes.energy[r]))),
                       "shape_at_points": shape})
    return modes, zeta, H, listed


def _acquire(cfg, H, freq, keep, rng, progress):
    """Hammer pulses, responses through the accelerances H (n_ch, n_p, n_f), anti-alias
    filter, noise and faults: the acquisition both generators share.

    Returns force (n_p, n_h, n_s), response (n_p, n_h, n_ch, n_s) and the hits' records.
    """
    fs, ns = cfg.sample_rate, cfg.n_samples
    aa = _anti_alias(freq, fs) if cfg.anti_alias else np.ones_like(freq)
    n_p, n_h, n_c = len(keep), cfg.n_hits, len(cfg.channels)
    force = np.zeros((n_p, n_h, ns))
    resp = np.zeros((n_p, n_h, n_c, ns))
    double = set(cfg.faults.double_hits)
    clipped = {}
    for p, h, c in cfg.faults.clipped:
        clipped.setdefault((p, h), []).append(c)
    hits = []
    dead = None if cfg.faults.dead_channel is None else [c.name for c in cfg.channels].index(cfg.faults.dead_channel)
    for ip, p in enumerate(keep):
        for h in range(n_h):
            width = cfg.pulse_width_s * (1 + cfg.pulse_width_jitter * rng.uniform(-1, 1))
            amp = cfg.amplitude_n * (1 + cfg.amplitude_jitter * rng.uniform(-1, 1))
            t0 = cfg.pretrigger_s + cfg.trigger_jitter_s * rng.uniform(-1, 1)
            spec = half_sine_spectrum(freq, width, amp) * np.exp(-2j * np.pi * freq * t0)
            hit = {"point": p, "hit": h, "width_s": width, "amplitude_n": amp, "t0_s": t0}
            if (p, h) in double:
                dt = rng.uniform(3e-3, 8e-3)
                a2 = rng.uniform(0.35, 0.7)
                spec = spec + a2 * half_sine_spectrum(freq, width, amp) * np.exp(-2j * np.pi * freq * (t0 + dt))
                hit["double_hit"] = {"delay_s": dt, "relative_amplitude": a2}
            spec = spec * aa * fs  # DFT of the samples of a band-limited signal
            force[ip, h] = np.fft.irfft(spec, n=ns)
            resp[ip, h] = np.fft.irfft(H[:, ip, :] * spec[None, :], n=ns)
            hits.append(hit)
            if progress is not None:
                progress(ip * n_h + h + 1, n_p * n_h)
    if cfg.noise > 0:
        # a sensor noise floor: std = noise × the channel's RMS over the whole test, so a
        # record at a node of the response holds noise, as a real one would
        f_rms = np.sqrt(np.mean(force**2))
        r_rms = np.sqrt(np.mean(resp**2, axis=(0, 1, 3), keepdims=True))
        force = force + cfg.noise * f_rms * rng.standard_normal(force.shape)
        resp = resp + cfg.noise * r_rms * rng.standard_normal(resp.shape)
    if dead is not None:
        level = 1e-6 * np.sqrt(np.mean(resp[:, :, dead] ** 2))
        resp[:, :, dead] = level * rng.standard_normal(resp[:, :, dead].shape)
    names = [c.name for c in cfg.channels]
    for (p, h), chans in clipped.items():
        ip = keep.index(p) if p in keep else None
        if ip is None:
            continue
        for c in chans:
            if c == "force":
                force[ip, h] = _clip(force[ip, h], 0.3)
            else:
                resp[ip, h, names.index(c)] = _clip(resp[ip, h, names.index(c)])
    return force, resp, hits


def _truth(cfg, listed, angles, keep, hits, modes) -> dict:
    faults = []
    for hit in hits:
        if "double_hit" in hit:
            faults.append({"kind": "double_hit", "point": hit["point"], "hit": hit["hit"]})
    for p, h, c in cfg.faults.clipped:
        faults.append({"kind": "clipped", "point": p, "hit": h, "channel": c})
    if cfg.faults.dead_channel is not None:
        faults.append({"kind": "dead_channel", "channel": cfg.faults.dead_channel})
    if cfg.faults.missing_point is not None:
        faults.append({"kind": "missing_point", "point": cfg.faults.missing_point})
    return {
        "format": "tiremodal.truth", "format_version": 1, "tiremodal_version": __version__,
        "config": cfg.to_dict(),
        **({"parameters": cfg.params.to_dict()} if cfg.model == "paper" else {"ring_parameters": modes.params.to_dict()}),
        "effects": {k: dict(v or {}) for k, v in cfg.effects.items()},
        "model": cfg.model,
        **({"ring_mesh_elements": int(modes.params.n_elements)} if cfg.model == "ring" else {}),
        "point_index_in_file": {str(p): i for i, p in enumerate(keep)},
        "point_angle_rad": [float(a) for a in angles],
        "modes": listed, "faults": faults, "hits": hits,
    }


#: The sample's test set-up (``sample_data/gl073a_sim.toml``) without its faults: 34 points,
#: 2 hits, 1 s records at 1,024 Hz, 0.5 % noise, a 2 ms pulse.
CAMPAIGN_CONFIG = SimulationConfig(params=TyreParameters(m_w=NOMINAL_RIM_KG), n_hits=2, sample_rate=1024.0,
                                   n_samples=1024, pulse_width_s=0.002, noise=0.005)


def simulate_campaign(folder, pressures_pa, *, repeats: int = 1, config: SimulationConfig = CAMPAIGN_CONFIG,
                      seed: int = 0) -> list:
    """Write a simulated campaign: one measurement file per pressure and repeat.

    The tyre is ``config``'s at each inflation pressure P0 (the model's pre-tension
    P0·b changes; nothing else does), each test with its own noise and hit jitter
    (seed ``seed`` + its index). Files are ``FOLDER/p<kPa>_r<repeat>.h5``.

    Returns the paths written.
    """
    from pathlib import Path

    from tiremodal_cli.io.measurement import write_measurement

    folder = Path(folder)
    out = []
    for i, (p0, r) in enumerate((p, r) for p in pressures_pa for r in range(repeats)):
        cfg = dataclasses.replace(config, params=dataclasses.replace(config.params, P0=float(p0)), seed=seed + i)
        path = folder / f"p{round(p0 / 1e3):04d}_r{r + 1}.h5"
        write_measurement(path, simulate(cfg).measurement, overwrite=True)
        out.append(path)
    return out
