"""The validation matrix: the tool measured on tests whose truth it did not write.

A *case* is one simulated roving-hammer test — from the paper's model (``paper``) or the
independent finite-element tyre (``ring``, :mod:`tiremodal_cli.tyre.ring`) — taken through
``run`` exactly as a user would, and scored against the generator's truth:

* **modes** — every truth mode a test could show (see
  :func:`~tiremodal_cli.workflow.validation_scoring.expected_groups`) is
  *found* when ``run``'s modal table has a mode within 0.3 % in frequency with the
  right order n and branch (for orders above the spatial Nyquist order N/2: flagged
  as aliased; for modes outside the tool's branches — cavity, tangential — any label),
  *mislabelled* when only the frequency matches, *missed* otherwise; a table mode with no
  truth mode of any kind within 0.3 % is *spurious*;
* **fit** — the base fit's RMS error (%) and the noise level of the test;
* **diagnosis** — what was adopted against what the case holds;
* the **run time** and, when ``run`` fails, its error.

How a case is scored — the ruler's rules — is :mod:`tiremodal_cli.workflow.validation_scoring`;
this module holds the matrix (its factors, levels and physics), each case's simulation,
and the taking of a case through ``run``.
"""

from __future__ import annotations

import dataclasses
import json
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tiremodal_cli.io.measurement import write_measurement
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.ring_parameters import RING_VARIANTS, RingParameters
from tiremodal_cli.tyre.simulate import Faults, SimulationConfig, simulate
from tiremodal_cli.workflow.pipeline import run as run_pipeline
from tiremodal_cli.workflow.run_options import RunOptions
from tiremodal_cli.workflow.validation_scoring import EXPECTED_DIAGNOSIS, TOLERANCE  # noqa: F401  (re-exported)
from tiremodal_cli.workflow.validation_scoring import (detectable, diagnosis_right, expected_groups, read_modes,
                                                       score_modes)

__all__ = ["Case", "FACTORS", "HELD_OUT_LEVELS", "REFERENCE", "PHYSICS", "PAIRS", "EXPECTED_DIAGNOSIS", "Tyre", "TYRES",
           "matrix", "held_out_levels", "config_for", "nominal_params", "expected_groups", "score_modes", "run_case",
           "TOLERANCE"]

#: Levels of every factor (the reference's level first).
FACTORS = {
    "sample_rate": (2048.0, 1024.0, 2560.0, 5120.0),
    "n_points": (34, 24, 40, 48),
    "n_hits": (3, 1, 5),
    "noise": (0.005, 0.02, 0.05),
    "form": ("accelerance", "receptance", "mobility"),
    "faults": ("none", "bounced+overload"),
}

