"""Two modes of different circumferential orders at one frequency, on a complete grid of
points round a symmetric ring, are two modes (:func:`tiremodal_cli.modal.merge._both_located`).

The FRFs are written here from the textbook roving-hammer model of an axisymmetric
structure, not from the package's tyre models: a mode of order n seen by a sensor at
angle θ_s has the residue φ_c cos n(θ_p − θ_s) at point p (the member of the degenerate
pair with an antinode at the sensor; the other has a node there). The order groups of
such a test are orthogonal, and a pole found in two of them is two modes.
"""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tiremodal_cli.modal.lsfd import synthesize
from tiremodal_cli.modal.merge import COPY_MAX_AMPLITUDE
from tiremodal_cli.modal.modes import ModalOptions, estimate_modes
from tiremodal_cli.modal.symmetry import antisymmetric_share, mirror_pairs

N_POINTS = 24
ZETA = 0.02
#: (order, Hz): n = 3 and n = 7 lie 0.02 Hz apart, 0.003 of their half-power bandwidth
#: (6 Hz) — under the estimator's bias floor, SAME_POLE_FLOOR_BW
MODES = [(2, 100.0), (3, 150.0), (7, 150.02), (5, 210.0)]


def _ring_frfs(seed: int, modes=MODES, sensor_deg: float = 0.0, split_deg: float | None = None):
    """(freq, H (2 channels, N_POINTS, n_freq), angles) of ``modes`` [(order, Hz)]:
    accelerance, a tread channel and a sidewall channel (half the tread's participation,
    opposite in sign for the third mode) at ``sensor_deg``, white noise of 0.5 % of each
    channel's RMS. ``split_deg``: each mode a pair split by a third of its half-power
    bandwidth, its members' antinodes at ``split_deg`` and a quarter-wave from it (a lumped
    mass there: the symmetry about the sensor broken)."""
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * np.arange(N_POINTS) / N_POINTS
    ts = np.deg2rad(sensor_deg)
    f = np.arange(0.0, 300.0, 0.25)
    fn = np.array([m[1] for m in modes])
    s = -ZETA * 2 * np.pi * fn + 1j * 2 * np.pi * fn * np.sqrt(1 - ZETA**2)
    amp = np.array([1.0, 0.8, 1.0, 0.6])[:len(modes)]
    side = np.array([0.5, 0.5, -0.5, 0.5])[:len(modes)]
    H = np.zeros((2, N_POINTS, f.size), dtype=complex)
    for c, part in enumerate((np.ones(len(modes)), side)):
        if split_deg is None:
            R = np.array([[a * p * np.cos(n * (th - ts)) for (n, _), a, p in zip(modes, amp, part)] for th in theta])
            H[c] = synthesize(f, R * 1e-3, s, form="accelerance")
            continue
        tm = np.deg2rad(split_deg)  # member k: shape cos n(θ − θ_m − kπ/2n) at f (1 − kζ/3)
        s2 = np.concatenate([s, s * (1 - ZETA / 3)])
        R = np.array([[a * p * np.cos(n * (th - tm) - k * np.pi / 2) * np.cos(n * (ts - tm) - k * np.pi / 2)
                       for k in (0, 1) for (n, _), a, p in zip(modes, amp, part)] for th in theta])
        H[c] = synthesize(f, R * 1e-3, s2, form="accelerance")
    rms = np.sqrt(np.mean(np.abs(H) ** 2, axis=(1, 2), keepdims=True))
    H = H + 0.005 * rms / np.sqrt(2) * (rng.standard_normal(H.shape) + 1j * rng.standard_normal(H.shape))
    return f, H, theta


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_two_orders_at_one_frequency_are_two_modes(seed):
    """Both 150 Hz modes are reported, each in its own order group, within 0.1 % (until
    session 16 the bias floor merged them into one mode of two groups)."""
    f, H, theta = _ring_frfs(seed)
    res = estimate_modes(f, H, point_angle=theta, channel_location=["tread", "sidewall"], channel_angle=[0.0, 0.0],
                         form="accelerance", opt=ModalOptions(band_hz=(40.0, 280.0), max_order=30))
    near = np.flatnonzero(np.abs(res.freq_hz - 150.0) < 1.5)
    assert sorted(res.group[near].tolist()) == [3, 7], (res.freq_hz, res.group)
    for k in near:
        want = dict((n, fr) for n, fr in MODES)[int(res.group[k])]
        assert_allclose(res.freq_hz[k], want, rtol=1e-3)
    assert res.freq_hz.size == len(MODES), res.freq_hz


