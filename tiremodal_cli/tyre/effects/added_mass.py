"""A lumped mass on the tread (an accelerometer, a valve, a repair patch).

A point mass m_a at angle θ_a adds kinetic energy ½ m_a u(θ_a)², with
u(θ) = Σ_n U_n^c cos nθ + U_n^s sin nθ. In the generalised coordinates this adds
``m_a ψ_i(θ_a) ψ_j(θ_a)`` to the mass matrix for every pair of tread coordinates
(ψ = cos nθ or sin nθ), coupling all orders. It breaks the axisymmetry: each cos/sin
pair splits, the member with an antinode at θ_a moving down, the one with a node there
staying put.

Residual signature: split pairs in the modal table (two modes of one (n, branch)), the
lower member lowered by about ½ m_a/(π R ρA_eff) relative; no trend otherwise.
Source: Rayleigh's perturbation of degenerate modes; Allaei, Soedel & Yang 1986.
"""

import numpy as np

from tiremodal_cli.tyre.effects import Effect, Param


def _couple(M, K, dofs, v, p):
    M = np.array(M, dtype=float)
    psi = np.zeros(len(dofs))
    for j, (kind, n, harm) in enumerate(dofs):
        if kind == "U":
            psi[j] = np.cos(n * v["theta_a"]) if harm == "cos" else np.sin(n * v["theta_a"])
    M += v["m_a"] * np.outer(psi, psi)
    return M, K


EFFECT = Effect(
    name="added_mass",
    title="lumped mass on the tread (splits the cos/sin pairs)",
    parameters=(Param("m_a", 0.5, 0.0, 20.0, "kg", "lumped mass on the tread"),
                Param("theta_a", 0.0, -2 * np.pi, 2 * np.pi, "rad", "its angle")),
    signature="split pairs: two modes of one (n, branch), the lower lowered",
    couple=_couple,
    kind="coupling",
    reference="Allaei, Soedel & Yang 1986",
    extra={"point_mass": "m_a"},  # a rank-one mass: model.point_mass_pairs solves it fast
    diagnose_free=("m_a",),  # the frequencies do not depend on where the mass sits
)
