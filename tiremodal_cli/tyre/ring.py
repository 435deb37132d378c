"""An in-plane finite-element tyre: the independent reference for validation.

This module shares no code with :mod:`tiremodal_cli.tyre.model` or :mod:`tiremodal_cli.tyre.effects`:
it discretises the tyre in the circumferential coordinate ``s = R θ`` instead of solving
per-order blocks, so a test simulated from it is truth the estimator did not write.

Structure (``docs/simulate.md``, section "The ring model"):

* **tread** — a curved beam on the circle of radius R: radial ``w`` (outwards),
  tangential ``v`` (in the sense of θ) and cross-section rotation ``ψ`` at every node.
  Strains of the thin ring (Soedel, *Vibrations of Shells and Plates*, ch. 4):
  membrane ``ε = v' + w/R``, shear ``γ = w' − v/R − ψ``, curvature ``κ = ψ'``
  (``' = d/ds``). Energy per length ``½(EA ε² + kGA γ² + EI κ²)``; inertia
  ``½(ρA (ẇ² + v̇²) + ρI ψ̇²)``. Euler–Bernoulli (``kGA = None``) is the limit of a stiff
  shear term, a penalty scaled with the mesh (:func:`_shear_stiffness`). (Imposing γ = 0
  exactly at the reduced Gauss points is not possible with quadratic ψ: the constraint
  matrix has the element's hourglass pattern in its null space.)
* **inflation** — hoop pre-tension ``T = P0 b R`` and the follower pressure ``P0 b``
  acting on the deformed tread. Their second-order potential, from the Green strain of
  the centre line and the change of the enclosed area (derived in docs/simulate.md), is
  ``½ T (w'² + v'² − 2 w' v / R)`` per length: for an inextensible ring it gives the
  radial stiffness ``(P0 b / R)(n² − 1)``, for a ring held radially (v = 0) ``T n²/R²``.
* **sidewall** — a layer with its own mass per length ``m_s`` and radial and tangential
  motion ``u_s, v_s``: springs tread–sidewall (``k_r1``, ``k_t1``) and sidewall–rim
  (``k_r2``, ``k_t2``) per unit tread length, and a circumferential coupling between
  neighbouring sidewall points: a tension ``sidewall_T`` on its radial slope
  (``½ T_s u_s'²``) and a stretch stiffness ``sidewall_EA`` (``½ EA_s (v_s' + u_s/R)²``).
* **rim** — a rigid body (translations x, y and rotation φ; mass ``rim_mass``, inertia
  ``rim_inertia``) on an optional fixture (``fixture_k``, ``fixture_k_rot``); ``rim_mass =
  None`` clamps it. The sidewall springs attach to it at the bead radius ``rim_radius``.
* **air cavity** (optional) — a one-dimensional acoustic annulus of mean radius
  ``cavity_radius`` and cross-section ``cavity_area``, described by the air's
  circumferential displacement ξ: kinetic energy ``½ ρ0 A ξ̇²``, potential
  ``½ ρ0 c² A (ξ' + b w / A)²`` (the tread's radial motion changes the cavity's volume).
* **lumped masses** on the tread (a sensor, a valve).

Quadratic (three-node) elements, Gauss integration: membrane and shear terms with two
points (selective reduced integration, free of shear and membrane locking), the others
with four. Massless freedoms (ψ of a Timoshenko tread without rotary inertia) are
condensed statically — exact for massless freedoms. Modes from a dense symmetric generalised eigenproblem
(``scipy.linalg.eigh``) on the condensed system: a few thousand freedoms at most, so a
dense solver is both simpler and faster than a sparse shift-invert for the hundreds of
modes below a test's Nyquist frequency. The matrices are assembled sparse
(``scipy.sparse``) and condensed with a sparse factorisation.

References
----------
W. Soedel, *Vibrations of Shells and Plates*, 3rd ed., Marcel Dekker, 2004 (ring strains,
in-plane ring frequencies). R. D. Cook et al., *Concepts and Applications of Finite Element
Analysis*, 4th ed., Wiley, 2002 (selective reduced integration, static condensation).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from tiremodal_cli.conventions import FRF_FORMS
from tiremodal_cli.errors import ParameterError

__all__ = ["RingParameters", "RingModes", "ring_modes", "ring_frf", "ring_observation",
           "RING_VARIANTS", "classical_ring_hz", "elements_for"]

#: Fields at each node, in this order (those switched off are removed).
_FIELDS = ("w", "v", "psi", "us", "vs", "xi")


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


@dataclass(frozen=True)
class RingModes:
    """Modes of the finite-element tyre.

    Attributes
    ----------
    freq_hz : (n_modes,) ndarray, Hz            ascending
    shapes : (n_modes, n_dof) ndarray           mass-normalised (φᵀ M φ = 1), m/√kg
    n : (n_modes,) ndarray of int               dominant circumferential order
    n_purity : (n_modes,) ndarray               share of the dominant order in the
        shape's strain-free measure (tread and sidewall displacements)
    branch : tuple of str                       "same", "opposite", "tangential", "rim",
        "cavity" (by energy, :func:`_label`)
    harmonic : tuple of str                     "cos", "sin" or "mixed"
    energy : (n_modes, 5) ndarray               kinetic energy shares: tread radial,
        tread tangential, sidewall, rim, cavity air
    params : RingParameters
    dof_index : dict                            field → (n_nodes,) global index (or None)
    rim_index : tuple of int                    global indices of rim x, y, φ (if free)
    n_nodes : int
    """

    freq_hz: np.ndarray
    shapes: np.ndarray
    n: np.ndarray
    n_purity: np.ndarray
    branch: tuple[str, ...]
    harmonic: tuple[str, ...]
    energy: np.ndarray
    params: RingParameters
    dof_index: dict = field(repr=False, default_factory=dict)
    rim_index: tuple[int, ...] = ()
    n_nodes: int = 0

    @property
    def node_angle(self) -> np.ndarray:
        """(n_nodes,) angles of the nodes, rad."""
        return 2 * np.pi * np.arange(self.n_nodes) / self.n_nodes


# ----------------------------------------------------------------------------- elements

def _shape_functions(xi):
    """Quadratic Lagrange shape functions and their ξ-derivatives at ``xi`` (k,) → (k, 3)."""
    xi = np.asarray(xi, dtype=float)[:, None]
    N = np.hstack([xi * (xi - 1) / 2, 1 - xi**2, xi * (xi + 1) / 2])
    dN = np.hstack([xi - 0.5, -2 * xi, xi + 0.5])
    return N, dN


def _shear_stiffness(p: RingParameters) -> float:
    """The shear stiffness used: kGA, or for Euler–Bernoulli a penalty 1e3 EI (N_e / R)².

    The penalty's relative effect on the bending stiffness of a wave of order n is
    EI k² / kGA = 1e-3 (n / N_e)²: 1.2e-5 for n = 20 at the default 180 elements, and
    below 1e-4 for every order the mesh resolves to 0.02 % (n ≤ N_e / 9, see
    :func:`elements_for`). Its ratio to one element's bending stiffness, kGA h² / EI =
    1e3 (2π)² ≈ 4e4, keeps the condensation well conditioned at any mesh: the eigenvalues'
    rounding floor, which grows with the penalty, stays below 1e-6 of a tyre's lowest ω².
    """
    return p.kGA if p.kGA is not None else 1e3 * p.EI * (p.n_elements / p.R) ** 2


def _active_fields(p: RingParameters) -> tuple[str, ...]:
    has_sidewall = p.m_s > 0 or p.k_r1 > 0
    tang_sidewall = p.tangential and has_sidewall and p.sidewall_tangential
    out = ["w"]
    if p.tangential:
        out.append("v")
    out.append("psi")
    if has_sidewall:
        out.append("us")
        if tang_sidewall:
            out.append("vs")
    if p.cavity:
        out.append("xi")
    return tuple(out)


def _rim_dofs(p: RingParameters) -> tuple[str, ...]:
    """Rim freedoms that exist: none when clamped; φ only when something turns it."""
    if p.rim_mass is None:
        return ()
    out = ["x", "y"]
    if p.tangential and (p.k_t2 > 0 or p.fixture_k_rot > 0):  # k_t2 > 0 implies a tangential spring to it
        out.append("phi")
    return tuple(out)


def _assemble(p: RingParameters):
    """Global sparse stiffness and mass, and the index of every field's nodes.

    Returns
    -------
    K, M : (n_dof, n_dof) scipy.sparse.csr_matrix
    index : dict field → (n_nodes,) int array
    rim : dict rim dof → int
    """
    fields_ = _active_fields(p)
    nf = len(fields_)
    ne = p.n_elements
    nn = 2 * ne
    dth = 2 * np.pi / ne
    L = p.R * dth  # element length along the tread, m
    J = L / 2  # ds/dξ
    fi = {f: i for i, f in enumerate(fields_)}
    rim_names = _rim_dofs(p)
    n_dof = nn * nf + len(rim_names)
    rim = {r: nn * nf + i for i, r in enumerate(rim_names)}
    index = {f: np.arange(nn) * nf + fi[f] for f in fields_}

    n_el_dof = 3 * nf

    def rows(N):
        """Row vectors (k, n_el_dof) of each field's interpolation ``N`` (k, 3)."""
        out = {}
        for f in fields_:
            r = np.zeros((N.shape[0], n_el_dof))
            r[:, np.arange(3) * nf + fi[f]] = N
            out[f] = r
        return out

    zero = None

    def get(d, f):
        return d[f] if f in d else zero

    T = p.T
    Ke = np.zeros((n_el_dof, n_el_dof))
    Me = np.zeros((n_el_dof, n_el_dof))

    def add(mat, coef, a, w, c=None):
        """mat += Σ_g w_g J coef a_g c_gᵀ (c = a: a square term)."""
        c = a if c is None else c
        mat += np.einsum("g,gi,gj->ij", coef * w * J, a, c)

    # reduced (2-point) Gauss for membrane and shear, 4-point for everything else
    for npts, terms in ((2, "reduced"), (4, "full")):
        xg, wg = np.polynomial.legendre.leggauss(npts)
        N, dN = _shape_functions(xg)
        V, D = rows(N), rows(dN / J)  # values, d/ds
        zero = np.zeros((npts, n_el_dof))
        w_, v_, psi = V["w"], get(V, "v"), V["psi"]
        dw, dv, dpsi = D["w"], get(D, "v"), D["psi"]
        if terms == "reduced":
            if p.tangential and p.EA > 0:
                add(Ke, p.EA, dv + w_ / p.R, wg)
            elif p.EA > 0:
                add(Ke, p.EA, w_ / p.R, wg)
            add(Ke, _shear_stiffness(p), dw - v_ / p.R - psi, wg)
            continue
        add(Ke, p.EI, dpsi, wg)
        # pre-tension and follower pressure: ½ T (w'² + v'² − 2 w' v / R)
        add(Ke, T, dw, wg)
        if p.tangential:
            add(Ke, T, dv, wg)
            add(Ke, -T / p.R, dw, wg, v_)
            add(Ke, -T / p.R, v_, wg, dw)
        add(Me, p.rhoA, w_, wg)
        if p.tangential:
            add(Me, p.rhoA, v_, wg)
        if p.rhoI > 0:
            add(Me, p.rhoI, psi, wg)
        if "us" in fields_:
            us, dus = V["us"], D["us"]
            add(Ke, p.k_r1, w_ - us, wg)
            add(Ke, p.k_r2, us, wg)  # the rim's share is added per element below
            add(Me, p.m_s, us, wg)
            if p.sidewall_T > 0:
                add(Ke, p.sidewall_T, dus, wg)
            if "vs" in fields_:
                vs, dvs = V["vs"], D["vs"]
                add(Ke, p.k_t1, v_ - vs, wg)
                add(Ke, p.k_t2, vs, wg)
                add(Me, p.m_s, vs, wg)
                if p.sidewall_EA > 0:
                    add(Ke, p.sidewall_EA, dvs + us / p.R, wg)
            elif p.tangential and p.k_t > 0:
                add(Ke, p.k_t, v_, wg)  # tread–rim in series; the rim's share in _rim_terms
        elif p.tangential and p.k_t > 0:
            add(Ke, p.k_t, v_, wg)
        if "xi" in fields_:
            # cavity: ½ ρ0 c² A (ξ' + b w / A)² and ½ ρ0 A ξ̇², per length of the tread (the
            # annulus' own length 2π R_c is mapped onto the tread's by ds_c = (R_c/R) ds)
            xi_, dxi = V["xi"], D["xi"]
            rc = p.cavity_radius / p.R
            A = p.cavity_area
            add(Ke, p.rho_air * p.c_air**2 * A * rc, dxi / rc + p.b * w_ / (A * rc), wg)
            add(Me, p.rho_air * A * rc, xi_, wg)

    # scatter the (identical) element matrices around the ring
    el_nodes = (2 * np.arange(ne)[:, None] + np.arange(3)[None, :]) % nn  # (ne, 3)
    el_dofs = (el_nodes[:, :, None] * nf + np.arange(nf)[None, None, :]).reshape(ne, -1)
    ii = np.repeat(el_dofs, n_el_dof, axis=1).ravel()
    jj = np.tile(el_dofs, (1, n_el_dof)).ravel()
    K = scipy.sparse.coo_matrix((np.tile(Ke.ravel(), ne), (ii, jj)), shape=(n_dof, n_dof))
    M = scipy.sparse.coo_matrix((np.tile(Me.ravel(), ne), (ii, jj)), shape=(n_dof, n_dof))
    K, M = K.tocsr(), M.tocsr()
    K = K + _rim_terms(p, index, rim, ne, nf, J, n_dof)
    M = M + _rim_mass(p, rim, n_dof) + _lumped(p, index, nn, n_dof)
    K = K + _fixture(p, rim, n_dof)
    return K.tocsr(), M.tocsr(), index, rim