#: Levels no rule was ever measured on (none is a level of :data:`FACTORS`; the record
#: length, fixed at :data:`RECORD_S` in the matrix, varies too: other line spacings).
HELD_OUT_LEVELS = {
    "sample_rate": (1600.0, 3200.0, 4096.0),
    "n_points": (20, 30, 36, 60),
    "n_hits": (2, 4),
    "noise": (0.01, 0.03),
    "form": ("accelerance", "receptance", "mobility"),
    "faults": ("none", "bounced+overload"),
    "record_s": (1.0, 4.0),
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

@dataclass(frozen=True)
class Tyre:
    """A tyre the matrix can be run on.

    Attributes
    ----------
    params : the paper model's parameters (SI): the ``paper`` generator's truth, and for
        what a user knows of a tyre (R, b, P0, rhoA, m_s) the nominal values ``run`` is given
    ring : the finite-element ring's parameters (SI): the ``ring`` generator's truth
    ring_variants : {physics name: ring parameter overrides}, the keys of ``RING_VARIANTS``
    effects : {paper effect name: its parameter values} ({} or a missing name: the effect's
        defaults, which are GL073A's)
    rim_mass_kg : kg, the free rim of the paper generator's physics ``rim``
    """

    params: TyreParameters
    ring: RingParameters
    ring_variants: dict
    effects: dict
    rim_mass_kg: float


#: The tyres: ``gl073a``, the paper's 16.00R20 truck tyre, on which every rule of the modal
#: stage was measured; ``car``, a 205/55 R16 passenger-car tyre at 2.2 bar that no rule was
#: measured on (held out: other dimensions, 8 × less tread mass, 17 × less hoop tension, its
#: sidewall resonance and branch crowd at 303 Hz rather than 168 Hz). The car's values are
#: plausible magnitudes for that size (docs/validation.md, "Another tyre"), not a measured
#: tyre; each variant keeps the truck variant's proportion to its tyre (e.g. the sidewall
#: tension about 11 % of the hoop tension; a 50 g sensor, 1 % of the tread's mass).
TYRES: dict[str, Tyre] = {
    "gl073a": Tyre(TyreParameters(), RingParameters(), RING_VARIANTS, {}, 60.0),
    "car": Tyre(
        TyreParameters(R=0.30, b=0.16, P0=2.2e5, rhoA=2.39, m_s=1.38, EI=5.0, k_r1=3.0e6, k_r2=2.0e6),
        RingParameters(R=0.30, b=0.16, P0=2.2e5, rhoA=2.39, m_s=1.38, EI=5.0, k_r1=3.0e6, k_r2=2.0e6,
                       rim_radius=0.203, cavity_radius=0.25, cavity_area=0.0155, rho_air=3.8),
        {"none": {},
         "tangential": {"tangential": True, "EA": 3.0e7, "k_t1": 1.0e6, "k_t2": 0.7e6},
         "extensible": {"tangential": True, "EA": 1.5e6, "k_t1": 1.0e6, "k_t2": 0.7e6},
         "sidewall_shear": {"tangential": True, "EA": 3.0e7, "k_t1": 1.0e6, "k_t2": 0.7e6,
                            "sidewall_tangential": True},
         "timoshenko": {"kGA": 2.0e5, "rhoI": 2.39 * 0.012**2 / 12},
         "sidewall_coupling": {"sidewall_T": 1.2e3},
         "rim": {"rim_mass": 10.0, "fixture_k": 1.0e6},
         "cavity": {"cavity": True},
         "mass": {"masses": ((45.0, 0.05),)}},
        {"sidewall_membrane": {"T_s": 1.0e3}, "air_cavity": {"f_cavity_hz": 218.0},
         "added_mass": {"m_a": 0.05}, "tangential": {"k_t": 1.0e6},
         "timoshenko": {"rhoI": 6.0e-4, "c_s": 5.0e-6}},
        10.0),
}

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
    record_s: float = RECORD_S
    seed: int = 0
    label: str = "reference"
    tyre: str = "gl073a"  # a TYRES name

    @property
    def name(self) -> str:
        return f"{self.generator}:{self.label}" if self.tyre == "gl073a" else f"{self.generator}[{self.tyre}]:{self.label}"

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


REFERENCE = {k: v[0] for k, v in FACTORS.items()} | {"physics": "none"}


def matrix(*, combinations: int = 4, seed: int = 2026, generators=("ring", "paper"), tyre: str = "gl073a") -> list[Case]:
    """Every level of every factor, one factor at a time around the reference, for both
    generators; the pairs of effects of :data:`PAIRS`; and ``combinations`` seeded random
    combinations per generator (each with one or two physical effects); all on ``tyre``
    (a :data:`TYRES` name; the same seeds and levels whatever the tyre)."""
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
                                n_hits=int(c.n_hits), noise=float(c.noise), tyre=_tyre(tyre)) for c in out]


def _tyre(name: str) -> str:
    if name not in TYRES:
        raise ValueError(f"tyre {name!r}; allowed: {', '.join(TYRES)}")
    return name


def held_out_levels(count: int, *, seed: int = 5000, generators=("ring", "paper"), tyre: str = "gl073a") -> list[Case]:
    """``count`` seeded random tests per generator at the levels of :data:`HELD_OUT_LEVELS`,
    each with one or two physical effects (or none, one case in three): set-ups no rule was
    measured on, for ``benchmarks/validation.py --held-out-levels``; on ``tyre`` (the same
    draw whatever the tyre)."""
    rng = np.random.default_rng(seed)
    out = []
    for g in generators:
        for k in range(count):
            lv = {f: levels[rng.integers(len(levels))] for f, levels in HELD_OUT_LEVELS.items()}
            phys = list(PHYSICS[g][1:])
            n_eff = k % 3
            pick = sorted(rng.choice(len(phys), size=n_eff, replace=False)) if n_eff else []
            ph = _compatible(g, "+".join(phys[i] for i in pick)) if pick else "none"
            label = "held-out: " + ", ".join(f"{f}={v}" for f, v in lv.items()) + f", physics={ph}"
            out.append(Case(generator=g, **(lv | {"physics": ph}), seed=seed + len(out), label=label))
    return [dataclasses.replace(c, sample_rate=float(c.sample_rate), n_points=int(c.n_points), n_hits=int(c.n_hits),
                                noise=float(c.noise), record_s=float(c.record_s), tyre=_tyre(tyre)) for c in out]


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
    ns = int(round(case.record_s * case.sample_rate))
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
    tyre = TYRES[case.tyre]
    if case.generator == "ring":
        values = {}
        for p in parts:
            values.update(tyre.ring_variants[p])
        return SimulationConfig(model="ring", ring=tyre.ring.replace(**values), **common)
    params = tyre.params.replace(m_w=tyre.rim_mass_kg) if "rim" in parts else tyre.params
    effects = {p: dict(tyre.effects.get(p, {})) for p in parts if p != "rim"}
    return SimulationConfig(params=params, effects=effects, **common)


