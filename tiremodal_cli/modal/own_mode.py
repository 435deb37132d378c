"""A weak pole of its own order group beside a stronger mode of another, where the orders
mix: a mode, not the stronger one's copy (session 37; :func:`~tiremodal_cli.modal.merge.merge_groups`).

Where the order groups are no complete model of their orders — a complete grid of a
structure that is not symmetric about its sensors (:mod:`~tiremodal_cli.modal.symmetry`),
or is but a lumped mass mixes its orders (:func:`~tiremodal_cli.modal.mixing.order_mixing`)
— a strong mode has a real share in every group. That share is its own pole: a group's fit
places it within the pole's scatter over the model orders. A weak mode of the group itself
is measured against a residual that is mostly misfit there, so neither the visibility rule
nor the swap test can hold it apart: the matrix's sidewall coupling + mass's same-direction
n = 41 and 42 (479.03 Hz in group 7, 0.29 Hz scatter, 2.9 × its best row's residual; 489.70
Hz in group 8, 0.22 Hz, 2.1 ×; each within 0.04 % of the generator's truth) were merged into
the opposite n = 19's members in group 15, 2.4 and 5.7 Hz away (scatter 0.37 and 0.01 Hz).

:func:`own_mode` keeps such a pole apart when the data pin both poles apart, it is its own
group's mode there, and it moves the channels otherwise than the stronger one does — a copy
moves them as its source does, and the two members of a split pair move them alike
(rank one over channel and point, :func:`~tiremodal_cli.modal.merge._other_channel_shape`'s
argument; here short of its MAC under 1/2: a weak same-direction mode beside an opposite one
of another order shares much of its channel pattern).
"""

from __future__ import annotations

import numpy as np

__all__ = ["COPY_CHANNEL_MAC", "channel_shape", "own_mode"]

#: a pole whose channel shape has a MAC at least this high against the stronger mode's may
#: be its copy, or its split partner's (:func:`own_mode`). Measured on the validation
#: matrix's two ring mass cases (session 36's merge, f31fe9d: every cross-group join of two poles
#: pinned apart): the 11 joined copies of a mode or of its pair partner stand at 0.985–1.000
#: (a 12th, at 0.80, in the same-direction crowd under the sidewall resonance: another
#: crowd's copy, merged with a pole of its own alias class), the 3 weak modes of the other
#: branch at 0.33, 0.68 and 0.85.
COPY_CHANNEL_MAC = 0.95


def channel_shape(m, n_channels: int) -> np.ndarray:
    """The pole's shape over the channels: the first left singular vector of its physical
    residues as (n_channels, n_points) (channel-major, as the band's FRFs)."""
    return np.linalg.svd(np.asarray(m.residues).reshape(n_channels, -1), full_matrices=False)[0][:, 0]


def own_mode(found, i: int, j: int, fn, zeta, line_hz: float, n_channels: int) -> bool:
    """Whether ``found[j]`` is a mode of its own beside the stronger ``found[i]`` of another
    group, on mixed orders, however the swap test reads it.

    All of: (a) both pinned — each cluster's frequency scatter over the model orders at most
    a line ``line_hz`` (Hz); (b) more than a line and 3 √(σ_i² + σ_j²) apart (one pole
    estimated in two groups falls within its scatter; within a line the FRFs cannot tell
    them); (c) alone in its group — no stronger pole of its own group within that pole's
    half-power half-width ζ f or a line (else it may be a pole that group's fit of its
    stronger neighbour left beside it: the held-out 36-point ring with an extensible belt and
    a mass held one at 137.10 Hz in group 7, 0.12 Hz scatter on 0.25 Hz lines, 1.3 Hz from
    its group's 100 × stronger same n = 7, at no truth mode); (d) its channel shape's MAC
    against ``found[i]``'s under :data:`COPY_CHANNEL_MAC` (with one channel every MAC is 1:
    the rule says nothing).

    found : sequence of :class:`~tiremodal_cli.modal.merge.GroupMode` ; fn, zeta : (n,)
    their frequencies (Hz) and damping ratios ; n_channels : the channels of the residues.
    """
    a, b = found[i], found[j]
    sa, sb = a.frequency_std_hz, b.frequency_std_hz
    if line_hz <= 0 or n_channels < 2 or max(sa, sb) > line_hz:
        return False
    if abs(fn[i] - fn[j]) <= max(line_hz, 3 * float(np.hypot(sa, sb))):
        return False
    e = np.linalg.norm(b.residues)
    if any(k != j and m.group == b.group and np.linalg.norm(m.residues) > e
           and abs(fn[k] - fn[j]) <= max(zeta[k] * fn[k], line_hz) for k, m in enumerate(found)):
        return False
    u, v = channel_shape(a, n_channels), channel_shape(b, n_channels)
    return abs(np.vdot(u, v)) ** 2 < COPY_CHANNEL_MAC
