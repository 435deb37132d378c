"""Tread shear deformation and rotary inertia (Timoshenko beam).

For a wave number k = n/R, a Timoshenko beam's bending stiffness softens by shear and its
cross-sections add rotary inertia. To first order in the small corrections::

    K_bend = EI k⁴ / (1 + EI k² c_s),    M_UU = ρA + ρI k²

``c_s`` = 1/κGA is the tread's shear compliance (1/N; κGA its shear stiffness), ``rhoI``
the rotary inertia per length (kg·m). The effect is **nested** in the model it extends:
at c_s = 0 (a shear-rigid, Euler–Bernoulli tread) and ρI = 0 both terms vanish and the
blocks are the current model's exactly, so the diagnosis's F-test is a test of nested
models and a parameter that vanishes is the model without that part. (Parametrised by
κGA, the null is κGA → ∞, outside any search range: a fixed κGA of 1e5 N still softened
the bending of the ring's n = 20 by a third at ρI = 0.)

Bounds of c_s: 0 … 1e-2 1/N, κGA ≥ 100 N — softer than any tread: a rubber layer alone of
shear modulus 0.3 MPa, 0.1 m wide, 5 mm thick has κGA = 5/6 · G b h ≈ 1.2e2 N. A value below
1e-6 of that bound (the diagnosis's "vanishes", κGA > 1e8 N) is stiffer in shear than a
solid steel belt 0.35 m × 2 mm (G b h ≈ 5.6e7 N): shear-rigid.

Residual signature: frequencies over-predicted increasingly with n² on both branches.
Source: Timoshenko 1921; the tyre literature's Timoshenko tread models (Pinnington 2006).
"""

import numpy as np

from tiremodal_cli.tyre.effects import Block, Effect, Param


def _modify(n, block: Block, v, p, freq_hz=None) -> Block:
    M = np.array(block.M, dtype=float)
    K = np.array(block.K, dtype=float)
    i = block.dofs.index("U")
    k = np.asarray(n, dtype=float) / p.R
    bend = p.EI * k**4
    K[..., i, i] += bend / (1.0 + p.EI * k**2 * v["c_s"]) - bend
    M[..., i, i] += v["rhoI"] * k**2
    return Block(M, K, block.dofs)


EFFECT = Effect(
    name="timoshenko",
    title="tread shear deformation and rotary inertia (Timoshenko)",
    parameters=(Param("rhoI", 5.0e-3, 0.0, 0.2, "kg·m",
                      "rotary inertia of the tread cross-section per length"),
                Param("c_s", 1.0e-5, 0.0, 1.0e-2, "1/N",
                      "shear compliance 1/κGA of the tread (0: shear-rigid; 1e-5: κGA = 1e5 N)")),
    signature="frequencies over-predicted increasingly with n² on both branches",
    modify_block=_modify,
    reference="Timoshenko 1921; Pinnington 2006",
)