def _rim_terms(p, index, rim, ne, nf, J, n_dof):
    """Coupling of the sidewall springs k_r2, k_t2 to the rim's rigid motion.

    The spring energy ½ k_r2 (u_s − x cos θ − y sin θ)² (and ½ k_t2 (v_s + x sin θ − y cos θ
    − r_b φ)²) has the sidewall-only part in the element matrices; here are the cross and
    rim-rim parts, integrated with the same 4-point rule per element.
    """
    if not rim:
        return scipy.sparse.csr_matrix((n_dof, n_dof))
    xg, wg = np.polynomial.legendre.leggauss(4)
    N, _ = _shape_functions(xg)
    nn = 2 * ne
    rows_, cols, vals = [], [], []

    def put(i, j, v):
        rows_.append(i), cols.append(j), vals.append(v)

    springs = [("us", p.k_r2, lambda th: {"x": np.cos(th), "y": np.sin(th)})]
    if "vs" in index and p.k_t2 > 0:
        springs.append(("vs", p.k_t2, lambda th: {"x": -np.sin(th), "y": np.cos(th), "phi": p.rim_radius}))
    elif "v" in index and p.k_t > 0:
        springs.append(("v", p.k_t, lambda th: {"x": -np.sin(th), "y": np.cos(th), "phi": p.rim_radius}))
    for e in range(ne):
        nodes = np.array([2 * e, 2 * e + 1, 2 * e + 2]) % nn
        th = 2 * np.pi / ne * (e + (xg + 1) / 2)  # Gauss points' angles
        for fld, k, gfun in springs:
            if fld not in index:
                continue
            g = gfun(th)
            g = {r: np.broadcast_to(v, th.shape) for r, v in g.items() if r in rim}
            dofs = index[fld][nodes]
            for r, gr in g.items():
                # cross terms −k ∫ N_a g_r ds (both orders)
                c = -k * np.einsum("g,ga,g->a", wg * J, N, gr)
                for a in range(3):
                    put(dofs[a], rim[r], c[a])
                    put(rim[r], dofs[a], c[a])
                for r2, gr2 in g.items():
                    put(rim[r], rim[r2], k * np.sum(wg * J * gr * gr2))
    return scipy.sparse.coo_matrix((vals, (rows_, cols)), shape=(n_dof, n_dof)).tocsr()


