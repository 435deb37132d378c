"""A closed-form first estimate of the base model's stiffnesses from measured modes.

For every order whose block is 2 × 2 (n ≠ 1; n = 1 too when the rim is clamped; docs/model.md:
M = diag(ρA, m_s), K_n = [[a_n + k_r1, −k_r1], [−k_r1, k_r1 + k_r2]], a_n = EI n⁴/R⁴ + T n²/R²)
the two roots λ = ω² of det(K_n − λM) = 0 have the sum and product (trace and determinant
of M⁻¹K_n)

    λ_same + λ_opposite = (a_n + k_r1)/ρA + (k_r1 + k_r2)/m_s,
    λ_same · λ_opposite · ρA m_s = a_n (k_r1 + k_r2) + k_r1 k_r2.

With ρA, m_s, T and R known, the sum is linear in (EI, c), c = k_r1/ρA + (k_r1 + k_r2)/m_s
(the k's enter every order's sum in that one combination); with EI known, the product is
linear in (s, p) = (k_r1 + k_r2, k_r1 k_r2). So, over the orders measured on both branches,
two weighted linear least-squares solves — (EI, c) from the sums, then (s, p) from the
products — and k_r1 = ρA (c − s/m_s), k_r2 = s − k_r1. Each order's equation is weighted by
the inverse of its uncertainty (from the fit's relative-error weights: the sum's
2 √(Σ λ² σ_rel²), the product's P · 2 √(Σ σ_rel²)). p is left as a check: it is not needed.

It is a *start*: ``identify``'s base fit takes it as the warm start of the local search
(least squares, safeguarded by a short evolutionary search) instead of a full evolutionary
search over the bounds. When it does not apply — another parameter is free, fewer than
three orders measured on both branches, a rank-deficient system, or a non-positive
stiffness — it returns None and the fit runs the full search; it never stands in for a fit.

References
----------
Soedel, W. (2004), *Vibrations of Shells and Plates*, 3rd ed. (two-degree-of-freedom
pencils: the trace and determinant of M⁻¹K); the paper's Eqs. (16)/(17) fit the same sum
and difference of ω² (docs/model.md).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from tiremodal_cli.tyre.model import TyreParameters

__all__ = ["CLOSED_FORM_FREE", "first_estimate"]

#: The free parameters the closed form estimates (the base fit's default).
CLOSED_FORM_FREE = ("k_r1", "k_r2", "EI")


def first_estimate(modes, base: TyreParameters, free=CLOSED_FORM_FREE, *, weights=None) -> dict | None:
    """EI, k_r1, k_r2 in closed form from measured modes, or None where it does not apply.

    Parameters
    ----------
    modes : sequence of MeasuredMode (n, branch, frequency_hz)
    base : TyreParameters — ρA, m_s, R, P0, b (known); ``m_w`` None means a clamped rim
        (n = 1 is then a 2 × 2 order)
    free : the parameters to estimate; anything but {k_r1, k_r2, EI} → None
    weights : (n_modes,) the fit's weights of the relative frequency errors (1 if None);
        a mode's relative uncertainty is taken as their inverse

    Returns
    -------
    {"k_r1": N/m², "k_r2": N/m², "EI": N·m²} or None
    """
    if set(free) != set(CLOSED_FORM_FREE):
        return None
    w_fit = np.ones(len(modes)) if weights is None else np.asarray(weights, dtype=float)
    by_order: dict[int, dict[str, list]] = {}
    for m, w in zip(modes, w_fit):
        if m.branch in ("same", "opposite") and m.frequency_hz > 0 and w > 0 and (m.n != 1 or base.m_w is None):
            by_order.setdefault(int(m.n), {"same": [], "opposite": []})[m.branch].append(
                ((2 * np.pi * m.frequency_hz) ** 2, 1 / w))
    lam, rel, n = [], [], []
    for order, br in sorted(by_order.items()):
        if br["same"] and br["opposite"]:
            # a split pair's two members: their mean λ, its relative uncertainty / √2
            lam.append([np.mean([x[0] for x in br[b]]) for b in ("same", "opposite")])
            rel.append([np.sqrt(np.mean([x[1] ** 2 for x in br[b]]) / len(br[b])) for b in ("same", "opposite")])
            n.append(order)
    if len(n) < 3:
        return None
    lam, rel, n = np.array(lam), np.array(rel), np.array(n, dtype=float)
    rA, ms = base.rhoA, base.m_s
    q, t = n**4 / base.R**4, base.T * n**2 / base.R**2
    # (EI, c) from the sums
    sig = 2 * np.sqrt(np.sum((lam * rel) ** 2, axis=1))
    sol = _wlstsq(np.column_stack([q / rA, np.ones_like(q)]), lam.sum(axis=1) - t / rA, sig)
    if sol is None or not sol[0] > 0:
        return None
    EI, c = sol
    # (s, p) from the products, with a_n from EI
    P = lam.prod(axis=1) * rA * ms
    sol = _wlstsq(np.column_stack([EI * q + t, np.ones_like(q)]), P, P * 2 * np.sqrt(np.sum(rel**2, axis=1)))
    if sol is None:
        return None
    k1 = rA * (c - sol[0] / ms)
    k2 = sol[0] - k1
    if not (k1 > 0 and k2 > 0):
        return None
    return {"k_r1": float(k1), "k_r2": float(k2), "EI": float(EI)}


def _wlstsq(A, y, sigma):
    """Weighted least squares A x ≈ y (rows weighted 1/σ, columns scaled); None if rank deficient."""
    Aw = A / sigma[:, None]
    scale = np.linalg.norm(Aw, axis=0)
    if not np.all(scale > 0):
        return None
    x, _, rank, _ = scipy.linalg.lstsq(Aw / scale, y / sigma)
    return None if rank < A.shape[1] else x / scale
