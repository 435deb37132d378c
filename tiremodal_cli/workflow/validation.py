"""The validation matrix: the tool measured on tests whose truth it did not write.

A *case* is one simulated roving-hammer test — from the paper's model (``paper``) or the
independent finite-element tyre (``ring``, :mod:`tiremodal_cli.tyre.ring`) — taken through
``run`` exactly as a user would, and scored against the generator's truth:

* **modes** — every truth mode a test could show (see :func:`expected_groups`) is
  *found* when ``run``'s modal table has a mode within 0.3 % in frequency with the
  right order n and branch (for orders above the spatial Nyquist order N/2: flagged
  as aliased; for modes outside the tool's branches — cavity, tangential — any label),
  *mislabelled* when only the frequency matches, *missed* otherwise; a table mode with no
  truth mode of any kind within 0.3 % is *spurious*;
* **fit** — the base fit's RMS error (%) and the noise level of the test;
* **diagnosis** — what was adopted against what the case holds;
* the **run time** and, when ``run`` fails, its error.

The rules that decide what a test *could* show are the ruler's, stated here and in
docs/validation.md, and use only the generator's truth and the test's set-up:

* the front end's usable band: the mode's half-power band, up to f (1 + ζ), below
  fs / 2.56 (the usual analyser bandwidth under the anti-alias filter) and where the
  hammer's force spectrum is within 20 dB of its low-frequency level — a mode with one
  flank cut off by the band's top is fitted to that flank alone, its frequency biased
  (the estimator rejects such a pole: :func:`tiremodal_cli.modal.modes._off_edges`);
* visibility: the mode's peak accelerance at its best channel and point, |φ_o φ_i| / 2ζ,
  at least 3 × the H1 noise floor there (sensor noise of std ``noise`` × the channel's
  RMS, white, over the hits' averaged force spectrum);
* not in an unresolvable crowd: no other truth mode of the same branch whose order is an
  alias of this one with N points (n' ≡ ±n mod N) within one half-power bandwidth 2ζf
  (different orders are told apart by the circumferential decomposition, aliases are not);
* a degenerate cos/sin pair (or a pair split by less than ζ f) is one mode.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.ring_parameters import RING_VARIANTS, RingParameters
from tiremodal_cli.tyre.simulate import Faults, SimulationConfig, half_sine_spectrum, simulate

__all__ = ["Case", "FACTORS", "REFERENCE", "PHYSICS", "PAIRS", "EXPECTED_DIAGNOSIS", "matrix", "config_for",
           "expected_groups", "score_modes", "run_case", "TOLERANCE"]

#: Frequency tolerance of a match (relative).
TOLERANCE = 0.003

#: Levels of every factor (the reference's level first).
FACTORS = {
    "sample_rate": (2048.0, 1024.0, 2560.0, 5120.0),
    "n_points": (34, 24, 40, 48),
    "n_hits": (3, 1, 5),
    "noise": (0.005, 0.02, 0.05),
    "form": ("accelerance", "receptance", "mobility"),
    "faults": ("none", "bounced+overload"),
}

#: Physical variants of each generator ("none": the paper's model itself / its limit).
PHYSICS = {
    "paper": ("none", "tangential", "timoshenko", "sidewall_membrane", "air_cavity", "added_mass",
              "viscoelastic", "rim"),
    "ring": tuple(RING_VARIANTS),
}

#: Two effects at once, at the reference set-up: can the diagnosis tell them apart?
PAIRS = {
    "paper": ("sidewall_membrane+air_cavity", "tangential+added_mass"),
    "ring": ("tangential+cavity", "sidewall_coupling+mass"),
}

#: What a right diagnosis adopts for each variant: (required, allowed). ``required``: the
#: names (effects of the candidate library, or a parameter found off its nominal value) any
#: one of which must be adopted; ``allowed``: names that may be adopted besides, because the
#: variant holds that physics too. The three tangential variants of the ring are a belt
#: that moves tangentially *and* stretches (finite EA): its n = 0 mode is held by the hoop
#: stiffness (``extensible_belt``) and its n ≥ 1 modes feel the tangential coupling
#: (``tangential``); the variants differ in how much of each shows. The ring's sidewall
#: shear is the tangential sidewall stiffness k_t of the ``tangential`` effect. The ring's
#: cavity air also stiffens the breathing mode (its uniform pressure, ρc²b²/A per length):
#: on n = 0 that is the same stiffness as a belt's EA/R², which frequencies cannot tell apart.
EXPECTED_DIAGNOSIS = {
    "none": ((), ()),
    "tangential": (("tangential",), ("extensible_belt",)),
    "extensible": (("extensible_belt",), ("tangential",)),
    "sidewall_shear": (("tangential",), ("extensible_belt",)),
    "timoshenko": (("timoshenko",), ()),
    "sidewall_coupling": (("sidewall_membrane",), ()),
    "sidewall_membrane": (("sidewall_membrane",), ()),
    "rim": (("m_w", "rim_fixture"), ("m_w", "rim_fixture")),
    "cavity": (("air_cavity",), ("extensible_belt",)),
    "air_cavity": (("air_cavity",), ()),
    "mass": (("added_mass",), ()),
    "added_mass": (("added_mass",), ()),
    "viscoelastic": (("viscoelastic",), ()),
}

#: Level of the test that decides whether an effect is detectable at all (the diagnosis's).
DETECT_ALPHA = 0.01

#: Record length of every case, s (frequency resolution 0.5 Hz: a tenth of the narrowest
#: half-power bandwidth, 2ζf = 2 × 0.02 × 55 Hz ≈ 2 Hz, is resolved five times over).
RECORD_S = 2.0


@dataclass(frozen=True)
class Case:
    """One test of the matrix."""

    generator: str = "ring"
    sample_rate: float = 2048.0
    n_points: int = 34
    n_hits: int = 3
    noise: float = 0.005
    form: str = "accelerance"
    faults: str = "none"
    physics: str = "none"  # a PHYSICS name, or two joined by "+"
    seed: int = 0
    label: str = "reference"

    @property
    def name(self) -> str:
        return f"{self.generator}:{self.label}"

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


REFERENCE = {k: v[0] for k, v in FACTORS.items()} | {"physics": "none"}


def matrix(*, combinations: int = 4, seed: int = 2026, generators=("ring", "paper")) -> list[Case]:
    """Every level of every factor, one factor at a time around the reference, for both
    generators; the pairs of effects of :data:`PAIRS`; and ``combinations`` seeded random
    combinations per generator (each with one or two physical effects)."""
    rng = np.random.default_rng(seed)
    out = []
    for g in generators:
        out.append(Case(generator=g, **REFERENCE, seed=len(out), label="reference"))
        for factor, levels in FACTORS.items():
            for lv in levels[1:]:
                out.append(Case(generator=g, **(REFERENCE | {factor: lv}), seed=len(out), label=f"{factor}={lv}"))
        for ph in PHYSICS[g][1:]:
            out.append(Case(generator=g, **(REFERENCE | {"physics": ph}), seed=len(out), label=f"physics={ph}"))
        for ph in PAIRS[g]:
            out.append(Case(generator=g, **(REFERENCE | {"physics": ph}), seed=len(out), label=f"physics={ph}"))
        for k in range(combinations):
            lv = {f: levels[rng.integers(len(levels))] for f, levels in FACTORS.items()}
            phys = list(PHYSICS[g][1:])
            n_eff = 1 + k % 2
            pick = sorted(rng.choice(len(phys), size=n_eff, replace=False))
            ph = _compatible(g, "+".join(phys[i] for i in pick))
            label = "combo: " + ", ".join(f"{f}={v}" for f, v in lv.items() if v != REFERENCE[f]) + f", physics={ph}"
            out.append(Case(generator=g, **(lv | {"physics": ph}), seed=len(out), label=label))
    return [dataclasses.replace(c, sample_rate=float(c.sample_rate), n_points=int(c.n_points),
                                n_hits=int(c.n_hits), noise=float(c.noise)) for c in out]


def _compatible(generator: str, physics: str) -> str:
    """Two ring variants that set the same parameters (the three tangential ones) cannot
    be combined; keep the first."""
    parts = physics.split("+")
    if generator == "ring" and len(parts) == 2 and set(RING_VARIANTS[parts[0]]) & set(RING_VARIANTS[parts[1]]):
        return parts[0]
    return physics


def config_for(case: Case) -> SimulationConfig:
    """The simulation of a case: the reference tyre of its generator with its physics, the
    test set-up of its factors, a clamped rim unless the physics is ``rim``."""
    ns = int(round(RECORD_S * case.sample_rate))
    faults = Faults()
    if case.faults != "none":
        rng = np.random.default_rng(10_000 + case.seed)
        hits = [(p, h) for p in range(case.n_points) for h in range(case.n_hits)]
        pick = rng.choice(len(hits), size=max(1, len(hits) // 5), replace=False)
        bounced = tuple(hits[i] for i in sorted(pick))
        rest = [hits[i] for i in range(len(hits)) if i not in set(pick)]
        over = rest[int(rng.integers(len(rest)))]
        faults = Faults(double_hits=bounced, clipped=((over[0], over[1], "tread"),))
    common = dict(n_points=case.n_points, n_hits=case.n_hits, sample_rate=case.sample_rate, n_samples=ns,
                  noise=case.noise, faults=faults, seed=case.seed, n_max=60)
    parts = [p for p in case.physics.split("+") if p != "none"]
    if case.generator == "ring":
        values = {}
        for p in parts:
            values.update(RING_VARIANTS[p])
        return SimulationConfig(model="ring", ring=RingParameters().replace(**values), **common)
    params = TyreParameters(m_w=60.0) if "rim" in parts else TyreParameters()
    effects = {p: {} for p in parts if p != "rim"}
    return SimulationConfig(params=params, effects=effects, **common)


# ----------------------------------------------------------------------------- scoring

def _alias(n: int, n_points: int) -> int:
    r = n % n_points
    return min(r, n_points - r)


def _h_noise_floor(cfg: SimulationConfig, sim, freq_hz: float, channel: int) -> float:
    """Std of the H1 estimate's error at ``freq_hz`` on ``channel`` (m/s²/N): white sensor
    noise of std noise × the channel's RMS over the test, on the DFT of the record, over the
    nominal hammer pulse's spectrum, averaged over the hits."""
    if cfg.noise == 0:
        return 0.0
    resp = np.asarray(sim.measurement.response[:, :, channel, :], dtype=float)
    rms = np.sqrt(np.mean(resp**2))
    f_spec = abs(half_sine_spectrum([freq_hz], cfg.pulse_width_s, cfg.amplitude_n)[0]) * cfg.sample_rate
    return float(cfg.noise * rms * np.sqrt(cfg.n_samples) / (f_spec * np.sqrt(cfg.n_hits)))