def _rim_mass(p, rim, n_dof):
    d = np.zeros(n_dof)
    if "x" in rim:
        d[rim["x"]] = d[rim["y"]] = p.rim_mass
    if "phi" in rim:
        d[rim["phi"]] = p.rim_inertia if p.rim_inertia is not None else p.rim_mass * p.rim_radius**2
    return scipy.sparse.diags(d)


def _fixture(p, rim, n_dof):
    d = np.zeros(n_dof)
    if "x" in rim:
        d[rim["x"]] = d[rim["y"]] = p.fixture_k
    if "phi" in rim:
        d[rim["phi"]] = p.fixture_k_rot
    return scipy.sparse.diags(d)


def _lumped(p, index, nn, n_dof):
    """Lumped masses on the tread, shared between the neighbouring nodes' w (and v) by the
    element's shape functions (the consistent load vector of a point mass, to first order)."""
    M = scipy.sparse.lil_matrix((n_dof, n_dof))
    for angle_deg, mass in p.masses:
        c = _interp_weights(np.deg2rad(angle_deg), nn)
        for fld in ("w", "v"):
            if fld in index:
                idx = index[fld][c[0]]
                M[np.ix_(idx, idx)] += mass * np.outer(c[1], c[1])
    return M.tocsr()


def _interp_weights(angle_rad: float, nn: int):
    """Nodes and quadratic shape-function weights of the tread point at ``angle_rad``."""
    ne = nn // 2
    t = (angle_rad % (2 * np.pi)) / (2 * np.pi) * ne
    e = min(int(np.floor(t)), ne - 1)
    xi = 2 * (t - e) - 1
    N, _ = _shape_functions([xi])
    nodes = np.array([2 * e, 2 * e + 1, 2 * e + 2]) % nn
    return nodes, N[0]


