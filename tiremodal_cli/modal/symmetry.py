"""Does the test show a structure symmetric about its sensors? The FRFs at points mirrored
about each sensor's angle, compared.

A structure with a plane of symmetry through a sensor gives that sensor the same FRF from
two points mirrored about it (reciprocity and the symmetry): H(θ_s + δ) = H(θ_s − δ). An
axisymmetric tyre has every such plane. A lumped mass (a valve, a balance weight), a
splice, any asymmetry off the sensor's plane, puts into the FRFs an antisymmetric part
D = H(θ_s + δ) − H(θ_s − δ) beside the symmetric S = H(θ_s + δ) + H(θ_s − δ), and mixes
the circumferential orders of each mode: a mode shows a copy of itself in other order
groups. :func:`antisymmetric_share` measures the antisymmetric part above the noise; the
merge keeps apart two located poles of different groups only when it is small
(:data:`~tiremodal_cli.modal.merge.COPY_MAX_AMPLITUDE`, :func:`~tiremodal_cli.modal.merge.merge_groups`).

Blind spot: an asymmetry in the sensor's own plane (a mass at the sensor's angle, or
opposite it) keeps that plane's symmetry and is not seen; nor is anything with one sensor
angle whose points have no mirror images (a sensor neither on a point nor midway between
two) — then nothing is measured and the answer is None.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mirror_pairs", "antisymmetric_share"]


def mirror_pairs(point_angle, sensor_angle: float, tol_rad: float) -> list[tuple[int, int]]:
    """Pairs (i, j), i < j, of points mirrored about ``sensor_angle`` (rad): θ_i − θ_s ≡
    −(θ_j − θ_s) within ``tol_rad``; a point on the sensor's plane has no partner."""
    rel = np.angle(np.exp(1j * (np.asarray(point_angle, dtype=float) - sensor_angle)))
    out = []
    for i, r in enumerate(rel):
        if abs(r) <= tol_rad or abs(abs(r) - np.pi) <= tol_rad:
            continue
        d = np.abs(np.angle(np.exp(1j * (rel + r))))
        j = int(np.argmin(d))
        if d[j] <= tol_rad and i < j:
            out.append((i, j))
    return out


def _noise_gain(exp_tau_s, line_hz: float) -> float:
    """E|Δ²x|² / σ² for the noise of an FRF estimate (second differences over lines): 6 for
    independent lines; with an exponential window of time constant τ on the response the
    lines' noise is correlated, ρ(m) = a / (a + i 2π m Δf), a = 2/τ (the window's power
    e^{−2t/τ} over one record, T = 1/Δf), and the gain is 6 − 8 Re ρ(1) + 2 Re ρ(2)."""
    if not exp_tau_s or not np.isfinite(exp_tau_s):
        return 6.0
    a = 2.0 / float(exp_tau_s)
    rho = [(a / (a + 2j * np.pi * m * line_hz)).real for m in (1, 2)]
    return 6.0 - 8.0 * rho[0] + 2.0 * rho[1]


def antisymmetric_share(freq_hz, H, point_angle, channel_angle, exp_tau_s=None, tol_rad: float = 1e-3):
    """The largest, over the sensors, antisymmetric part of the FRFs about the sensor's plane,
    as an amplitude share of the symmetric part, above the noise; None when no sensor has
    mirrored points.

    For each channel c with mirror pairs, a_c² = (⟨|D|²⟩ − σ_D²) / ⟨|S|²⟩ over the band's
    lines and pairs, σ_D² the noise power of D per line from its second differences over
    frequency (:func:`_noise_gain`; a modal response is smooth over a line, white noise is
    not). Noise alone gives a ≈ 0 (measured on the validation matrix's noisy cases: the
    noise-normalised power 0.5–1.2).

    Parameters
    ----------
    freq_hz : (K,) Hz ; H : (n_channels, n_points, K) complex, the band's FRFs
    point_angle : (n_points,) rad ; channel_angle : (n_channels,) rad
    exp_tau_s : float or None, the response's exponential window

    Returns
    -------
    float or None
    """
    freq_hz = np.asarray(freq_hz, dtype=float)
    if freq_hz.size < 8:
        return None
    gain = _noise_gain(exp_tau_s, float(freq_hz[1] - freq_hz[0]))
    best = None
    for c in range(H.shape[0]):
        pairs = mirror_pairs(point_angle, float(channel_angle[c]), tol_rad)
        if not pairs:
            continue
        i, j = (np.array(x) for x in zip(*pairs))
        D, S = H[c, i] - H[c, j], H[c, i] + H[c, j]
        noise = np.mean(np.abs(np.diff(D, 2, axis=1)) ** 2) / gain
        a2 = max(0.0, float(np.mean(np.abs(D) ** 2)) - noise) / max(float(np.mean(np.abs(S) ** 2)), np.finfo(float).tiny)
        best = max(best or 0.0, float(np.sqrt(a2)))
    return best