@pytest.mark.parametrize("seed", [0, 1])
def test_a_lone_mode_is_not_split_into_groups(seed):
    """The orthogonality rule adds no mode where there is one: the same ring with only
    n = 3 at 150 Hz gives one mode there (in group 3)."""
    f, H, theta = _ring_frfs(seed, modes=[(2, 100.0), (3, 150.0), (5, 210.0)])
    res = estimate_modes(f, H, point_angle=theta, channel_location=["tread", "sidewall"], channel_angle=[0.0, 0.0],
                         form="accelerance", opt=ModalOptions(band_hz=(40.0, 280.0), max_order=30))
    near = np.flatnonzero(np.abs(res.freq_hz - 150.0) < 1.5)
    assert res.group[near].tolist() == [3], (res.freq_hz, res.group)


def test_points_mirrored_about_a_sensor():
    """24 points: a sensor on a point has 11 mirrored pairs (that point and the opposite one
    have none), one midway between points has 12, one 7° off the grid none."""
    theta = 2 * np.pi * np.arange(N_POINTS) / N_POINTS
    assert len(mirror_pairs(theta, 0.0, 1e-6)) == 11
    assert len(mirror_pairs(theta, np.pi / N_POINTS, 1e-6)) == 12
    assert mirror_pairs(theta, np.deg2rad(7.0), 1e-6) == []


@pytest.mark.parametrize("seed", [0, 1])
def test_antisymmetric_share_sees_a_broken_symmetry_not_the_noise(seed):
    """The symmetric ring's mirrored FRFs differ by their noise alone: share under a
    hundredth. With each mode a pair split by a third of its bandwidth and oriented at 30°
    (a mass there), the share is above the copy limit and the merge is left as it was."""
    f, H, theta = _ring_frfs(seed)
    sym = antisymmetric_share(f, H, theta, [0.0, 0.0])
    assert sym is not None and sym < 0.01
    f, H, theta = _ring_frfs(seed, split_deg=30.0)
    assert antisymmetric_share(f, H, theta, [0.0, 0.0]) > COPY_MAX_AMPLITUDE
    assert antisymmetric_share(f, H, theta, [np.deg2rad(7.0)] * 2) is None


def _group_mode(f_hz, group, amp, std_hz, accepts_any):
    from tiremodal_cli.modal.merge import GroupMode
    z = 0.03
    pole = 2 * np.pi * f_hz * (-z + 1j * np.sqrt(1 - z * z))
    return GroupMode(pole=pole, group=group, residues=amp * np.ones(6, complex), significance=0.3,
                     frequency_std_hz=std_hz, swap_cost=(lambda s: 0.0) if accepts_any else (lambda s: 1e3),
                     significance_in_group=0.9, group_noise=1e-3, peak=amp, visibility=50.0)


def test_a_located_mode_is_not_merged_into_an_unlocated_blend_of_another_order():
    """The matrix's 24-point paper test at 2,560 Hz: group 1 holds the opposite n = 47 and 49
    (834 and 852 Hz, one pole for both: a crowd, scattered by 4.5 Hz over the model orders),
    group 0 the opposite n = 48 at 843.6 Hz, pinned (0.35 Hz), visible, 43 % of the blend's
    energy. On a complete grid of a symmetric structure a copy holds a few thousandths of its
    source's energy (``COPY_MAX_AMPLITUDE``): n = 48 is its own mode, though the blend's
    broad pole lets its group's data accept any pole near it (the swap test merged them, and
    n = 48 was lost). Where the stronger pole is pinned and the weaker one wanders within 3 ×
    its scatter of it, the swap test still decides (a wandering pole beside a located one may
    be its copy); one that wanders less than a third of its distance is located apart (session
    28, ``merge._both_located``)."""
    from tiremodal_cli.modal.merge import merge_groups
    blend = _group_mode(837.15, 1, 1.0, 4.48, accepts_any=True)
    own = _group_mode(843.64, 0, np.sqrt(0.43), 0.35, accepts_any=False)
    out = merge_groups([blend, own], line_hz=0.5, orthogonal=True)
    assert len(out) == 2
    assert len(merge_groups([blend, own], line_hz=0.5, orthogonal=False)) == 1
    pinned = _group_mode(837.15, 1, 1.0, 0.3, accepts_any=True)
    wanders = _group_mode(843.64, 0, np.sqrt(0.43), 2.5, accepts_any=True)  # 6.5 Hz < 3 × 2.5 Hz
    assert len(merge_groups([pinned, wanders], line_hz=0.5, orthogonal=True)) == 1
    apart = _group_mode(843.64, 0, np.sqrt(0.43), 2.0, accepts_any=True)  # 6.5 Hz > 3 × 2.0 Hz
    assert len(merge_groups([pinned, apart], line_hz=0.5, orthogonal=True)) == 2


