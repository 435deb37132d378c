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

from tiremodal_cli.tyre.effects import Block, Effect, Param

MU = 0.05


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    n = np.asarray(n)
    if n.ndim > 0 and not np.all(n == 1):  # a stack of other orders: unchanged
        if np.any(n == 1):
            raise ValueError("air_cavity: the n = 1 blocks must come in a stack of their own")
        return block
    if n.ndim == 0 and n != 1:
        return block
    # one n = 1 block ((k, k)) or a stack of them ((N, k, k), one parameter set per row)
    k = len(block.dofs)
    Mb, Kb = np.asarray(block.M, dtype=float), np.asarray(block.K, dtype=float)
    M = np.zeros(Mb.shape[:-2] + (k + 1, k + 1))
    K = np.zeros_like(M)
    M[..., :k, :k] = Mb
    K[..., :k, :k] = Kb
    ma = MU * p.rhoA
    w2c = (2 * np.pi * v["f_cavity_hz"]) ** 2
    kappa = v["gamma"] * ma * w2c
    iu = block.dofs.index("U")
    M[..., k, k] = ma
    K[..., k, k] = ma * w2c
    K[..., iu, iu] += kappa
    K[..., iu, k] = -kappa
    K[..., k, iu] = -kappa
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