# ----------------------------------------------------------------------------- solving

def _condense(K, M):
    """Static condensation of the massless freedoms (exact for them).

    Returns the reduced dense K, M and the map back ``q_full = G q_kept`` (None when
    nothing is massless).
    """
    massless = np.flatnonzero(np.asarray(abs(M).sum(axis=1)).ravel() == 0)
    keep = np.setdiff1d(np.arange(K.shape[0]), massless)
    if massless.size == 0:
        return K.toarray(), M.toarray(), None
    Kkk = K[keep][:, keep]
    Kkm = K[keep][:, massless]
    # K_mm (bending and shear of the rotations) is symmetric positive definite and small:
    # a dense Cholesky solve with many right-hand sides is far faster than a sparse LU's
    Kmm = K[massless][:, massless].toarray()
    X = scipy.linalg.cho_solve(scipy.linalg.cho_factor(Kmm), -(Kkm.T).toarray())  # q_m = X q_k
    Kr = Kkk.toarray() + Kkm.toarray() @ X
    Kr = (Kr + Kr.T) / 2
    Mr = M[keep][:, keep].toarray()
    G = np.zeros((K.shape[0], keep.size))
    G[keep, np.arange(keep.size)] = 1.0
    G[massless] = X
    return Kr, Mr, G


def _reduced(p: RingParameters):
    """Assembled system with its massless freedoms condensed; returns dense K, M, the map to
    every freedom, the full sparse M, the field index and the rim freedoms."""
    K, M, index, rim = _assemble(p)
    Kr, Mr, G = _condense(K, M)
    return Kr, Mr, G, M, index, rim


