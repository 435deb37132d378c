"""The finite-element reference tyre's parameters (SI), and the variants the validation
matrix uses (each a physics the paper's model lacks, or has).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from tiremodal_cli.errors import ParameterError

__all__ = ['FIELDS', 'RingParameters', 'RING_VARIANTS']


#: Fields at each node, in this order (those switched off are removed).
FIELDS = ("w", "v", "psi", "us", "vs", "xi")


@dataclass(frozen=True)
class RingParameters:
    """Parameters of the finite-element tyre (SI; per unit tread arc length where marked).

    The defaults are the paper's GL073A tyre in the limit of the paper's model: no
    tangential freedom, no membrane stiffness, Euler–Bernoulli tread, radial sidewall
    springs only, clamped rim, no cavity. ``RING_VARIANTS`` switches on one physical
    effect at a time.

    Attributes
    ----------
    R : m                      tread radius
    b : m                      tread width (tension T = P0 b R; cavity wall width)
    P0 : Pa                    inflation pressure
    rhoA : kg/m                tread mass per length
    EI : N·m²                  tread bending stiffness
    EA : N                     tread membrane (hoop) stiffness; 0 = none
    kGA : N or None            tread shear stiffness; None = Euler–Bernoulli
    rhoI : kg·m                tread rotary inertia per length; 0 = none
    tangential : bool          the tread (and sidewall) move tangentially
    m_s : kg/m                 sidewall mass per length
    k_r1, k_r2 : N/m²          radial stiffness tread–sidewall, sidewall–rim, per length
    k_t1, k_t2 : N/m²          tangential (shear) stiffness tread–sidewall, sidewall–rim
    sidewall_tangential : bool the sidewall's mass also moves tangentially (its own
                               freedom); otherwise k_t1 and k_t2 act in series between
                               tread and rim
    sidewall_T : N             tension of the sidewall on its radial slope (coupling)
    sidewall_EA : N            circumferential stretch stiffness of the sidewall
    rim_mass : kg or None      rim (+ fixture) mass; None = clamped rim
    rim_inertia : kg·m²        rim polar inertia (None: a thin ring at rim_radius)
    rim_radius : m             bead (rim attachment) radius
    fixture_k : N/m            translational spring of the rim to the ground
    fixture_k_rot : N·m/rad    rotational spring of the rim to the ground
    cavity : bool              include the air cavity
    c_air : m/s                speed of sound in the cavity air
    rho_air : kg/m³            density of the cavity air (at the inflation pressure)
    cavity_radius : m          mean radius of the cavity annulus
    cavity_area : m²           cross-section of the cavity annulus
    masses : tuple of (angle_deg, kg)   lumped masses on the tread (radial and tangential)
    n_elements : int           quadratic elements around the circumference
    """

    R: float = 0.65
    b: float = 0.35
    P0: float = 8.0e5
    rhoA: float = 19.64
    EI: float = 25.697
    EA: float = 0.0
    kGA: float | None = None
    rhoI: float = 0.0
    tangential: bool = False
    m_s: float = 10.0
    k_r1: float = 6.686e6
    k_r2: float = 4.431e6
    k_t1: float = 0.0
    k_t2: float = 0.0
    sidewall_tangential: bool = False
    sidewall_T: float = 0.0
    sidewall_EA: float = 0.0
    rim_mass: float | None = None
    rim_inertia: float | None = None
    rim_radius: float = 0.254
    fixture_k: float = 0.0
    fixture_k_rot: float = 0.0
    cavity: bool = False
    c_air: float = 343.0
    rho_air: float = 10.6
    cavity_radius: float = 0.44
    cavity_area: float = 0.12
    masses: tuple[tuple[float, float], ...] = ()
    n_elements: int = 180

    UNITS = {"R": "m", "b": "m", "P0": "Pa", "rhoA": "kg/m", "EI": "N·m²", "EA": "N", "kGA": "N",
             "rhoI": "kg·m", "tangential": "bool", "m_s": "kg/m", "k_r1": "N/m²", "k_r2": "N/m²",
             "k_t1": "N/m²", "k_t2": "N/m²",
             "sidewall_tangential": "bool", "sidewall_T": "N", "sidewall_EA": "N", "rim_mass": "kg",
             "rim_inertia": "kg·m²", "rim_radius": "m", "fixture_k": "N/m", "fixture_k_rot": "N·m/rad",
             "cavity": "bool", "c_air": "m/s", "rho_air": "kg/m³", "cavity_radius": "m",
             "cavity_area": "m²", "masses": "[(deg, kg)]", "n_elements": "count"}
    _POSITIVE = ("R", "b", "rhoA", "EI", "c_air", "rho_air", "cavity_radius", "cavity_area", "rim_radius")
    _NONNEGATIVE = ("P0", "EA", "rhoI", "m_s", "k_r1", "k_r2", "k_t1", "k_t2", "sidewall_T", "sidewall_EA",
                    "fixture_k", "fixture_k_rot")

    def __post_init__(self):
        def bad(name, why):
            raise ParameterError(f"ring parameter {name}={getattr(self, name)!r} {why} ({self.UNITS[name]})")
        for name in self._POSITIVE + self._NONNEGATIVE:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
                bad(name, "must be a finite number")
            if (name in self._POSITIVE and v <= 0) or v < 0:
                bad(name, "must be > 0" if name in self._POSITIVE else "must be ≥ 0")
        for name in ("kGA", "rim_mass", "rim_inertia"):
            v = getattr(self, name)
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))
                                  or not np.isfinite(v) or v <= 0):
                bad(name, "must be a positive finite number or absent")
        for name in ("tangential", "cavity", "sidewall_tangential"):
            if not isinstance(getattr(self, name), bool):
                bad(name, "must be true or false")
        if not isinstance(self.n_elements, int) or isinstance(self.n_elements, bool) or not 12 <= self.n_elements <= 2000:
            bad("n_elements", "must be an integer in 12 … 2000")
        for item in self.masses:
            if (len(item) != 2 or not all(isinstance(x, (int, float)) and np.isfinite(x) for x in item)
                    or item[1] <= 0):
                bad("masses", "must be pairs [angle_deg, kg > 0]")
        if self.m_s == 0 and (self.k_r1 > 0) != (self.k_r2 > 0):
            bad("m_s", "is 0: a massless sidewall needs both k_r1 and k_r2 or neither")
        if self.cavity_radius >= self.R:
            bad("cavity_radius", f"must be below the tread radius R={self.R}")

    @property
    def T(self) -> float:
        """Hoop pre-tension P0 b R, N."""
        return self.P0 * self.b * self.R

    @property
    def k_t(self) -> float:
        """Tangential stiffness tread–rim of a sidewall without tangential mass: k_t1 and
        k_t2 in series, N/m²."""
        if self.k_t1 == 0 or self.k_t2 == 0:
            return 0.0
        return self.k_t1 * self.k_t2 / (self.k_t1 + self.k_t2)

    def replace(self, **changes) -> "RingParameters":
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["masses"] = [list(m) for m in self.masses]
        return d

    @classmethod
    def from_mapping(cls, values: Mapping, base: "RingParameters | None" = None,
                     where: str = "ring") -> "RingParameters":
        """Parameters from a mapping (a TOML ``[ring]`` table); unknown keys and wrong types
        raise ParameterError naming the key and what is allowed."""
        names = {f.name: f for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - set(names))
        if unknown:
            raise ParameterError(f"{where}: unknown ring parameter {unknown[0]!r}; allowed: "
                                 f"{', '.join(sorted(names))}")
        out = {}
        for k, v in values.items():
            if isinstance(v, str) and k not in ("kGA", "rim_mass", "rim_inertia"):
                v = {"true": True, "false": False}.get(v.strip().lower(), v)  # command-line text
            if k in ("tangential", "cavity", "sidewall_tangential"):
                if not isinstance(v, bool):
                    raise ParameterError(f"{where}: {k}={v!r} must be true or false")
                out[k] = v
            elif k == "n_elements":
                if isinstance(v, str) and v.strip().isdigit():
                    v = int(v)
                if isinstance(v, bool) or not isinstance(v, int):
                    raise ParameterError(f"{where}: n_elements={v!r} must be an integer")
                out[k] = v
            elif k == "masses":
                try:
                    out[k] = tuple((float(a), float(m)) for a, m in v)
                except (TypeError, ValueError):
                    raise ParameterError(f"{where}: masses={v!r} must be a list of [angle_deg, kg]") from None
            elif k in ("kGA", "rim_mass", "rim_inertia") and (v is None or (isinstance(v, str) and v.lower() in ("none", "clamped"))):
                out[k] = None
            else:
                if isinstance(v, bool):
                    raise ParameterError(f"{where}: {k}={v!r} must be a number ({cls.UNITS[k]})")
                try:
                    out[k] = float(v)
                except (TypeError, ValueError):
                    raise ParameterError(f"{where}: {k}={v!r} must be a number ({cls.UNITS[k]})") from None
        return dataclasses.replace(base or cls(), **out)


#: One physical effect at a time on top of the default (the paper's model as a limit).
#: Values are plausible for a 16.00R20 truck tyre; each is documented in docs/simulate.md.
RING_VARIANTS: dict[str, dict] = {
    "none": {},
    # a ring that moves tangentially, nearly inextensible (steel belt), and a sidewall that
    # resists tangential (shear) motion
    "tangential": {"tangential": True, "EA": 1.0e8, "k_t1": 2.0e6, "k_t2": 1.5e6},
    # the same with a belt of finite hoop stiffness: the breathing (n = 0) mode rises
    "extensible": {"tangential": True, "EA": 8.0e6, "k_t1": 2.0e6, "k_t2": 1.5e6},
    # the sidewall's mass moving tangentially too (its own tangential modes)
    "sidewall_shear": {"tangential": True, "EA": 1.0e8, "k_t1": 2.0e6, "k_t2": 1.5e6,
                       "sidewall_tangential": True},
    # shear deformation and rotary inertia of a 20 mm tread
    "timoshenko": {"kGA": 6.0e5, "rhoI": 19.64 * 0.02**2 / 12},
    # circumferential coupling in the sidewall (a membrane tension on its radial slope)
    "sidewall_coupling": {"sidewall_T": 2.0e4},
    # a free rim of 60 kg on a soft fixture
    "rim": {"rim_mass": 60.0, "fixture_k": 2.0e6},
    # the air cavity
    "cavity": {"cavity": True},
    # a 0.5 kg lumped mass (valve and sensor block) at 45°
    "mass": {"masses": ((45.0, 0.5),)},
}
