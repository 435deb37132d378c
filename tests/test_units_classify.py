"""Direct tests of the tyre classification of modes (:mod:`tiremodal_cli.modal.classify`).

Truths used: a tread shape cos n(θ − φ) has circumferential order n (any phase, any complex
scaling); a sidewall moving with the tread (positive real ratio) is the in-phase branch,
against it (negative ratio) the anti-phase one; on N equally spaced points order n and
N − n take the same values (sampling theory) and within a branch the frequencies rise with
n (the ring's dispersion), which is what tells an alias; two modes of one (n, branch) a few
per cent apart are a split cos/sin pair; a mode is in a crowd when another order aliasing
onto it lies within its half-power bandwidth 2ζf on the branch's dispersion curve (the
module's documented definition).
"""

from __future__ import annotations

import numpy as np
import pytest

from tiremodal_cli.modal.classify import classify, order_energy

LOCS = ("tread", "sidewall")


def _grid(n_p, offset=0.0):
    return offset + 2 * np.pi * np.arange(n_p) / n_p


def _shapes(th, modes, rng=None):
    """(n_modes, 2, n_p) residues: tread c·cos n(θ − φ), sidewall ratio × tread."""
    S = np.zeros((len(modes), 2, th.size), complex)
    for r, (n, ratio) in enumerate(modes):
        phi = 0.0 if rng is None else rng.uniform(0, np.pi)
        c = 1.0 if rng is None else np.exp(1j * rng.uniform(-np.pi, np.pi)) * rng.uniform(0.5, 2)
        S[r, 0] = c * np.cos(n * (th - phi))
        S[r, 1] = ratio * S[r, 0]
    return S


@pytest.mark.parametrize("n", [0, 1, 2, 3, 4, 5])
def test_order_from_the_shape_any_phase_and_complex_scale(n):
    rng = np.random.default_rng(30 + n)
    th = _grid(12, offset=0.2)
    S = _shapes(th, [(n, 0.7)], rng)
    (c,) = classify([100.0], S, th, LOCS)
    assert c.n == c.n_spatial == n and not c.aliased
    assert c.n_confidence == pytest.approx(1.0, abs=1e-9)


def test_order_energy_of_a_mixture_is_its_power_split():
    """a·cos 2θ + b·sin 5θ on a uniform grid: energy shares a²/(a²+b²), b²/(a²+b²)."""
    th = _grid(16)
    a, b = 2.0, 1.0
    e = order_energy(a * np.cos(2 * th) + b * np.sin(5 * th), th)
    assert e[2] == pytest.approx(a**2 / (a**2 + b**2), abs=1e-12)
    assert e[5] == pytest.approx(b**2 / (a**2 + b**2), abs=1e-12)
    assert sum(v for k, v in e.items() if k not in (2, 5)) < 1e-12


def test_in_phase_sidewall_is_same_out_of_phase_is_opposite():
    rng = np.random.default_rng(1)
    th = _grid(12)
    modes = [(2, 0.8), (2, -0.8), (3, 2.5), (3, -0.3)]
    res = classify([50.0, 120.0, 70.0, 160.0], _shapes(th, modes, rng), th, LOCS)
    assert [c.branch for c in res] == ["same", "opposite", "same", "opposite"]
    assert all(c.branch_confidence == pytest.approx(1.0, abs=1e-9) for c in res)


def test_branch_confidence_falls_as_the_sidewall_goes_in_quadrature():
    """|Re ρ|/(‖t‖‖s‖) with s = e^{iα} t is |cos α|: 1 in or out of phase, 0 in quadrature."""
    th = _grid(12)
    for alpha in (0.0, 0.5, 1.0, 2.0, 3.0):
        S = _shapes(th, [(3, 1.0)])
        S[0, 1] = np.exp(1j * alpha) * S[0, 0]
        (c,) = classify([80.0], S, th, LOCS)
        assert c.branch_confidence == pytest.approx(abs(np.cos(alpha)), abs=1e-9)
        assert c.branch == ("same" if np.cos(alpha) >= 0 else "opposite")


