"""The tyre model solved in full: every order's modes with shapes (coupling effects too),
the observation of a sensor, and FRFs synthesised from the modes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from tiremodal_cli.errors import ParameterError
from tiremodal_cli.tyre.effects import resolve_effects
from tiremodal_cli.tyre.model import FRF_FORMS, TyreParameters, block, branch_label, dof_list, eig_pairs, generalised_length, solve_block
__all__ = ['ModalModel', 'solve_modes', 'observation', 'frf']


@dataclass(frozen=True)
class ModalModel:
    """Modes of the tyre model.

    Attributes
    ----------
    freq_hz : (n_modes,) ndarray, Hz       sorted ascending
    n : (n_modes,) ndarray of int          circumferential order (dominant one if coupled)
    harmonic : tuple of str                "cos", "sin" or "mixed"
    branch : tuple of str                  "same", "opposite", "rim" or "cavity"
    shapes : (n_modes, n_dof) ndarray      unit generalised mass, m/√kg
    dofs : tuple of (kind, n, harmonic)    the generalised coordinates
    """

    freq_hz: np.ndarray
    n: np.ndarray
    harmonic: tuple[str, ...]
    branch: tuple[str, ...]
    shapes: np.ndarray
    dofs: tuple[tuple[str, int, str], ...]

    def select(self, mask) -> "ModalModel":
        idx = np.flatnonzero(mask)
        return ModalModel(self.freq_hz[idx], self.n[idx], tuple(self.harmonic[i] for i in idx),
                          tuple(self.branch[i] for i in idx), self.shapes[idx], self.dofs)


def solve_modes(p: TyreParameters, *, n_max: int = 30, effects=None) -> ModalModel:
    """All modes of orders 0 … ``n_max`` (both harmonics of every n ≥ 1).

    Parameters
    ----------
    p : TyreParameters
    n_max : int, keyword-only
    effects : mapping ``{name: {param: value}}`` or resolved sequence, keyword-only

    Returns
    -------
    ModalModel
        Without a coupling effect every mode is a pure (n, harmonic); with one (a lumped
        mass) the modes of the assembled system are labelled by their dominant order.
    """
    if not (isinstance(n_max, (int, np.integer)) and n_max >= 1):
        raise ParameterError(f"n_max={n_max!r} must be an integer ≥ 1")
    eff = resolve_effects(effects) if (effects is None or isinstance(effects, Mapping)) else tuple(effects)
    freq_dep = any(e.frequency_dependent for e, _ in eff)
    coupling = [(e, v) for e, v in eff if e.couple is not None]
    dofs, spans, _ = dof_list(p, eff, n_max)
    nd = len(dofs)
    if not coupling:
        freqs, ns, harms, branches, shapes = [], [], [], [], []
        for n in range(n_max + 1):
            blk, w2, vecs = solve_block(n, p, eff, freq_dep)
            L = generalised_length(n, p)
            md = np.diag(blk.M)
            for h in (("cos",) if n == 0 else ("cos", "sin")):
                for r in range(len(w2)):
                    phi = np.zeros(nd)
                    phi[spans[(n, h)]] = vecs[:, r] / np.sqrt(L)
                    freqs.append(np.sqrt(w2[r]) / (2 * np.pi))
                    ns.append(n)
                    harms.append(h)
                    branches.append(branch_label(vecs[:, r], blk.dofs, md))
                    shapes.append(phi)
        order = np.argsort(np.asarray(freqs), kind="stable")
        return ModalModel(np.asarray(freqs)[order], np.asarray(ns)[order],
                          tuple(harms[i] for i in order), tuple(branches[i] for i in order),
                          np.asarray(shapes)[order], dofs)
    return _solve_coupled(p, eff, coupling, dofs, spans, n_max, freq_dep)


def _assemble(p, eff, coupling, dofs, spans, n_max, freq_hz=None):
    M = np.zeros((len(dofs),) * 2)
    K = np.zeros_like(M)
    for n in range(n_max + 1):
        blk = block(n, p, eff, freq_hz=freq_hz)
        L = generalised_length(n, p)
        for h in (("cos",) if n == 0 else ("cos", "sin")):
            s = spans[(n, h)]
            M[s, s] = L * blk.M
            K[s, s] = L * blk.K
    for e, v in coupling:
        M, K = e.couple(M, K, dofs, v, p)
    return M, K


def _solve_coupled(p, eff, coupling, dofs, spans, n_max, freq_dep):
    M, K = _assemble(p, eff, coupling, dofs, spans, n_max)
    w2, vecs = eig_pairs(M, K)
    if freq_dep:
        for r in range(len(w2)):
            f = np.sqrt(w2[r]) / (2 * np.pi)
            for _ in range(100):
                Mf, Kf = _assemble(p, eff, coupling, dofs, spans, n_max, freq_hz=f)
                w2_f, v_f = eig_pairs(Mf, Kf)
                f_new = np.sqrt(w2_f[r]) / (2 * np.pi)
                done = abs(f_new - f) <= 1e-12 * max(f, 1.0)
                f = f_new
                if done:
                    break
            w2[r], vecs[:, r] = w2_f[r], v_f[:, r]
    ns, harms, branches = [], [], []
    kinds = np.array([d[0] for d in dofs])
    dof_n = np.array([d[1] for d in dofs])
    dof_h = np.array([d[2] for d in dofs])
    md = np.diag(M)
    for r in range(len(w2)):
        e = md * vecs[:, r] ** 2
        n_dom = int(np.argmax(np.bincount(dof_n, weights=e, minlength=n_max + 1)))
        sel = dof_n == n_dom
        e_cos, e_sin = e[sel & (dof_h == "cos")].sum(), e[sel & (dof_h == "sin")].sum()
        tot = e_cos + e_sin
        harm = "cos" if e_cos > 0.9 * tot else "sin" if e_sin > 0.9 * tot else "mixed"
        h_dom = "cos" if e_cos >= e_sin else "sin"
        sub = sel & (dof_h == h_dom)
        branches.append(branch_label(vecs[sub, r], tuple(kinds[sub]), md[sub]))
        ns.append(n_dom)
        harms.append(harm)
    return ModalModel(np.sqrt(w2) / (2 * np.pi), np.asarray(ns), tuple(harms), tuple(branches),
                      vecs.T.copy(), dofs)


def observation(dofs, location: str, angle_rad: float) -> np.ndarray:
    """Weights that turn generalised coordinates into a radial displacement.

    Parameters
    ----------
    dofs : tuple of (kind, n, harmonic)
    location : {"tread", "sidewall", "rim"}
    angle_rad : float, rad

    Returns
    -------
    c : (n_dof,) ndarray
        ``u(θ) = c @ q``; the same vector is the generalised force of a unit radial point
        force at that place (reciprocity).
    """
    kind = {"tread": "U", "sidewall": "S", "rim": "W"}.get(location)
    if kind is None:
        raise ParameterError(f"location={location!r}; allowed: tread, sidewall, rim")
    c = np.zeros(len(dofs))
    for j, (k, n, h) in enumerate(dofs):
        if k == kind:
            c[j] = np.cos(n * angle_rad) if h == "cos" else np.sin(n * angle_rad)
    return c


def frf(model: ModalModel, freq_hz, damping_ratio, out_locations, out_angles, in_angles, *,
        form: str = "accelerance") -> np.ndarray:
    """FRFs between tread point forces and radial responses, by modal superposition.

    ``H_oi(ω) = Σ_r c_o·φ_r c_i·φ_r / (ω_r² − ω² + 2iζ_r ω_r ω)`` (receptance), times
    iω (mobility) or −ω² (accelerance).

    Parameters
    ----------
    model : ModalModel
    freq_hz : (n_freq,) array, Hz
    damping_ratio : float or (n_modes,) array
    out_locations : sequence of str, length n_out
    out_angles : (n_out,) array, rad
    in_angles : (n_in,) array, rad      angles of the tread point forces
    form : {"receptance", "mobility", "accelerance"}

    Returns
    -------
    H : (n_out, n_in, n_freq) complex ndarray
        m/N, m/(s·N) or m/(s²·N).
    """
    if form not in FRF_FORMS:
        raise ParameterError(f"form={form!r}; allowed: {', '.join(FRF_FORMS)}")
    w = 2 * np.pi * np.asarray(freq_hz, dtype=float)
    wr = 2 * np.pi * model.freq_hz
    zeta = np.broadcast_to(np.asarray(damping_ratio, dtype=float), wr.shape)
    C_out = np.array([observation(model.dofs, loc, a) for loc, a in zip(out_locations, out_angles)])
    C_in = np.array([observation(model.dofs, "tread", a) for a in np.atleast_1d(in_angles)])
    po = C_out @ model.shapes.T  # (n_out, n_modes)
    pi = C_in @ model.shapes.T  # (n_in, n_modes)
    den = wr[:, None] ** 2 - w[None, :] ** 2 + 2j * zeta[:, None] * wr[:, None] * w[None, :]
    H = np.einsum("or,ir,rf->oif", po, pi, 1.0 / den)
    if form == "mobility":
        H = H * (1j * w)
    elif form == "accelerance":
        H = H * (-(w**2))
    return H
