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

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.ring_fe import interp_weights, reduced_matrices
from tiremodal_cli.tyre.ring_parameters import RingParameters

__all__ = ['RingModes', 'ring_modes', 'elements_for', 'ring_observation', 'ring_frf', 'classical_ring_hz']


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
    Kr, Mr, G, M, index, rim = reduced_matrices(p)
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
        nodes, wts = interp_weights(angle_rad, modes.n_nodes)
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
    if form not in ("receptance", "mobility", "accelerance"):
        raise ParameterError(f"form={form!r}; allowed: receptance, mobility, accelerance")
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
