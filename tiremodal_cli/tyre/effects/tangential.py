"""Tangential coupling of an inextensible tread.

An inextensible ring ties tangential to radial motion: ∂v/∂θ = −u, so for
u = U cos nθ the tangential displacement is v = −(U/n) sin nθ (n ≥ 1). Its kinetic
energy adds a tangential inertia ρA/n², and a tangential sidewall stiffness k_t acting
on v adds k_t/n², both on the tread coordinate::

    M_UU = ρA (1 + c_t / n²),   K_UU = K_n + k_t / n² + c_t (−T/R² + EI (1 − 2n²)/R⁴)

The last term turns the straight beam's tension and bending stiffness, T n²/R² and
EI n⁴/R⁴, into the inextensible ring's, T (n² − 1)/R² and EI (n² − 1)²/R⁴: with v = −u/n
the geometric stiffness ½T(w'² + v'² − 2w'v/R) averages to ½T (n² − 1)U²/(2R²), and the
curvature change (w'' + w/R²) gives (n² − 1)²; the rigid translation n = 1 has neither
(Soedel 2004, §4.3: the tensioned inextensible ring, ω² = T n²(n² − 1)/(ρA R² (n² + 1))).

``c_t`` (0 … 1) is the participating fraction of the tangential inertia (1 for a fully
inextensible tread). n = 0 is left unchanged (an inextensible ring cannot breathe; the
seed model's n = 0 stands for the extensible limit).

Residual signature: strongest at low n: n = 1, 2 pulled down by the inertia and lifted
by k_t; vanishes as 1/n².
Source: Kung, Soedel & Yang 1986; Huang & Soedel 1987.
"""

import numpy as np

from tiremodal_cli.tyre.effects import Block, Effect, Param


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    n = np.asarray(n, dtype=float)
    inv_n2 = np.divide(1.0, n**2, out=np.zeros_like(n), where=n > 0)  # n = 0 unchanged
    M = np.array(block.M, dtype=float)
    K = np.array(block.K, dtype=float)
    i = block.dofs.index("U")
    M[..., i, i] += p.rhoA * v["c_t"] * inv_n2
    K[..., i, i] += v["k_t"] * inv_n2
    # the inextensible ring's own stiffness: tension T(n² − 1)/R² and bending EI(n² − 1)²/R⁴
    # in place of the straight beam's T n²/R² and EI n⁴/R⁴ (the rigid translation n = 1 has
    # none), in proportion to the share c_t of the tread that moves tangentially
    ring = np.where(n > 0, -p.T / p.R**2 + p.EI * (1.0 - 2.0 * n**2) / p.R**4, 0.0)
    K[..., i, i] += v["c_t"] * ring
    return Block(M, K, block.dofs)


EFFECT = Effect(
    name="tangential",
    title="tangential inertia and stiffness of an inextensible tread ∝ 1/n²",
    parameters=(Param("c_t", 1.0, 0.0, 1.0, "1",
                      "participating fraction of the tangential inertia ρA/n²", upper_is_physical=True),
                Param("k_t", 2.0e6, 0.0, 5.0e7, "N/m²",
                      "tangential sidewall stiffness per length (enters as k_t/n²)")),
    signature="strongest at n = 1, 2, decaying as 1/n²; both branches",
    modify_block=_modify,
    reference="Kung, Soedel & Yang 1986; Huang & Soedel 1987",
)