def expected_groups(sim, cfg: SimulationConfig) -> list[dict]:
    """The truth modes grouped (a degenerate pair is one mode), each with what a test could
    show of it: ``valid`` (in the usable band), ``visible``, ``crowd``, ``aliased``
    (n > N/2), ``foreign`` (a branch outside the tool's labels) and ``expected``
    (valid, visible and not in a crowd)."""
    truth = sim.truth
    n_pts = len(truth["point_angle_rad"])
    fs = cfg.sample_rate
    f_pulse = np.linspace(0, 0.5 * fs, 2049)
    spec = abs(half_sine_spectrum(f_pulse, cfg.pulse_width_s))
    below = np.flatnonzero(spec < 0.1 * spec[0])
    f_force = f_pulse[below[0]] if below.size else 0.5 * fs
    f_valid = min(fs / 2.56, f_force)
    names = [c.name for c in cfg.channels]
    tread = next(c.name for c in cfg.channels if c.location == "tread")
    modes = sorted(truth["modes"], key=lambda m: (m["branch"], m["n"], m["frequency_hz"]))
    groups = []
    for m in modes:
        g = groups[-1] if groups else None
        if (g is not None and g["branch"] == m["branch"] and g["n"] == m["n"]
                and m["frequency_hz"] - g["members"][-1] <= m["damping_ratio"] * m["frequency_hz"]):
            g["members"].append(m["frequency_hz"])
            g["shapes"].append(m["shape_at_points"])
            continue
        groups.append({"n": m["n"], "branch": m["branch"], "zeta": m["damping_ratio"],
                       "members": [m["frequency_hz"]], "shapes": [m["shape_at_points"]]})
    out = []
    for g in groups:
        f = float(np.mean(g["members"]))
        best = 0.0
        for sh in g["shapes"]:
            phi_in = np.asarray(sh[tread])
            for ic, c in enumerate(names):
                peak = np.max(np.abs(sh[c][0] * phi_in)) / (2 * g["zeta"])
                floor = _h_noise_floor(cfg, sim, f, ic)
                best = max(best, peak / floor if floor > 0 else (np.inf if peak > 0 else 0.0))
        out.append({"frequency_hz": f, "members": list(g["members"]), "n": g["n"], "branch": g["branch"],
                    "zeta": g["zeta"],
                    "snr": float(best), "valid": bool(f * (1 + g["zeta"]) <= f_valid), "visible": bool(best >= 3.0),
                    "aliased": bool(g["n"] > n_pts / 2),
                    "foreign": g["branch"] not in ("same", "opposite", "rim")})
    for g in out:
        bw = 2 * g["zeta"] * g["frequency_hz"]
        g["crowd"] = any(h is not g and h["branch"] == g["branch"] and _alias(h["n"], n_pts) == _alias(g["n"], n_pts)
                         and abs(h["frequency_hz"] - g["frequency_hz"]) < bw for h in out)
        g["expected"] = g["valid"] and g["visible"] and not g["crowd"]
    return out