def ring_modes(p: RingParameters, *, f_max_hz: float | None = None) -> RingModes:
    """Modes of the finite-element tyre below ``f_max_hz`` (all when None).

    Parameters
    ----------
    p : RingParameters
    f_max_hz : float, optional, Hz
        Keep modes up to this frequency (rigid-body modes, below 0.1 Hz, are dropped).

    Returns
    -------
    RingModes
    """
    Kr, Mr, G, M, index, rim = _reduced(p)
    hi = None if f_max_hz is None else (2 * np.pi * f_max_hz) ** 2
    w2, vec = scipy.linalg.eigh(Kr, Mr, subset_by_value=(-np.inf, hi) if hi is not None else None,
                                driver="gvx" if hi is not None else "gvd")
    phi = vec if G is None else G @ vec  # (n_dof, n_modes), φᵀ M φ = 1
    ok = w2 > (2 * np.pi * 0.1) ** 2
    w2, phi = w2[ok], phi[:, ok]
    nn = 2 * p.n_elements
    phi = _align_pairs(w2, phi, index, nn)
    n, purity, harmonic = _orders(phi, index, nn)
    energy = _energy(phi, M, index, rim)
    branch = tuple(_label(phi[:, j], index, rim, energy[j], int(n[j]), nn) for j in range(phi.shape[1]))
    return RingModes(freq_hz=np.sqrt(w2) / (2 * np.pi), shapes=phi.T.copy(), n=n, n_purity=purity,
                     branch=branch, harmonic=harmonic, energy=energy, params=p, dof_index=index,
                     rim_index=tuple(rim.values()), n_nodes=nn)


def _harmonics(x, nn):
    """Fourier coefficients of nodal values (…, nn) → complex (…, nn//2 + 1)."""
    return np.fft.rfft(x, axis=-1) / nn