def test_no_sidewall_sensor_no_branch():
    th = _grid(12)
    S = _shapes(th, [(2, 1.0)])[:, :1]
    (c,) = classify([40.0], S, th, ("tread",))
    assert c.branch is None and c.n == 2


def test_orders_above_the_grid_are_unfolded_by_the_branch_dispersion():
    """8 points: n = 5, 6 look like 3, 2. Within the in-phase branch the orders 1…4 have
    been passed at lower frequencies, so these are the aliases 8 − 3 = 5 and 8 − 2 = 6."""
    th = _grid(8)
    true_n = [1, 2, 3, 4, 5, 6]
    f = [60.0, 80.0, 100.0, 120.0, 140.0, 160.0]
    S = _shapes(th, [(n, 0.5) for n in true_n])
    res = classify(f, S, th, LOCS)
    assert [c.n for c in res] == true_n
    assert [c.n_spatial for c in res] == [1, 2, 3, 4, 3, 2]
    assert [c.aliased for c in res] == [False] * 4 + [True] * 2
    assert all(c.in_order for c in res)


def test_no_unfolding_before_the_branch_reaches_the_grid_top():
    """The same spatial orders with the branch stopping at n = 2: nothing is aliased
    (aliasing can only start once ⌊N/2⌋ − 1 has been passed)."""
    th = _grid(12)
    S = _shapes(th, [(1, 0.5), (2, 0.5), (1, -0.5)])
    res = classify([60.0, 80.0, 200.0], S, th, LOCS)
    assert [c.n for c in res] == [1, 2, 1] and not any(c.aliased for c in res)


def test_a_mode_out_of_dispersion_order_is_flagged():
    """Same branch: n = 4 at 60 Hz below n = 3 at 70 Hz (equal significance) contradicts
    a rising dispersion; the n = 4 mode is the misread."""
    th = _grid(12)
    S = _shapes(th, [(2, 0.5), (4, 0.5), (3, 0.5)])
    res = classify([50.0, 60.0, 70.0], S, th, LOCS)
    assert [c.n for c in res] == [2, 4, 3]
    assert [c.in_order for c in res] == [True, False, True]


def test_split_pair_is_paired_with_its_splitting():
    th = _grid(12)
    S = _shapes(th, [(3, 0.5), (3, 0.5), (3, -0.5), (4, 0.5)])
    f = [100.0, 102.0, 150.0, 130.0]
    res = classify(f, S, th, LOCS)
    assert res[0].pair == res[1].pair == 0
    assert res[0].splitting_hz == pytest.approx(2.0) and res[1].splitting_hz == pytest.approx(2.0)
    assert res[2].pair is None and res[3].pair is None  # other branch / other order


def test_same_order_and_branch_far_apart_is_not_a_pair():
    th = _grid(12)
    S = _shapes(th, [(3, 0.5), (3, 0.5)])
    res = classify([100.0, 110.0], S, th, LOCS)  # 10 % apart > 5 %
    assert res[0].pair is None and res[1].pair is None


def test_crowd_when_an_alias_order_falls_in_the_half_power_band():
    """8 points; the in-phase branch flattens: f(1…4) = 100, 150, 170, 175 Hz, continued
    with the last slope, 5 Hz per order. The n = 3 mode's alias 8 − 3 = 5 lies at 180 Hz,
    10 Hz away: inside 2ζf = 17 Hz at ζ = 0.05 (a crowd of candidates (3, 5)), outside
    3.4 Hz at ζ = 0.01 (no crowd)."""
    th = _grid(8)
    S = _shapes(th, [(1, 0.5), (2, 0.5), (3, 0.5), (4, 0.5)])
    f = [100.0, 150.0, 170.0, 175.0]
    wide = classify(f, S, th, LOCS, damping_ratio=[0.05] * 4)
    assert [c.crowd for c in wide] == [False, False, True, False]
    assert wide[2].n_candidates == (3, 5)
    assert wide[2].n_confidence == pytest.approx(0.5, abs=1e-9)  # one of two candidates
    assert wide[2].aliased  # a candidate above the grid's top order
    narrow = classify(f, S, th, LOCS, damping_ratio=[0.01] * 4)
    assert not any(c.crowd for c in narrow)
    assert narrow[2].n_confidence == pytest.approx(1.0, abs=1e-9)