def _read_modes(path) -> list[dict]:
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    out = []
    for r in rows:
        n = r.get("n", "")
        out.append({"frequency_hz": float(r["frequency_hz"]), "damping_ratio": float(r["damping_ratio"]),
                    "n": int(n) if n not in ("", None) else None, "branch": r.get("branch") or None,
                    "aliased": str(r.get("n_aliased", "")).lower() == "true"})
    return out


def score_modes(groups: list[dict], rows: list[dict], truth_modes: list[dict]) -> dict:
    """Found / mislabelled / missed / spurious (module docstring) and the errors of the
    found modes' frequencies and damping ratios (relative)."""
    found = mis = missed = 0
    f_err, z_err, detail, bw_err = [], [], [], []
    for g in (g for g in groups if g["expected"]):
        cand = [r for r in rows if abs(r["frequency_hz"] / g["frequency_hz"] - 1) <= TOLERANCE]
        if g["foreign"]:
            ok = [r for r in cand]
        elif g["aliased"]:
            ok = [r for r in cand if r["aliased"]]
        else:
            ok = [r for r in cand if r["n"] == g["n"] and r["branch"] == g["branch"] and not r["aliased"]]
        if ok:
            found += 1
            r = min(ok, key=lambda r: abs(r["frequency_hz"] - g["frequency_hz"]))
            f_err.append(abs(r["frequency_hz"] / g["frequency_hz"] - 1))
            z_err.append(abs(r["damping_ratio"] / g["zeta"] - 1))
            bw_err.append(abs(r["frequency_hz"] - g["frequency_hz"]) / (2 * g["zeta"] * g["frequency_hz"]))
            status = "found"
        elif cand:
            mis += 1
            r = cand[0]
            status = f"mislabelled as n={r['n']} {r['branch']}"
        else:
            missed += 1
            status = "missed"
        detail.append({"frequency_hz": round(g["frequency_hz"], 3), "n": g["n"], "branch": g["branch"],
                       "status": status})
    tf = np.array([m["frequency_hz"] for m in truth_modes]) if truth_modes else np.zeros(0)
    spurious = [r for r in rows if not np.any(np.abs(tf / r["frequency_hz"] - 1) <= TOLERANCE)]
    return {"expected": found + mis + missed, "found": found, "mislabelled": mis, "missed": missed,
            "spurious": len(spurious), "adopted": len(rows), "surplus": _surplus(groups, rows),
            "freq_err_bw": [float(x) for x in bw_err],
            "spurious_hz": [round(r["frequency_hz"], 2) for r in spurious],
            "freq_err_median_pct": 100 * float(np.median(f_err)) if f_err else None,
            "damping_err_median_pct": 100 * float(np.median(z_err)) if z_err else None,
            "n_aliased_groups": sum(1 for g in groups if g["expected"] and g["aliased"]),
            "n_crowd_groups": sum(1 for g in groups if g["valid"] and g["crowd"]),
            "detail": detail}


