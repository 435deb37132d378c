"""Sidewall circumferential (membrane) stiffness, growing with n².

The seed model's sidewall springs are radial and the same for every n. A real sidewall
also resists circumferential stretching and in-plane shear when it deforms into n waves;
like a membrane under tension ``T_s`` wrapped around radius R, this adds a stiffness
per length ``T_s n² / R²`` on the sidewall coordinate::

    K_SS = k_r1 + k_r2 + T_s n² / R²

Residual signature: the seed model underpredicts the same-direction branch increasingly
with n (the branch no longer saturates at √((k_r1 + k_r2)/m_s)/2π) and the
opposite-direction branch a little; low n unaffected.
Source: the ring-on-elastic-foundation literature (Gong 1993; Pinnington 2006).
"""

import numpy as np

from tiremodal_cli.tyre.effects import Block, Effect, Param


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    K = np.array(block.K, dtype=float)
    i = block.dofs.index("S")
    K[..., i, i] += v["T_s"] * np.asarray(n, dtype=float) ** 2 / p.R**2
    return Block(block.M, K, block.dofs)


EFFECT = Effect(
    name="sidewall_membrane",
    title="sidewall circumferential (membrane) stiffness ∝ n²",
    parameters=(Param("T_s", 5.0e3, 0.0, 1.0e6, "N",
                      "sidewall membrane tension: adds T_s n²/R² to the sidewall stiffness"),),
    signature="same-direction branch under-predicted increasingly with n; low n unaffected",
    modify_block=_modify,
    reference="Gong 1993; Pinnington 2006",
)