def test_an_alias_out_of_order_does_not_flatten_the_dispersion():
    """12 points; the anti-phase branch n = 0 … 6 at 100 … 235 Hz (ζ = 0.02), and one more
    order-1 pattern at 130 Hz (an air-cavity mode: n = 1 is held at 110 Hz; its alias 11
    would make the branch fall below n = 3 at 145 Hz, so it keeps n = 1, out of the branch's
    order). The branch's dispersion is the measured
    orders': continued from n = 5 → 6 (35 Hz per order), the top mode's alias 12 + 6 = 18
    lies ~420 Hz above it, far outside 2ζf = 9.4 Hz — no crowd. Taking the 130 Hz mode's
    inferred order 11 as a point of the curve flattened it at 235 Hz from n = 6 to 11 (a
    branch's f(n) is made to rise) and put n = 18 inside the band (a false crowd: the
    ring's 1,024 Hz combination with failed points read its opposite n = 15 so, behind
    the cavity's n = 2 given the alias 38)."""
    th = _grid(12)
    modes = [(n, -0.5) for n in range(7)] + [(1, -0.5)]
    f = [100.0, 110.0, 125.0, 145.0, 170.0, 200.0, 235.0, 130.0]
    res = classify(f, _shapes(th, modes), th, LOCS, damping_ratio=[0.02] * 8)
    # (session 13) its alias 11 would make the branch fall (n = 3 is clear at 145 Hz, above
    # it): it keeps its spatial order 1, out of the branch's order
    assert [c.n for c in res] == [0, 1, 2, 3, 4, 5, 6, 1]
    assert not res[7].aliased and [c.in_order for c in res].count(False) == 1  # one of a falling pair
    assert not any(c.crowd for c in res)
    alone = classify(f[:7], _shapes(th, modes[:7]), th, LOCS, damping_ratio=[0.02] * 7)
    assert not res[6].aliased and res[6].n_confidence == pytest.approx(alone[6].n_confidence, abs=1e-12)


def test_an_alias_order_seen_as_its_own_pole_a_bandwidth_away_is_no_crowd():
    """12 points, ζ = 0.02; the in-phase branch f(1…6) = 100, 140, 160, 170, 171.5, 173 Hz
    (n = 5, 6 weak, as in a crowd) continued with 1.5 Hz per order puts n = 8, the alias
    12 − 4 of n = 4, at 176 Hz: 6 Hz from the n = 4 mode at 170 Hz, inside its 2ζf = 6.8 Hz.
    But the estimator found n = 8's mode itself, a pole reading spatial order 4 (its branch
    barely readable) at 177.5 Hz, 7.5 Hz from n = 4: the two were resolved and n = 4 is no
    crowd. With that pole at 175 Hz (5 Hz away, inside the band) n = 4 is (4, 8)."""
    th = _grid(12)
    modes = [(1, 0.5), (2, 0.5), (3, 0.5), (4, 0.5), (5, 0.5), (6, 0.5), (8, 0.5 * np.exp(1.3j))]
    S = _shapes(th, modes)
    sig = [0.9, 0.9, 0.9, 0.9, 0.2, 0.2, 0.1]
    for f_q, crowd in ((177.5, ()), (175.0, (4, 8))):
        res = classify([100.0, 140.0, 160.0, 170.0, 171.5, 173.0, f_q], S, th, LOCS, significance=sig,
                       damping_ratio=[0.02] * 7)
        assert res[6].n_spatial == 4 and res[6].branch_confidence < 0.5
        assert res[3].n == 4 and res[3].n_candidates == crowd


