"""Air-cavity acoustic mode.

The first acoustic mode of the toroidal cavity is a circumferential standing wave with a
cos θ pressure pattern at about f_c = c / (2π r_c) (c the speed of sound, r_c the
cavity's mean radius; 120–130 Hz for this tyre). Its pressure loads the tread with the
n = 1 pattern, so it couples only to n = 1. It is represented by an equivalent
oscillator coordinate A in each n = 1 harmonic block, with modal mass μ ρA (μ = 0.05
fixed) and a coupling spring κ = γ μ ρA (2π f_c)² to the tread::

    M_AA = μ ρA,   K_AA = μ ρA (2π f_c)²,   K_UA = −κ,   K_UU += κ

so that f_c is the cavity's resonance with the tread held still (the rigid-wall value
c/(2π r_c)); γ < 1 sets how strongly the two exchange energy. The coupled mode appears
near f_c with an n = 1 tread pattern and little sidewall motion; it belongs to no
structural (n, branch), and it pushes the structural n = 1 modes apart.

Residual signature: a measured mode that no structural (n, branch) explains, near f_c,
often duplicating an n = 1 label; structural modes otherwise unaffected (n = 1 slightly).
Source: Sakata, Morimura & Ide 1990; Thompson 1995; Gunda, Gau & Dohrmann 2000.
"""

import numpy as np

from . import Block, Effect, Param

MU = 0.05


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    if np.ndim(n) > 0:  # a stack of orders: n = 1 always comes alone (the block grows)
        if np.any(np.asarray(n) == 1):
            raise ValueError("air_cavity: the n = 1 block must be modified alone")
        return block
    if n != 1:
        return block
    k = len(block.dofs)
    M = np.zeros((k + 1, k + 1))
    K = np.zeros((k + 1, k + 1))
    M[:k, :k] = block.M
    K[:k, :k] = block.K
    ma = MU * p.rhoA
    kappa = v["gamma"] * ma * (2 * np.pi * v["f_cavity_hz"]) ** 2
    iu = block.dofs.index("U")
    M[k, k] = ma
    K[k, k] = ma * (2 * np.pi * v["f_cavity_hz"]) ** 2
    K[iu, iu] += kappa
    K[iu, k] = K[k, iu] = -kappa
    return Block(M, K, block.dofs + ("A",))


EFFECT = Effect(
    name="air_cavity",
    title="air-cavity acoustic mode coupled to n = 1",
    parameters=(Param("f_cavity_hz", 125.0, 50.0, 400.0, "Hz",
                      "first cavity resonance, about c/(2π r_cavity)"),
                Param("gamma", 0.3, 0.0, 0.95, "1",
                      "coupling stiffness relative to the cavity oscillator's stiffness")),
    signature="an extra mode near c/(2π r_cavity) that fits no structural (n, branch)",
    modify_block=_modify,
    kind="acoustic",
    reference="Sakata, Morimura & Ide 1990; Thompson 1995",
)
