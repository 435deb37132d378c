"""A mode one sensor sees clearly is kept, though another sensor's response swamps it.

Truth: a tyre-like test built from known modes (receptance of single modes, each with the
pattern cos nθ over 12 impact points, seen by a tread and a sidewall sensor): the modes
are what was put in, whichever sensor carries them.
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.modal.modes import ModalOptions, estimate_modes

# (frequency Hz, order n, tread amplitude, sidewall amplitude): the 70 Hz mode moves the
# sidewall only (the sidewall's own modes, whose tread barely moves), in the same order
# group as a tread mode a hundred times stronger
MODES = [(40.0, 0, 100.0, 0.0), (62.0, 2, 100.0, 0.0), (70.0, 2, 0.0, 1.0), (95.0, 3, 100.0, 0.0)]


def _test_frfs(seed: int):
    rng = np.random.default_rng(seed)
    th = 2 * np.pi * np.arange(12) / 12
    f = np.arange(0, 150, 0.25)
    w = 2 * np.pi * f
    H = np.zeros((2, th.size, f.size), dtype=complex)
    for fr, n, tread, side in MODES:
        wr = 2 * np.pi * fr
        g = 1 / (wr**2 - w**2 + 2j * 0.02 * wr * w)
        H[0] += tread * np.cos(n * th)[:, None] * g
        H[1] += side * np.cos(n * th)[:, None] * g
    for c in range(2):  # 0.5 % noise of each sensor's own level
        H[c] += 0.005 * np.abs(H[c]).mean() * (rng.standard_normal(H[c].shape) + 1j * rng.standard_normal(H[c].shape))
    return f, H, th


@pytest.mark.parametrize("seed", [7, 8])
def test_a_mode_seen_by_one_sensor_only_is_kept(seed):
    """Summed over both sensors the sidewall's 70 Hz mode explains ~4 % of the response in
    its half-power band, in the physical FRFs and in its order group alike (below the 5 %
    share that drops a mode); in the sidewall's FRFs nearly all of it. Every mode put in
    is found within 0.1 % (the 70 Hz one measured at 0.03 %), the 70 Hz one included."""
    f, H, th = _test_frfs(seed)
    res = estimate_modes(f, H, point_angle=th, channel_location=["tread", "sidewall"], form="receptance",
                         opt=ModalOptions(band_hz=(20, 130)))
    assert res.meta["spatial"]
    for fr, *_ in MODES:
        k = np.flatnonzero(np.abs(res.freq_hz / fr - 1) <= 1e-3)
        assert k.size == 1, (fr, res.freq_hz)
    k = int(np.argmin(np.abs(res.freq_hz - 70.0)))
    assert res.significance[k] < 0.05 and res.meta["significance_in_group"][k] < 0.05