def test_a_misread_alias_out_of_the_branch_order_does_not_flatten_its_dispersion():
    """12 points, ζ = 0.06; a branch rising 20 Hz per order, f(n) = 100 + 20 n (n = 1…6). A weak
    mode at 190 Hz reading spatial order 1 (order 1 held at 120 Hz) is read as the alias 11,
    and lies below n = 5 and 6: out of the branch's order, a misread. Kept in the dispersion
    it would lift f(7…11) to 220 Hz, inside the n = 5 mode's 2ζf = 24 Hz (a crowd (5, 7));
    by the branch's rise n = 7 lies at 240 Hz, 40 Hz away: no crowd."""
    th = _grid(12)
    S = _shapes(th, [(1, 0.5), (2, 0.5), (3, 0.5), (4, 0.5), (1, 0.5), (5, 0.5), (6, 0.5)])
    f = [120.0, 140.0, 160.0, 180.0, 190.0, 200.0, 220.0]
    res = classify(f, S, th, LOCS, significance=[0.9, 0.9, 0.9, 0.9, 0.1, 0.9, 0.9], damping_ratio=[0.06] * 7)
    assert res[4].n == 11 and not res[4].in_order
    assert res[5].n == 5 and not res[5].crowd and res[5].n_confidence == pytest.approx(1.0, abs=1e-9)


def test_grid_top_order_is_read_on_a_uniform_grid_from_any_start():
    th = _grid(12, offset=0.2)
    S = _shapes(th, [(6, 0.5)])
    (c,) = classify([100.0], S, th, LOCS)
    assert c.n_spatial == 6 and c.n_confidence == pytest.approx(1.0, abs=1e-9)


def test_an_unreadable_mode_out_of_order_is_read_on_the_other_branch():
    """12 points. Same branch n = 1 … 6 at 40 … 90 Hz and n = 8 at 110 Hz; opposite branch
    n = 0 … 4 at 180 … 220 Hz. A mode at 100 Hz with true n = 7 on the same branch, whose
    sidewall moves in quadrature (branch confidence 0.1, read "opposite"), reads n_s = 5:
    out of the opposite branch's order, it is read on the same branch, where of its alias
    class {5, 7, 17, 19} only 7 fits the dispersion (5 is held, 17 and 19 lie above n = 8)."""
    th = _grid(12)
    modes = [(n, 0.5) for n in range(1, 7)] + [(8, 0.5), (7, -0.1 + 1j)] + [(n, -0.5) for n in range(5)]
    f = [40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 110.0, 100.0, 180.0, 190.0, 200.0, 210.0, 220.0]
    res = classify(f, _shapes(th, modes), th, LOCS)
    odd = res[7]
    assert odd.branch_confidence < 0.5 and odd.n_spatial == 5
    assert (odd.n, odd.branch, odd.aliased, odd.in_order) == (7, "same", True, True)
    assert [c.n for c in res[:7]] == [1, 2, 3, 4, 5, 6, 8] and [c.n for c in res[8:]] == [0, 1, 2, 3, 4]


@pytest.mark.parametrize("seven_seen", [False, True])
def test_an_unreadable_mode_beside_a_clear_one_of_its_order_is_read_on_the_other_branch(seven_seen):
    """12 points. In-phase branch n = 1 … 6 at 40 … 90 Hz and n = 8 at 300 Hz (spatial 4);
    anti-phase n = 0 … 5 at 180 … 230 Hz. A mode at 222 Hz with true n = 7 in phase (spatial
    5), its sidewall in quadrature (branch confidence 0.1, read "anti-phase"), lies in the
    anti-phase branch's order and 3.5 % below its clear n = 5: read there, it would be that
    mode's split partner. On the in-phase branch only n = 7 of its alias class {5, 7, 17, 19,
    29} fits the dispersion, so it is read there (the ring coupling + mass's in-phase n = 22 at
    292.5 Hz, read as the partner of the anti-phase n = 12 at 307.1 Hz, 4.8 % away, at branch
    confidence 0.06, where the mass splits its neighbours' pairs by 0.5–0.8 %). When the
    in-phase branch holds a clear n = 7 (at 100 Hz) no order fits there, and the mode stays the
    anti-phase n = 5's partner. (Where the orders mix: ``mixed``, a lumped mass splitting the
    pairs.)"""
    th = _grid(12)
    modes = ([(n, 0.5) for n in range(1, 7)] + [(8, 0.5)] + ([(7, 0.5)] if seven_seen else [])
             + [(n, -0.5) for n in range(6)] + [(7, -0.1 + 1j)])
    f = ([40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 300.0] + ([100.0] if seven_seen else [])
         + [180.0, 190.0, 200.0, 210.0, 220.0, 230.0, 222.0])
    res = classify(f, _shapes(th, modes), th, LOCS, mixed=True)
    odd, n5 = res[-1], res[-2]
    assert odd.branch_confidence < 0.5 and odd.n_spatial == 5
    if seven_seen:
        assert (odd.n, odd.branch) == (5, "opposite") and odd.pair is not None and odd.pair == n5.pair
    else:
        assert (odd.n, odd.branch, odd.aliased, odd.in_order) == (7, "same", True, True)
        assert n5.pair is None
    assert [c.n for c in res[:7]] == [1, 2, 3, 4, 5, 6, 8]


