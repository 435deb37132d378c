"""Frequency-dependent (viscoelastic) stiffness of the rubber springs.

Filled rubber stiffens with frequency, close to a power law over a decade or two. The
sidewall springs then read::

    k_r1(f) = k_r1 (f / f_ref)^β,   k_r2(f) = k_r2 (f / f_ref)^β,   f_ref = 100 Hz

with f the frequency of the mode itself (the eigenproblem is solved by fixed-point
iteration on f). β = 0 is the seed model.

Residual signature: modes below f_ref over-predicted and modes above under-predicted by
the seed model, on both branches; a trend with frequency rather than with n.
Source: Nashif, Jones & Henderson, Vibration Damping (1985); Pinnington 2006.
"""

import numpy as np

from tiremodal_cli.tyre.effects import Block, Effect, Param

F_REF_HZ = 100.0


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    if freq_hz is None or np.all(np.asarray(v["beta"]) == 0.0):  # β may be one per stacked block
        return block
    scale = (np.maximum(freq_hz, 1e-3) / F_REF_HZ) ** v["beta"] - 1.0
    K = np.array(block.K, dtype=float)
    iu, is_ = block.dofs.index("U"), block.dofs.index("S")
    d1, d2 = p.k_r1 * scale, p.k_r2 * scale
    K[..., iu, iu] += d1
    K[..., iu, is_] -= d1
    K[..., is_, iu] -= d1
    K[..., is_, is_] += d1 + d2
    if "W" in block.dofs:
        iw = block.dofs.index("W")
        K[..., is_, iw] -= d2
        K[..., iw, is_] -= d2
        K[..., iw, iw] += d2
    return Block(block.M, K, block.dofs)


EFFECT = Effect(
    name="viscoelastic",
    title="frequency-dependent rubber stiffness k(f) = k (f/100 Hz)^β",
    parameters=(Param("beta", 0.08, 0.0, 0.5, "1",
                      "power-law exponent of the rubber springs' stiffness with frequency"),),
    signature="a trend with frequency on both branches: low modes over-, high modes under-predicted",
    modify_block=_modify,
    frequency_dependent=True,
    reference="Nashif, Jones & Henderson 1985; Pinnington 2006",
)