def _surplus(groups: list[dict], rows: list[dict]) -> int:
    """Table modes beyond one per truth mode: rows within 0.3 % of some truth mode (so not
    spurious) that a one-to-one matching of rows to truth groups (a degenerate pair is one)
    leaves over — one mode reported twice (a pole seen in two order groups and not merged)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import maximum_bipartite_matching

    if not rows or not groups:
        return 0
    fr = np.array([r["frequency_hz"] for r in rows])
    fg = np.array([g["frequency_hz"] for g in groups])
    near = np.abs(fr[:, None] / fg[None, :] - 1) <= TOLERANCE
    matched = maximum_bipartite_matching(csr_matrix(near.astype(np.int8)), perm_type="column")
    return int(np.sum(near.any(axis=1) & (matched < 0)))


def _diagnosis_right(physics: str, adopted: list[str], detectable: bool = True) -> bool:
    """Right when every part of ``physics`` has one of its required names adopted and
    nothing else is adopted but their allowed names; an effect the base model absorbs within
    the noise (:func:`detectable`): that, or nothing."""
    parts = [p for p in physics.split("+") if p != "none"]
    if not parts:
        return not adopted
    if not detectable and not adopted:  # at the edge of detectability: nothing, or the right effect
        return True
    spec = [EXPECTED_DIAGNOSIS.get(p, ((p,), ())) for p in parts]
    ok = set().union(*(set(r) | set(a) for r, a in spec))
    if any(a not in ok for a in adopted):
        return False
    return all(any(a in r for a in adopted) for r, _ in spec)


def detectable(case: "Case", groups, params: TyreParameters) -> dict:
    """Can the paper's model tell this case's physics from noise, given perfect modes?

    The base model (k_r1, k_r2, EI free, rim as in ``run``) is fitted robustly to the
    case's expected same/opposite truth modes (split pairs as their two members), each with
    the diagnosis's 0.1 % frequency uncertainty: the physics is *detectable* when that fit's
    residual exceeds the noise (χ² p < 0.01 or a mode set aside). An effect the base model
    absorbs within the noise is not missing physics for it, and a right diagnosis adopts
    nothing. Returns {"detectable", "rms_pct", "p_value", "set_aside"}."""
    if case.physics == "none":
        return {"detectable": False, "rms_pct": 0.0, "p_value": 1.0, "set_aside": 0}
    from tiremodal_cli.diagnose.loop import DiagnoseOptions, base_fit, residual_analysis
    from tiremodal_cli.tyre.measured import MeasuredMode
    from tiremodal_cli.tyre.robust import with_sigma

    modes = []
    for g in groups:
        if not (g["expected"] and g["branch"] in ("same", "opposite") and not g["aliased"]):
            continue
        mem = sorted(g["members"])
        if len(mem) >= 2 and mem[-1] - mem[0] > 1e-6 * mem[0]:
            modes += [MeasuredMode(g["n"], g["branch"], mem[0], member="lower"),
                      MeasuredMode(g["n"], g["branch"], mem[-1], member="upper")]
        else:
            modes.append(MeasuredMode(g["n"], g["branch"], float(np.mean(mem))))
    opt = DiagnoseOptions(alpha=DETECT_ALPHA)
    rf = base_fit(with_sigma(modes, opt.noise_floor_pct), params, opt)
    res = residual_analysis(rf, opt)
    return {"detectable": bool(res["exceeds_noise"]), "rms_pct": rf.fit.rms_error_pct, "p_value": res["p_value"],
            "set_aside": len(rf.set_aside)}


def run_case(case: Case, workdir) -> dict:
    """Simulate a case, take it through ``run`` and score it (the module docstring).

    Returns one flat record (JSON-able); a failure of ``run`` is recorded with its error
    (type and message), never raised.
    """
    from tiremodal_cli.io.measurement import write_measurement
    from tiremodal_cli.workflow.run_options import RunOptions
    from tiremodal_cli.workflow.pipeline import run as run_pipeline

    workdir = Path(workdir)
    workdir.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    cfg = config_for(case)
    sim = simulate(cfg)
    t_sim = time.perf_counter() - t0
    meas = workdir / "test.h5"
    write_measurement(meas, sim.measurement, overwrite=True)
    groups = expected_groups(sim, cfg)
    rec = {"case": case.to_dict(), "name": case.name, "simulate_s": round(t_sim, 2)}
    t1 = time.perf_counter()
    try:
        summary = run_pipeline(meas, workdir / "run", RunOptions(form=case.form))
    except Exception as exc:  # the scorecard records any failure of run, traceback included
        rec.update(status="error", error=f"{type(exc).__name__}: {exc}",
                   traceback=traceback.format_exc(limit=3), run_s=round(time.perf_counter() - t1, 2))
        rec.update({k: v for k, v in score_modes(groups, [], sim.truth["modes"]).items() if k != "detail"})
        return rec
    rec["run_s"] = round(time.perf_counter() - t1, 2)
    rows = _read_modes(workdir / "run" / "modes.csv")
    sc = score_modes(groups, rows, sim.truth["modes"])
    diag = json.loads((workdir / "run" / "diagnosis.json").read_text(encoding="utf-8"))
    # an effect adopted and a parameter found off, each once (a parameter can be both)
    adopted = list(dict.fromkeys(list(diag.get("adopted_effects", [])) + list(diag.get("parameter_off", []))))
    man = json.loads((workdir / "run" / "run.json").read_text(encoding="utf-8"))
    det = detectable(case, groups, TyreParameters.from_mapping(man["params"]).replace(
        P0=man["model_P0"], m_w=man["model_m_w"]))
    rec.update(status="ok", **sc, base_rms_pct=float(diag["base"]["rms_error_pct"]),
               final_rms_pct=float(diag["augmented"]["rms_error_pct"]), adopted_effects=adopted,
               detectable=det["detectable"], truth_base_rms_pct=det["rms_pct"],
               set_aside=len(diag.get("set_aside_before", [])),
               diagnosis_right=_diagnosis_right(case.physics, adopted, det["detectable"]),
               verdict=diag.get("verdict", ""))
    return rec