@pytest.mark.parametrize("sig, reread", [(0.01, True), (0.5, False)])
def test_a_weak_mode_out_of_order_is_read_on_the_other_branch_whatever_its_branch_confidence(sig, reread):
    """The set-up above, but the 100 Hz mode's sidewall reads clearly "opposite" (ratio
    −0.5, confidence 1). Explaining 1 % of the response in its band (under the misread
    level, 15 %), its reading is no evidence: it is read on the same branch as n = 7. At
    50 % its branch stands, and it stays out of the opposite branch's order (a misread)."""
    th = _grid(12)
    modes = [(n, 0.5) for n in range(1, 7)] + [(8, 0.5), (7, -0.5)] + [(n, -0.5) for n in range(5)]
    f = [40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 110.0, 100.0, 180.0, 190.0, 200.0, 210.0, 220.0]
    significance = np.full(len(f), 0.5)
    significance[7] = sig
    res = classify(f, _shapes(th, modes), th, LOCS, significance=significance)
    odd = res[7]
    assert odd.branch_confidence > 0.99 and odd.n_spatial == 5
    if reread:
        assert (odd.n, odd.branch, odd.aliased, odd.in_order) == (7, "same", True, True)
    else:
        assert (odd.branch, odd.in_order) == ("opposite", False)
    assert [c.n for c in res[:7]] == [1, 2, 3, 4, 5, 6, 8] and [c.n for c in res[8:]] == [0, 1, 2, 3, 4]


def test_a_clear_mode_off_the_branch_keeps_its_order_when_its_alias_would_make_the_branch_fall():
    """12 points; the in-phase branch n = 1 … 6 at 40 … 110 Hz, and one more clear order-4
    pattern at 92 Hz, 8 % above the branch's n = 4 (a family the branch does not hold: the
    ring's sidewall-shear modes of n = 1–5 at 93–98 Hz). "Each order once per branch" read it
    as the alias 12 − 4 = 8, yet the branch's n = 5 and 6, clear and read at their own orders,
    lie above it: n = 8 there would make the branch fall. It keeps n = 4, not aliased (the
    ruler's truth for the ring: n = 4 at 98.34 Hz beside the branch's n = 4 at 90.37 Hz);
    the branch's own modes keep theirs. A weak such mode is still read as the alias (the
    test above)."""
    th = _grid(12)
    modes = [(n, 0.5) for n in range(1, 7)] + [(4, 0.5)]
    f = [40.0, 55.0, 70.0, 85.0, 100.0, 110.0, 92.0]
    res = classify(f, _shapes(th, modes), th, LOCS, significance=[0.9, 0.9, 0.9, 0.9, 0.9, 0.9, 0.8],
                   damping_ratio=[0.02] * 7)
    assert [c.n for c in res] == [1, 2, 3, 4, 5, 6, 4]
    assert not any(c.aliased for c in res)
    assert all(c.in_order for c in res[:6])


def test_on_a_grid_with_failed_points_the_walk_alone_reads_the_aliases():
    """The configuration above with one of the 12 points failed: a spatial reading then holds
    every order's leak (modal.gaps), and the walk's reading stands — the extra order-4 mode
    is the alias 8, as before session 13 (the paper's failed-points case: its n = 8 at 147.2
    Hz, read as spatial order 2, would otherwise be given n = 2)."""
    th = np.delete(_grid(12), 5)
    modes = [(n, 0.5) for n in range(1, 7)] + [(4, 0.5)]
    f = [40.0, 55.0, 70.0, 85.0, 100.0, 110.0, 92.0]
    res = classify(f, _shapes(th, modes), th, LOCS, significance=[0.9, 0.9, 0.9, 0.9, 0.9, 0.9, 0.8],
                   damping_ratio=[0.02] * 7)
    assert res[6].n_spatial == 4 and res[6].n == 8 and res[6].aliased


