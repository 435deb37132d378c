"""Extensional (hoop) stiffness of the belt: what holds the breathing mode n = 0.

The seed model's tread is a beam under tension: its n = 0 (uniform radial) motion is held
only by the foundation k_r1, and the model puts the breathing modes where the foundation
alone would. A real belt (steel cords) resists the hoop strain ε = u / R of that motion:
the membrane energy ½ EA ε² per length adds a stiffness EA / R² to the radial tread
coordinate of n = 0::

    K_UU(n = 0) = k_r1 + EA / R²

For n ≥ 1 a belt this stiff is inextensible (its radial and tangential motion tied,
v = −u / n): that is the ``tangential`` effect, and the two act together (the diagnosis
adopts both when both show). ``EA`` is the belt's membrane stiffness (N), the tread's
Young's modulus times the cord-layer cross-section (10⁶ … 10⁹ N for a truck tyre).

The upper bound, 10⁹ N, is a steel belt's: there EA/R² is some 300 × k_r1 for a truck tyre,
the n = 0 tread motion is held to a few tenths of a per cent and the breathing mode is the
sidewall's own, sqrt((k_r1 + k_r2)/m_s)/2π; a fit that rests on it says "a belt too stiff in
hoop for the modes to tell how stiff".

The cavity air's uniform pressure stiffens the same motion (ρc²b²/A per length, A the
cavity's cross-section): on n = 0 that stiffness and EA/R² are one term, and frequencies
alone cannot tell whose it is — the verdict names the hoop stiffness and says so.

Residual signature: the n = 0 modes (same and opposite) measured far above the model —
a factor of several for a steel belt — the other orders untouched; the base fit sets
them aside, and this effect brings them back.
Source: Soedel, *Vibrations of Shells and Plates* (3rd ed., 2004), §4.3 (the ring's
extensional mode); Kung, Soedel & Yang 1986.
"""

import numpy as np

from tiremodal_cli.tyre.effects import Block, Effect, Param


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    K = np.array(block.K, dtype=float)
    i = block.dofs.index("U")
    zero = np.asarray(n) == 0
    K[..., i, i] += np.where(zero, v["EA"] / p.R**2, 0.0)
    return Block(block.M, K, block.dofs)


EFFECT = Effect(
    name="extensible_belt",
    title="hoop (extensional) stiffness of the belt on the breathing mode n = 0",
    parameters=(Param("EA", 1.0e7, 1.0e4, 1.0e9, "N",
                      "membrane (hoop) stiffness of the belt: adds EA/R² to the n = 0 tread stiffness",
                      upper_is_physical=True),),
    signature="n = 0 measured far above the model; other orders untouched",
    modify_block=_modify,
    reference="Soedel 2004, §4.3; Kung, Soedel & Yang 1986",
)