def test_a_pole_without_a_peak_of_its_own_is_the_stronger_modes_copy():
    """The matrix's held-out ring with a lumped mass (seed + 1000): the opposite n = 20 at
    508.6 Hz (group 14) shows in group 1 as a pole at 505.7 Hz — 0.5 % low, its peak 1.7 ×
    the residual RMS of the row that shows it best, scattered 2.3 Hz over the model orders —
    whose group's data reject the stronger pole (swap cost 11.5 against 6.9). Neither on a
    peak of its own (under ``PEAK_OVER_NOISE``) nor pinned by its data (scatter over a
    line), nothing tells it from the stronger mode's copy: one mode (session 31). The same
    pole on a peak of its own, or pinned within a line (the sidewall coupling + mass's
    same n = 43 at 499.82 Hz: 2.7 × its row's residual, 0.05 Hz scatter, beside the
    opposite n = 20 of group 14), stays for the swap test to judge, which keeps it apart."""
    import dataclasses

    from tiremodal_cli.modal.groupfit import PEAK_OVER_NOISE
    from tiremodal_cli.modal.merge import merge_groups
    strong = _group_mode(508.59, 14, 1.0, 0.3, accepts_any=False)
    weak = dataclasses.replace(_group_mode(505.67, 1, 0.067, 2.26, accepts_any=False), visibility=1.7)
    assert weak.visibility < PEAK_OVER_NOISE
    assert len(merge_groups([strong, weak], line_hz=0.5)) == 1
    assert len(merge_groups([strong, dataclasses.replace(weak, visibility=5.0)], line_hz=0.5)) == 2
    assert len(merge_groups([strong, dataclasses.replace(weak, frequency_std_hz=0.05)], line_hz=0.5)) == 2


def test_on_mixed_orders_a_pinned_pole_of_its_own_group_is_not_a_copy():
    """The matrix's sidewall coupling + mass: the same n = 42 at 489.70 Hz in group 8 (truth
    489.52 Hz), 0.22 Hz scatter over the model orders, 2.1 × its best row's residual — a
    residual that is mostly misfit where the mass mixes the orders (off the sensors' plane:
    no symmetry about it), so its group's data accept any pole near it — beside the
    opposite n = 19's member at 483.99 Hz in group 15 (0.01 Hz scatter, 1,100 × its energy),
    whose channels it moves otherwise (sidewall-led; MAC 0.68). A strong mode's share in
    another group is its own pole, placed there within its scatter: on mixed orders two
    poles pinned 5.7 Hz apart are two modes (session 37, ``modal.own_mode``). Each condition
    is needed: on unmixed orders the weaker must still be visible (a free rim's pinned leak
    3.8 Hz above the opposite n = 18, 1.6 × its group's residual); a weaker pole that wanders
    over the orders, lies within a line of the stronger, moves the channels as it does (a
    copy of its split partner, MAC 0.985–1.000 on the matrix) or has a stronger pole of its
    own group within its half-power half-width (the held-out 36-point ring with a mass: a
    pinned pole 1.3 Hz from its group's 100 × stronger n = 7, no mode) is still the swap
    test's to merge; with one channel the rule says nothing."""
    import dataclasses

    from tiremodal_cli.modal.groupfit import PEAK_OVER_NOISE
    from tiremodal_cli.modal.merge import merge_groups

    def channels(m, tread, sidewall):  # 2 channels × 3 points, channel-major
        return dataclasses.replace(m, residues=np.outer([tread, sidewall], [1.0, -0.5, -0.5]).astype(complex).ravel())

    strong = dataclasses.replace(channels(_group_mode(483.99, 15, 1.0, 0.01, accepts_any=True), 1.0, 0.6),
                                 visibility=117.0)
    weak = dataclasses.replace(channels(_group_mode(489.70, 8, 0.03, 0.22, accepts_any=True), 0.012, 0.03),
                               visibility=2.1, significance=0.018)
    assert weak.visibility < PEAK_OVER_NOISE

    def n_modes(*modes, mixed=True, n_channels=2):
        return len(merge_groups(list(modes), line_hz=0.5, mixed=mixed, n_channels=n_channels))

    assert n_modes(strong, weak) == 2
    assert n_modes(strong, weak, mixed=False) == 1
    assert n_modes(strong, weak, n_channels=1) == 1
    assert n_modes(strong, dataclasses.replace(weak, frequency_std_hz=0.8)) == 1  # wanders over a line
    assert n_modes(strong, channels(weak, 0.03, 0.018)) == 1  # the stronger one's channel shape: a copy
    near = dataclasses.replace(weak, pole=weak.pole * 484.40 / 489.70)  # 0.41 Hz: within a line
    assert n_modes(strong, near) == 1
    own = channels(_group_mode(490.50, 8, 0.5, 0.01, accepts_any=True), 0.4, 1.0)  # its group's, 0.8 Hz away
    assert n_modes(strong, weak, own) == 2
    assert n_modes(strong, weak, dataclasses.replace(own, pole=own.pole * 1.05)) == 3  # 25 Hz: outside ζ f