@pytest.mark.parametrize("zeta", [0.01, 0.02])
def test_an_alias_after_missed_orders_is_read_from_the_branch_step(zeta):
    """On 34 points a rising branch (9.5 Hz per order, the ring's sidewall coupling at
    400 Hz) is seen up to n = 31, then n = 32–34 are missed and n = 35, 36, 39 are seen: each
    is read as the alias of its spatial order (1, 2, 5) that the branch's step puts at its
    frequency — 35, 36, 39, not the smallest aliases above the mark (33, 32 → 36, 39). Where
    the candidates' predicted frequencies lie within one bandwidth (a flat branch) the
    smallest stays: the same branch flat (0.05 Hz per order) from n = 25 reads the n = 35 as 33."""
    th = _grid(34)
    orders = list(range(0, 32)) + [35, 36, 39]
    f = [100.0 + 9.5 * n for n in orders]
    S = _shapes(th, [(n, 0.7) for n in orders])
    cls = classify(f, S, th, LOCS, significance=np.ones(len(f)), damping_ratio=np.full(len(f), zeta))
    assert [c.n for c in cls[-3:]] == [35, 36, 39] and all(c.aliased for c in cls[-3:])
    flat = [100.0 + 9.5 * n if n <= 25 else 337.5 + 0.05 * (n - 25) for n in orders]  # flat from n = 25
    cls = classify(flat, S, th, LOCS, significance=np.ones(len(f)), damping_ratio=np.full(len(f), zeta))
    assert cls[-3].n == 33


def test_an_alias_beyond_three_grid_lengths_is_read():
    """A clean rising branch seen far past its grid (12 points, n = 0 … 50: aliases up to
    4 N + 2) reads every order."""
    th = _grid(12)
    orders = list(range(0, 51))
    f = [100.0 + 9.5 * n for n in orders]
    S = _shapes(th, [(n, 0.7) for n in orders])
    cls = classify(f, S, th, LOCS, significance=np.ones(len(f)), damping_ratio=np.full(len(f), 0.01))
    assert [c.n for c in cls] == orders


def test_a_clear_mode_below_a_rising_branch_s_aliases_keeps_its_order():
    """On 34 points an opposite branch rises ever faster (f = 150 + 0.9 n², its steps
    growing) from n = 1 past the grid's top up to n = 29 at 907 Hz, and a second clear
    order-1 pattern stands 7 Hz above that mode (the ring's tangential n = 1 opposite, 785 Hz
    beside the branch's n = 29 at 778 Hz). Its smallest alias, 33, lies at 907 + 3 × 52 Hz
    or higher by the branch's last step: 150 Hz, many bandwidths, above it. It keeps n = 1, not aliased,
    out of the branch's order, and does not move the mark: the branch's n = 30 … 33 above
    it read their own orders (they were read as 38, 65, 100 … when its alias moved the
    mark). A weak such mode (significance < 0.3) is no evidence against the walk and is
    read as the alias; on a branch that flattens (steps shrinking) no bound holds."""
    th = _grid(34)
    orders = list(range(1, 34))
    f_of = lambda n: 150.0 + 0.9 * n**2  # noqa: E731
    f = [f_of(n) for n in orders] + [f_of(29) + 7.0]
    S = _shapes(th, [(n, -0.7) for n in orders] + [(1, -0.7)])
    sig = np.r_[np.full(len(orders), 0.8), 0.4]
    cls = classify(f, S, th, LOCS, significance=sig, damping_ratio=np.full(len(f), 0.02))
    assert (cls[-1].n, cls[-1].aliased, cls[-1].in_order) == (1, False, False)
    assert [c.n for c in cls[:-1]] == orders
    weak = classify(f, S, th, LOCS, significance=np.r_[sig[:-1], 0.1], damping_ratio=np.full(len(f), 0.02))
    assert weak[-1].aliased and weak[-1].n > 17
    flat = [f_of(n) if n <= 20 else f_of(20) + 30.0 * (1 - 0.8 ** (n - 20)) for n in orders]  # saturating
    cls = classify(flat + [flat[orders.index(29)] + 1.0], S, th, LOCS, significance=sig,
                   damping_ratio=np.full(len(f), 0.02))
    assert cls[-1].aliased


