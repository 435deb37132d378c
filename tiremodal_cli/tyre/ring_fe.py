"""The finite-element reference tyre's matrices: Timoshenko ring elements (quadratic,
three nodes) with the sidewall, rim, fixture, lumped mass and air-cavity terms,
assembled sparse, and the static condensation of the fields without mass.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from tiremodal_cli.tyre.ring_parameters import FIELDS, RingParameters

__all__ = ['active_fields', 'rim_dofs', 'interp_weights', 'condense', 'reduced_matrices']


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


def active_fields(p: RingParameters) -> tuple[str, ...]:
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


def rim_dofs(p: RingParameters) -> tuple[str, ...]:
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
    fields_ = active_fields(p)
    nf = len(fields_)
    ne = p.n_elements
    nn = 2 * ne
    J = p.R * (2 * np.pi / ne) / 2  # ds/dξ (element length along the tread / 2), m
    fi = {f: i for i, f in enumerate(fields_)}
    rim_names = rim_dofs(p)
    n_dof = nn * nf + len(rim_names)
    rim = {r: nn * nf + i for i, r in enumerate(rim_names)}
    index = {f: np.arange(nn) * nf + fi[f] for f in fields_}
    el = _Element(fields_, J)
    # reduced (2-point) Gauss for membrane and shear, 4-point for everything else
    for npts, terms in ((2, _reduced_terms), (4, _full_terms)):
        xg, wg = np.polynomial.legendre.leggauss(npts)
        N, dN = _shape_functions(xg)
        terms(el, p, el.rows(N), el.rows(dN / J), wg)
    # scatter the (identical) element matrices around the ring
    el_nodes = (2 * np.arange(ne)[:, None] + np.arange(3)[None, :]) % nn  # (ne, 3)
    el_dofs = (el_nodes[:, :, None] * nf + np.arange(nf)[None, None, :]).reshape(ne, -1)
    ii = np.repeat(el_dofs, el.n_dof, axis=1).ravel()
    jj = np.tile(el_dofs, (1, el.n_dof)).ravel()
    K = scipy.sparse.coo_matrix((np.tile(el.K.ravel(), ne), (ii, jj)), shape=(n_dof, n_dof))
    M = scipy.sparse.coo_matrix((np.tile(el.M.ravel(), ne), (ii, jj)), shape=(n_dof, n_dof))
    K, M = K.tocsr(), M.tocsr()
    K = K + _rim_terms(p, index, rim, ne, nf, J, n_dof)
    M = M + _rim_mass(p, rim, n_dof) + _lumped(p, index, nn, n_dof)
    K = K + _fixture(p, rim, n_dof)
    return K.tocsr(), M.tocsr(), index, rim


class _Element:
    """One element's stiffness ``K`` and mass ``M`` (3 nodes × the active fields), built
    term by term: each term a quadrature of coef · a(ξ) c(ξ)ᵀ over the element."""

    def __init__(self, fields_, J):
        self.fields, self.J = tuple(fields_), J
        self.nf = len(self.fields)
        self.n_dof = 3 * self.nf
        self.K = np.zeros((self.n_dof, self.n_dof))
        self.M = np.zeros((self.n_dof, self.n_dof))

    def rows(self, N) -> dict:
        """Row vectors (k, n_dof) of each field's interpolation ``N`` (k, 3); a field that
        is switched off reads as zeros."""
        out = {}
        for i, f in enumerate(FIELDS):
            r = np.zeros((N.shape[0], self.n_dof))
            if f in self.fields:
                r[:, np.arange(3) * self.nf + self.fields.index(f)] = N
            out[f] = r
        return out

    def add(self, which: str, coef, a, w, c=None):
        """K or M (``which``) += Σ_g w_g J coef a_g c_gᵀ (c = a: a square term)."""
        c = a if c is None else c
        mat = self.K if which == "K" else self.M
        mat += np.einsum("g,gi,gj->ij", coef * w * self.J, a, c)


def _reduced_terms(el: _Element, p: RingParameters, V, D, wg):
    """The membrane (hoop) and shear terms, by reduced integration."""
    if p.tangential and p.EA > 0:
        el.add("K", p.EA, D["v"] + V["w"] / p.R, wg)
    elif p.EA > 0:
        el.add("K", p.EA, V["w"] / p.R, wg)
    el.add("K", _shear_stiffness(p), D["w"] - V["v"] / p.R - V["psi"], wg)


def _full_terms(el: _Element, p: RingParameters, V, D, wg):
    """Bending, pre-tension and follower pressure, the tread's inertia, the sidewall and
    the cavity, by full integration."""
    w_, v_, dw, dv = V["w"], V["v"], D["w"], D["v"]
    el.add("K", p.EI, D["psi"], wg)
    # pre-tension and follower pressure: ½ T (w'² + v'² − 2 w' v / R)
    el.add("K", p.T, dw, wg)
    if p.tangential:
        el.add("K", p.T, dv, wg)
        el.add("K", -p.T / p.R, dw, wg, v_)
        el.add("K", -p.T / p.R, v_, wg, dw)
    el.add("M", p.rhoA, w_, wg)
    if p.tangential:
        el.add("M", p.rhoA, v_, wg)
    if p.rhoI > 0:
        el.add("M", p.rhoI, V["psi"], wg)
    if "us" in el.fields:
        _sidewall_terms(el, p, V, D, wg)
    elif p.tangential and p.k_t > 0:
        el.add("K", p.k_t, v_, wg)
    if "xi" in el.fields:
        # cavity: ½ ρ0 c² A (ξ' + b w / A)² and ½ ρ0 A ξ̇², per length of the tread (the
        # annulus' own length 2π R_c is mapped onto the tread's by ds_c = (R_c/R) ds)
        rc = p.cavity_radius / p.R
        A = p.cavity_area
        el.add("K", p.rho_air * p.c_air**2 * A * rc, D["xi"] / rc + p.b * w_ / (A * rc), wg)
        el.add("M", p.rho_air * A * rc, V["xi"], wg)


def _sidewall_terms(el: _Element, p: RingParameters, V, D, wg):
    """The sidewall's radial (and, with its tangential field, tangential) springs and mass."""
    us, v_ = V["us"], V["v"]
    el.add("K", p.k_r1, V["w"] - us, wg)
    el.add("K", p.k_r2, us, wg)  # the rim's share is added per element below
    el.add("M", p.m_s, us, wg)
    if p.sidewall_T > 0:
        el.add("K", p.sidewall_T, D["us"], wg)
    if "vs" in el.fields:
        vs = V["vs"]
        el.add("K", p.k_t1, v_ - vs, wg)
        el.add("K", p.k_t2, vs, wg)
        el.add("M", p.m_s, vs, wg)
        if p.sidewall_EA > 0:
            el.add("K", p.sidewall_EA, D["vs"] + us / p.R, wg)
    elif p.tangential and p.k_t > 0:
        el.add("K", p.k_t, v_, wg)  # tread–rim in series; the rim's share in _rim_terms


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
        c = interp_weights(np.deg2rad(angle_deg), nn)
        for fld in ("w", "v"):
            if fld in index:
                idx = index[fld][c[0]]
                M[np.ix_(idx, idx)] += mass * np.outer(c[1], c[1])
    return M.tocsr()


def interp_weights(angle_rad: float, nn: int):
    """Nodes and quadratic shape-function weights of the tread point at ``angle_rad``."""
    ne = nn // 2
    t = (angle_rad % (2 * np.pi)) / (2 * np.pi) * ne
    e = min(int(np.floor(t)), ne - 1)
    xi = 2 * (t - e) - 1
    N, _ = _shape_functions([xi])
    nodes = np.array([2 * e, 2 * e + 1, 2 * e + 2]) % nn
    return nodes, N[0]


def condense(K, M):
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


def reduced_matrices(p: RingParameters):
    """Assembled system with its massless freedoms condensed; returns dense K, M, the map to
    every freedom, the full sparse M, the field index and the rim freedoms."""
    K, M, index, rim = _assemble(p)
    Kr, Mr, G = condense(K, M)
    return Kr, Mr, G, M, index, rim
