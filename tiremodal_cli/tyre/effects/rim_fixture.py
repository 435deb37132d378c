"""A free rim on a flexible fixture: the rim mass and the fixture's stiffness.

The seed model's rim is a rigid body of mass m_w, free (or clamped: m_w → ∞); it moves
only in n = 1. On a test rig the hub sits on a fixture of finite stiffness k_f (N), which
holds the rim's translation: m_w Ẅ = π R k_r2 (S₁ − W) − k_f W. Divided by π R, as the
n = 1 block is (docs/model.md)::

    K_WW = k_r2 + k_f / (π R)

With k_f → 0 the rim is free, with k_f → ∞ clamped. The diagnosis fits k_f together
with the rim mass m_w.

Residual signature: the n = 1 modes only — a low rim mode (the rim bouncing on the
fixture) and the n = 1 tread modes pulled by it; other orders untouched. Needs a free
rim (a rim channel that moves).
Source: the rim/hub boundary condition of tyre modal tests (Kindt et al. 2009; Pinnington 2006).
"""

import numpy as np

from tiremodal_cli.tyre.effects import Block, Effect, Param


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    if "W" not in block.dofs:
        return block
    K = np.array(block.K, dtype=float)
    i = block.dofs.index("W")
    K[..., i, i] += v["k_f"] / (np.pi * p.R)
    return Block(block.M, K, block.dofs)


EFFECT = Effect(
    name="rim_fixture",
    title="a free rim on a fixture of finite stiffness (rim mass and fixture stiffness)",
    parameters=(Param("k_f", 1.0e6, 1.0e3, 1.0e9, "N/m",
                      "translational stiffness of the fixture holding the rim"),),
    signature="n = 1 only: a low rim mode and the n = 1 tread modes",
    modify_block=_modify,
    reference="Kindt, Sas & Desmet 2009; Pinnington 2006",
    extra={"also_free": ("m_w",), "needs_free_rim": True},
)