def test_on_a_grid_with_failed_points_a_reading_the_group_contradicts_is_read_at_the_group():
    """An opposite branch n = 0 … 12 on 19 of 24 points (the paper's failed-points
    combination's grid). Its n = 4 mode's residues hold the leak of a stronger order-11
    response (LSFD on a gappy grid: every order leaks into every other), so its tread
    shape reads spatial order 11 — clear (confidence ≥ 0.5, significance ≥ 0.3), it moves
    the alias mark to 11 and the walk then reads the branch's n = 9 … 11 as aliases (the
    collapse measured with the paper's model to 120 orders: n = 9, 10, 11 read as 15, 34,
    35). The order group the pole was estimated in (4) is read instead; on a complete grid
    the group is not consulted."""
    th_all = _grid(24)
    th = np.delete(th_all, [7, 13, 14, 17, 21])
    ns = list(range(13))
    f = [184.0 + 0.8 * n**2 for n in ns]
    S = _shapes(th, [(n, -0.5) for n in ns])
    S[4, 0] = 0.45 * np.cos(4 * th) + 0.9 * np.cos(11 * th + 0.3)  # the leak dominates the shape
    S[4, 1] = -0.5 * S[4, 0]
    kw = dict(significance=[0.6] * 13, damping_ratio=[0.03] * 13)
    before = classify(f, S, th, LOCS, **kw)
    assert before[4].n_spatial == 11 and [c.n for c in before[9:12]] != [9, 10, 11]  # what the rule fixes
    after = classify(f, S, th, LOCS, **kw, group=np.array(ns))
    assert [c.n for c in after] == ns and not any(c.aliased for c in after)
    assert after[4].n_spatial == 4 and after[4].n_confidence < before[4].n_confidence
    # a complete grid: the shape's own reading stands whatever the group
    Sc = _shapes(th_all, [(n, -0.5) for n in ns])
    Sc[4, 0] = 0.45 * np.cos(4 * th_all) + 0.9 * np.cos(11 * th_all + 0.3)
    Sc[4, 1] = -0.5 * Sc[4, 0]
    assert classify(f, Sc, th_all, LOCS, **kw, group=np.array(ns))[4].n_spatial == 11


def test_a_mode_read_below_the_mark_does_not_set_the_branch_step():
    """On 20 points an opposite branch f = 150 + 0.9 n² (steps of 30–40 Hz per order near
    n = 20, half-power bandwidths of about 20 Hz) is seen at n = 0 … 18 but for n = 3, whose
    absence leaves the n = 17 (spatial order 3, nothing of that pattern seen below it) read
    as n = 3, below the branch's mark; n = 19 is missed, n = 20 … 25 seen. The branch's step
    is that of its two highest orders, 16 → 18: the orders above the gap are read as
    20 … 25 (the out-of-order reading as the last step but one had put the step at 2 Hz per
    order, and the n = 20 at 510 Hz was read as its alias 40, each order above one span
    too high: the 20-point ring with an added mass, held out, session 38)."""
    th = _grid(20)
    orders = [n for n in range(0, 19) if n != 3] + list(range(20, 26))
    f = [150.0 + 0.9 * n**2 for n in orders]
    cls = classify(f, _shapes(th, [(n, -0.7) for n in orders]), th, LOCS, significance=np.full(len(f), 0.8),
                   damping_ratio=np.full(len(f), 0.02))
    by_f = dict(zip(orders, cls))
    assert by_f[17].n == 3  # the unseen alias: read at its spatial order
    assert [by_f[n].n for n in range(20, 26)] == list(range(20, 26))
    assert all(by_f[n].aliased for n in range(20, 26))


