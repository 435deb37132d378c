"""A mode at the top of the band, with the next mode just above it (session 33).

The FRFs are written here from the textbook roving-hammer model of an axisymmetric ring
(as ``test_lsce_orthogonal``), not from the package's tyre models: a mode of order n seen
by a sensor at angle θ_s has the residue φ_c cos n(θ_p − θ_s) at point p. The band ends
where the analyser's does (the FRFs stop there); the highest mode inside has its upper
half-power point just under the band's top, and the next order's mode lies just above
it, its flank in the band — the held-out 20-point tests' n = 41 at 1,210 Hz and n = 42
at 1,251 Hz under a 1,250 Hz top.
"""

import numpy as np
import pytest

from tiremodal_cli.modal.lsce import poles_to_modal
from tiremodal_cli.modal.lsfd import lsfd, synthesize
from tiremodal_cli.modal.modes import ModalOptions, estimate_modes
from tiremodal_cli.modal.refine import refine_poles

N_POINTS = 20
ZETA = 0.03
TOP_HZ = 600.0
#: (order, Hz): n = 6's half-power band ends at 599.5 Hz, under the 600 Hz top; n = 7 at
#: 610 Hz is outside the band, a third of a half-width above its top
MODES = [(2, 250.0), (3, 330.0), (4, 420.0), (5, 500.0), (6, 582.0), (7, 610.0), (8, 660.0)]


def _ring_frfs(seed: int):
    """(freq, H (2 channels, N_POINTS, n_freq), angles): accelerance, a tread channel and a
    sidewall channel (half the tread's participation), white noise of 0.5 % of each
    channel's RMS, lines every 0.25 Hz up to the band's top."""
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * np.arange(N_POINTS) / N_POINTS
    f = np.arange(0.0, TOP_HZ + 0.125, 0.25)
    fn = np.array([m[1] for m in MODES])
    s = -ZETA * 2 * np.pi * fn + 1j * 2 * np.pi * fn * np.sqrt(1 - ZETA**2)
    H = np.zeros((2, N_POINTS, f.size), dtype=complex)
    for c, part in enumerate((1.0, 0.5)):
        R = np.array([[part * np.cos(n * th) for n, _ in MODES] for th in theta])
        H[c] = synthesize(f, R * 1e-3, s, form="accelerance")
    rms = np.sqrt(np.mean(np.abs(H) ** 2, axis=(1, 2), keepdims=True))
    H = H + 0.005 * rms / np.sqrt(2) * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    return f, H, theta


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_the_band_top_mode_is_found_and_nothing_beside_it(seed):
    """n = 6 (582 Hz) is reported within 0.3 % in its order group, and no row stands
    between it and the band's top for the n = 7 mode outside the band (which nothing in
    this band locates). Before session 33 the edge check ran on LSCE's unrefined pole:
    582.5–582.6 Hz, its half-power band 0.2 Hz past the top, dropped in seeds 0, 1 and 4
    of 0–5 (refined first, 581.87–582.06 Hz in all six); and where the refinement moved a
    pole, the physical FRFs, in which only the residual terms stood for the flank of n = 7,
    could refuse the move."""
    f, H, theta = _ring_frfs(seed)
    res = estimate_modes(f, H, point_angle=theta, channel_location=["tread", "sidewall"], channel_angle=[0.0, 0.0],
                         form="accelerance", opt=ModalOptions(band_hz=(150.0, TOP_HZ)))
    near = np.flatnonzero(np.abs(res.freq_hz / 582.0 - 1) <= 0.003)
    assert near.size == 1 and res.group[near[0]] == 6, (res.freq_hz, res.group)
    assert not np.any((res.freq_hz > 582.0 * 1.003) & (res.freq_hz <= TOP_HZ)), (res.freq_hz, res.group)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_a_mode_just_above_the_top_does_not_pull_the_one_below(seed):
    """One order group's six rows (one reference): a mode at 480 Hz (ζ 3 %, its refinement
    window reaching 538 Hz) and the group's next mode at 560 Hz, 10 Hz above the band's
    550 Hz top, its flank in the window. Started 0.1 half-width off, the 480 Hz pole is
    refined to within 0.005 half-widths (0.015 %) of the truth and its damping within 1 %:
    the refinement fits a pole beyond the top (``refine.BEYOND_TOP_HALF_WIDTHS``). With the
    two residual terms alone standing for the 560 Hz mode (before session 33) the four seeds
    ended 0.011–0.087 half-widths off (up to +0.26 %), the damping up to 12.5 % high."""
    rng = np.random.default_rng(seed)
    f = np.arange(300.0, 550.0 + 0.125, 0.25)
    s = -0.03 * 2 * np.pi * np.array([480.0, 560.0]) + 1j * 2 * np.pi * np.array([480.0, 560.0]) * np.sqrt(1 - 0.03**2)
    R = (rng.normal(size=(6, 2)) + 1j * rng.normal(size=(6, 2))) * np.abs(s.real)
    H = synthesize(f, R, s)
    rms = np.sqrt(np.mean(np.abs(H) ** 2))
    H = H + 0.01 * rms * (rng.normal(size=H.shape) + 1j * rng.normal(size=H.shape)) / np.sqrt(2)
    s0 = s[:1] + 0.1j * abs(s[0].real)
    f1, z1 = poles_to_modal(refine_poles(f, H, lsfd(f, H, s0).synthesis, s0))
    assert abs(f1[0] - 480.0) / (0.03 * 480.0) < 0.005, f1
    assert abs(z1[0] / 0.03 - 1) < 0.01, z1