def _orders(phi, index, nn):
    """Dominant order n of each mode, its share, and the harmonic (cos/sin/mixed)."""
    power = 0
    for f in ("w", "v", "us", "vs"):
        if f in index:
            power = power + np.abs(_harmonics(phi[index[f]].T, nn)) ** 2
    n = np.argmax(power, axis=1)
    purity = power[np.arange(n.size), n] / power.sum(axis=1)
    c = _harmonics(phi[index["w"]].T, nn)[np.arange(n.size), n]
    if "us" in index:
        c2 = _harmonics(phi[index["us"]].T, nn)[np.arange(n.size), n]
        c = np.where(np.abs(c2) > np.abs(c), c2, c)
    harmonic = []
    for j in range(n.size):
        if n[j] == 0:
            harmonic.append("cos")
            continue
        a, b = abs(c[j].real), abs(c[j].imag)  # rfft: cos → real part, sin → −imag
        harmonic.append("cos" if b < 1e-3 * a else "sin" if a < 1e-3 * b else "mixed")
    return n.astype(int), purity, tuple(harmonic)


def _align_pairs(w2, phi, index, nn, rtol=1e-6):
    """Rotate each degenerate pair of modes (equal frequencies: an axisymmetric ring's cos/sin
    pair) so that the first is a cos and the second a sin shape of their order."""
    phi = phi.copy()
    j = 0
    while j < len(w2) - 1:
        if abs(w2[j + 1] - w2[j]) <= rtol * abs(w2[j]):
            pair = phi[:, j:j + 2]
            h = _harmonics(pair[index["w"]].T, nn)
            n = int(np.argmax(np.abs(h).sum(axis=0)[1:])) + 1
            a = h[:, n]  # complex coefficient of each member; cos part = real
            ang = np.arctan2(a[1].real, a[0].real)
            c, s = np.cos(ang), np.sin(ang)
            phi[:, j:j + 2] = pair @ np.array([[c, -s], [s, c]])
            j += 2
        else:
            j += 1
    return phi


def _energy(phi, M, index, rim):
    """Kinetic-energy shares of each mode (φᵀ M φ split by field): tread radial, tread
    tangential (and rotation), sidewall, rim, cavity air. (n_modes, 5)."""
    Mphi = M @ phi
    parts = [["w"], ["v", "psi"], ["us", "vs"], None, ["xi"]]
    out = np.zeros((phi.shape[1], 5))
    for k, fl in enumerate(parts):
        if fl is None:
            idx = np.array(list(rim.values()), dtype=int)
        else:
            idx = np.concatenate([index[f] for f in fl if f in index] + [np.zeros(0, int)])
        if idx.size:
            out[:, k] = np.einsum("ij,ij->j", phi[idx], Mphi[idx])
    tot = out.sum(axis=1, keepdims=True)
    return out / np.where(tot > 0, tot, 1)


def _label(vec, index, rim, energy, n, nn) -> str:
    """Branch of one mode from its energy and the phase of tread and sidewall.

    * cavity: most of the kinetic energy in the air;
    * rim: the rim's share is the largest;
    * tangential: the tread's tangential motion carries more energy than its radial motion
      and the sidewall's (an extensional / tangential mode of the ring);
    * same / opposite: tread and sidewall radial amplitudes of order n in phase / in
      anti-phase (the paper's two branches).
    """
    e_w, e_v, e_s, e_r, e_a = energy
    if e_a > 0.5:
        return "cavity"
    if e_r >= max(e_w, e_v, e_s):
        return "rim"
    if e_v > max(e_w, e_s):
        return "tangential"
    if "us" not in index:
        return "same"
    hw = _harmonics(vec[index["w"]], nn)[n]
    hs = _harmonics(vec[index["us"]], nn)[n]
    return "same" if (hw * np.conj(hs)).real >= 0 else "opposite"