@pytest.mark.parametrize("below", [True, False])
def test_a_clear_mode_below_its_lower_orders_does_not_alias_the_branch(below):
    """20 points; the anti-phase branch n = 1 … 16 rising from 184 Hz (14 Hz per order above
    n = 4) and, ``below`` it, three clear order-9 patterns at 152–159 Hz and two weak ones of
    orders 8 and 7 at 161–163 Hz (the held-out ring with a mass, seed 9000: its in-phase
    n = 9 and 11 fitted as three poles read on the anti-phase branch, and two crowd rows). A
    branch rises with n from n = 1, so it cannot hold n = 9 below n = 1 … 8: those rows are
    another branch's or family's, and they neither raise the walk's mark nor make the
    branch's own orders aliases. Every order of the branch is read as its own (aliased above
    N/2 = 10), with or without the rows below; before session 45 the branch's n = 7 … 16
    were read as aliases of the rows below or at their spatial orders."""
    th = _grid(20)
    true_n = list(range(1, 17))
    f_branch = [184.5, 185.4, 187.1, 189.2, 194.4, 201.5, 212.1, 225.9, 243.9, 263.8, 284.4, 306.8, 330.1, 354.2,
                378.8, 404.0]
    f_below, n_below, sig_below = ([152.5, 155.0, 158.8, 161.3, 163.4], [9, 9, 9, 8, 7], [0.8, 0.8, 0.8, 0.2, 0.2]) \
        if below else ([], [], [])
    f = f_below + f_branch
    modes = [(n, -0.5) for n in n_below + true_n]
    res = classify(f, _shapes(th, modes), th, LOCS, significance=sig_below + [0.8] * len(f_branch),
                   damping_ratio=[0.02] * len(f))
    branch = res[len(f_below):]
    assert [c.n for c in branch] == true_n
    assert [c.aliased for c in branch] == [n > 10 for n in true_n]
    assert all(c.n == 9 and not c.aliased for c in res[:3] if below)  # they keep their spatial order


def test_the_held_out_ring_with_a_mass_reads_its_anti_phase_orders():
    """The readings of a real run (tests/data/alias_walk_ring_mass_20pts.json: the held-out
    20-point ring with a mass, seed 9000, as classify handed them to the alias walk): three
    clear rows at 152.5–158.8 Hz read as anti-phase n = 9 (the in-phase n = 9 and 11, fitted
    as three poles) lie below the branch's n = 1 … 8. The finite-element ring's truth for the
    anti-phase rows from 184 Hz on is n = 0 … 23, each order once (the split pairs of the
    mass twice: 283.1 and 285.2 Hz are n = 11, 377.5 and 379.9 Hz n = 15); before session 45
    the walk read n = 11 … 17 as 9 … 3."""
    import json
    from pathlib import Path

    from tiremodal_cli.modal.alias_walk import BranchModes, Reading, resolve_aliases

    d = json.loads((Path(__file__).parent / "data" / "alias_walk_ring_mass_20pts.json").read_text())
    m = BranchModes(np.array(d["freq"]), [Reading(**r) for r in d["reads"]], d["n_points"],
                    np.array(d["significance"]), np.array(d["significance_group"]), d["free_rim"], d["complete"],
                    np.array(d["damping"]), d["mixed"])
    ns, _ = resolve_aliases(m)
    anti = [(f, n) for f, r, n in zip(d["freq"], d["reads"], ns) if r["branch"] == "opposite" and 180 < f < 600]
    truth = {184.38: 0, 184.48: 1, 185.38: 2, 187.09: 3, 189.17: 4, 194.4: 5, 201.51: 6, 212.08: 7, 225.86: 8,
             243.93: 9, 263.75: 10, 283.09: 11, 285.15: 11, 307.01: 12, 331.04: 13, 355.16: 14, 377.5: 15,
             379.85: 15, 404.2: 16, 430.83: 17, 457.09: 18, 483.87: 19, 508.32: 20, 538.78: 21, 567.03: 22,
             595.76: 23}
    assert {round(f, 2): n for f, n in anti} == truth