def nominal_params(case: Case) -> TyreParameters:
    """The parameters a user gives ``run`` for the case's tyre: what one knows of a tyre
    before a test — its dimensions R and b, pressure P0 (``run`` takes the measurement's),
    tread and sidewall masses per length — with the stiffnesses (k_r1, k_r2, EI, which the
    fit identifies) at the paper's GL073A values, a start the global search leaves. On
    GL073A these are ``TyreParameters()``, what ``run`` takes when given none."""
    t = TYRES[case.tyre].params
    return TyreParameters().replace(R=t.R, b=t.b, P0=t.P0, rhoA=t.rhoA, m_s=t.m_s)


def _detectable_parts(case: Case, params: TyreParameters) -> dict:
    """Each effect of a case with two, judged alone (:func:`detectable` on the same test
    set-up with that effect only): an effect that this test cannot show alone is not
    required of the diagnosis beside the other (its names stay allowed). {} for one effect."""
    parts = [p for p in case.physics.split("+") if p != "none"]
    if len(parts) < 2:
        return {}
    out = {}
    for p in parts:
        one = dataclasses.replace(case, physics=p)
        cfg = config_for(one)
        out[p] = bool(detectable(one, expected_groups(simulate(cfg), cfg), params)["detectable"])
    return out


def run_case(case: Case, workdir) -> dict:
    """Simulate a case, take it through ``run`` and score it (the module docstring).

    Returns one flat record (JSON-able); a failure of ``run`` is recorded with its error
    (type and message), never raised.
    """
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
        summary = run_pipeline(meas, workdir / "run", RunOptions(form=case.form), params=nominal_params(case))
    except Exception as exc:  # the scorecard records any failure of run, traceback included
        rec.update(status="error", error=f"{type(exc).__name__}: {exc}",
                   traceback=traceback.format_exc(limit=3), run_s=round(time.perf_counter() - t1, 2))
        rec.update({k: v for k, v in score_modes(groups, [], sim.truth["modes"]).items() if k != "detail"})
        return rec
    rec["run_s"] = round(time.perf_counter() - t1, 2)
    rows = read_modes(workdir / "run" / "modes.csv")
    sc = score_modes(groups, rows, sim.truth["modes"])
    diag = json.loads((workdir / "run" / "diagnosis.json").read_text(encoding="utf-8"))
    # an effect adopted and a parameter found off, each once (a parameter can be both)
    adopted = list(dict.fromkeys(list(diag.get("adopted_effects", [])) + list(diag.get("parameter_off", []))))
    man = json.loads((workdir / "run" / "run.json").read_text(encoding="utf-8"))
    params = TyreParameters.from_mapping(man["params"]).replace(P0=man["model_P0"], m_w=man["model_m_w"])
    det = detectable(case, groups, params)
    det_parts = _detectable_parts(case, params) if det["detectable"] else {}
    rec.update(status="ok", **sc, base_rms_pct=float(diag["base"]["rms_error_pct"]),
               final_rms_pct=float(diag["augmented"]["rms_error_pct"]), adopted_effects=adopted,
               detectable=det["detectable"], truth_base_rms_pct=det["rms_pct"],
               set_aside=len(diag.get("set_aside_before", [])),
               detectable_parts=det_parts,
               diagnosis_right=diagnosis_right(case.physics, adopted, det_parts or det["detectable"]),
               orders_mix=bool(summary.get("orders_mix")),
               verdict=diag.get("verdict", ""))
    return rec