def elements_for(p: RingParameters, f_max_hz: float) -> int:
    """Elements a mesh needs so that every tread-dominated order below ``f_max_hz`` is
    resolved to about 0.02 % in frequency.

    The highest such order is bounded by the bare tread under tension,
    ``ω² ρA = EI n⁴/R⁴ + T n²/R²`` (the foundation only raises a frequency, so every order
    whose bare-tread frequency is above f_max has its tread modes above it too). The
    measured convergence of the quadratic elements (tests/test_ring.py) gives 0.02 % at
    nine elements per order (n = 20 on 180 elements), so N_e = 9 n_top, rounded up to an
    even count. Sidewall-dominated modes of higher order (the same-direction branch
    saturating below √((k_r1 + k_r2)/m_s)) converge with their small tread share.
    """
    n = 1
    while n < 400:
        w2 = (p.EI * n**4 / p.R**4 + p.T * n**2 / p.R**2) / p.rhoA
        if np.sqrt(w2) / (2 * np.pi) > f_max_hz:
            break
        n += 1
    return int(2 * np.ceil(9 * n / 2))


# ----------------------------------------------------------------------------- FRFs

def ring_observation(modes: RingModes, location: str, angle_rad: float) -> np.ndarray:
    """Weights turning a mode shape into the radial displacement at a place.

    Parameters
    ----------
    modes : RingModes
    location : {"tread", "sidewall", "rim"}
    angle_rad : float, rad

    Returns
    -------
    c : (n_dof,) ndarray
        ``u = c @ q``; by reciprocity also the generalised force of a unit radial force there.
    """
    n_dof = modes.shapes.shape[1]
    c = np.zeros(n_dof)
    if location in ("tread", "sidewall"):
        fld = "w" if location == "tread" else "us"
        if fld not in modes.dof_index:
            raise ParameterError(f"location={location!r}: this ring model has no sidewall freedom")
        nodes, wts = _interp_weights(angle_rad, modes.n_nodes)
        c[modes.dof_index[fld][nodes]] = wts
    elif location == "rim":
        if modes.rim_index:
            c[modes.rim_index[0]] = np.cos(angle_rad)
            c[modes.rim_index[1]] = np.sin(angle_rad)
    else:
        raise ParameterError(f"location={location!r}; allowed: tread, sidewall, rim")
    return c


def ring_frf(modes: RingModes, freq_hz, damping_ratio, out_locations, out_angles, in_angles, *,
             form: str = "accelerance") -> np.ndarray:
    """FRFs between radial tread point forces and radial responses by modal superposition.

    ``H_oi(ω) = Σ_r c_o·φ_r c_i·φ_r / (ω_r² − ω² + 2iζ_r ω_r ω)`` (receptance, m/N), times iω
    (mobility) or −ω² (accelerance).

    Returns
    -------
    H : (n_out, n_in, n_freq) complex ndarray
    """
    if form not in FRF_FORMS:
        raise ParameterError(f"form={form!r}; allowed: {', '.join(FRF_FORMS)}")
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    wr = 2 * np.pi * modes.freq_hz
    zeta = np.broadcast_to(np.asarray(damping_ratio, dtype=float), wr.shape)
    C_out = np.array([ring_observation(modes, loc, a) for loc, a in zip(out_locations, out_angles)])
    C_in = np.array([ring_observation(modes, "tread", a) for a in np.atleast_1d(in_angles)])
    po = C_out @ modes.shapes.T
    pi = C_in @ modes.shapes.T
    den = wr[:, None] ** 2 - w[None, :] ** 2 + 2j * zeta[:, None] * wr[:, None] * w[None, :]
    # Σ_r po_or pi_ir / den_rf as one matrix product (n_out·n_in, n_modes) @ (n_modes, n_freq)
    H = ((po[:, None, :] * pi[None, :, :]).reshape(-1, wr.size) @ (1.0 / den)).reshape(po.shape[0], pi.shape[0], -1)
    if form == "mobility":
        H = H * (1j * w)
    elif form == "accelerance":
        H = H * (-(w**2))
    return H


def classical_ring_hz(n, p: RingParameters) -> np.ndarray:
    """In-plane bending frequencies of a free, thin, inextensible ring (no pressure):
    ω² = EI n² (n² − 1)² / (ρA R⁴ (n² + 1)) (Soedel 2004, eq. 4.5.x; Love 1944).

    Parameters
    ----------
    n : int or array of int, ≥ 2
    p : RingParameters  (R, rhoA, EI used)

    Returns
    -------
    freq_hz : ndarray, Hz
    """
    n = np.asarray(n, dtype=float)
    w2 = p.EI * n**2 * (n**2 - 1) ** 2 / (p.rhoA * p.R**4 * (n**2 + 1))
    return np.sqrt(w2) / (2 * np.pi)
