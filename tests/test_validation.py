"""The validation matrix's ruler (tiremodal_cli/validation.py) and a seeded subset of it.

The full matrix is ``benchmarks/validation.py`` (docs/validation.md). Here: the ruler's
rules on a ring test whose physics is known (spatial aliasing above N/2, degenerate pairs
as one mode, the same-direction crowd under the sidewall resonance, the usable band), the
counting rules on hand-made tables, and one case per generator through ``run``.
"""

import dataclasses

import numpy as np
import pytest

from tiremodal_cli.tyre.simulate import SimulationConfig, simulate
from tiremodal_cli.tyre.ring_parameters import RING_VARIANTS
from tiremodal_cli.workflow.validation import (FACTORS, HELD_OUT_LEVELS, PHYSICS, TYRES, Case, config_for,
                                               expected_groups, held_out_levels, matrix, nominal_params, run_case,
                                               score_modes)
from tiremodal_cli.workflow.validation_scoring import detectable, diagnosis_right


@pytest.fixture(scope="module")
def ring24():
    cfg = SimulationConfig(model="ring", n_points=24, n_hits=1, sample_rate=1024.0, n_samples=1024,
                           noise=0.005, seed=3)
    return cfg, simulate(cfg)


def test_groups_follow_the_physics_of_the_test(ring24):
    cfg, sim = ring24
    groups = expected_groups(sim, cfg)
    structural = [g for g in groups if g["branch"] in ("same", "opposite")]
    # 24 points: orders above 12 alias, 12 itself does not
    assert all(g["aliased"] == (g["n"] > 12) for g in structural)
    # an axisymmetric tyre: every pair n ≥ 1 is one group, so a group per (n, branch)
    keys = [(g["n"], g["branch"]) for g in structural]
    assert len(keys) == len(set(keys))
    # the usable band of a 1,024 Hz front end: fs/2.56 = 400 Hz, the whole half-power band in it
    assert all(g["valid"] == (g["frequency_hz"] * (1 + g["zeta"]) <= 400.0) for g in groups)
    # the same-direction branch saturates under √((k_r1+k_r2)/m_s)/2π ≈ 168 Hz: its high
    # orders crowd with their aliases; the low orders stand alone and are expected
    same = {g["n"]: g for g in structural if g["branch"] == "same"}
    assert all(not same[n]["crowd"] and same[n]["expected"] for n in range(0, 9))
    assert all(same[n]["crowd"] for n in (20, 30, 40) if n in same)
    # the mode count matches the model: opposite branch n = 0 … through the band, one each
    opp = sorted(g["n"] for g in structural if g["branch"] == "opposite" and g["valid"])
    assert opp == list(range(len(opp)))


def test_counting_rules():
    groups = [
        {"frequency_hz": 100.0, "n": 2, "branch": "same", "zeta": 0.02, "expected": True, "aliased": False, "foreign": False, "valid": True, "crowd": False},
        {"frequency_hz": 200.0, "n": 3, "branch": "opposite", "zeta": 0.02, "expected": True, "aliased": False, "foreign": False, "valid": True, "crowd": False},
        {"frequency_hz": 300.0, "n": 20, "branch": "opposite", "zeta": 0.02, "expected": True, "aliased": True, "foreign": False, "valid": True, "crowd": False},
        {"frequency_hz": 150.0, "n": 1, "branch": "cavity", "zeta": 0.005, "expected": True, "aliased": False, "foreign": True, "valid": True, "crowd": False},
        {"frequency_hz": 400.0, "n": 9, "branch": "same", "zeta": 0.02, "expected": False, "aliased": False, "foreign": False, "valid": False, "crowd": False},
    ]
    truth = [{"frequency_hz": g["frequency_hz"]} for g in groups]
    row = lambda f, n, b, al=False: {"frequency_hz": f, "damping_ratio": 0.02, "n": n, "branch": b, "aliased": al}  # noqa: E731
    rows = [row(100.2, 2, "same"),        # within 0.3 %: found
            row(200.0, 4, "opposite"),    # right frequency, wrong n: mislabelled
            row(300.5, 14, "opposite", True),  # an aliased order flagged as such: found
            row(150.1, 1, "same"),        # cavity mode, any label: found
            row(400.0, 9, "same"),        # not expected (outside the band), but true: not spurious
            row(250.0, 5, "same")]        # nothing within 0.3 %: spurious
    s = score_modes(groups, rows, truth)
    assert (s["expected"], s["found"], s["mislabelled"], s["missed"], s["spurious"]) == (4, 3, 1, 0, 1)
    assert s["freq_err_median_pct"] == pytest.approx(100 * np.median([0.002, 0.5 / 300, 0.1 / 150]))
    s = score_modes(groups, rows[2:], truth)  # the n = 2 and n = 3 modes missed
    assert (s["found"], s["missed"], s["mislabelled"]) == (2, 2, 0)


@pytest.mark.parametrize("n_spatial, status", [
    (14, "found"),           # n = 20 on 34 points aliases onto spatial order 14
    (None, "found"),         # a table without spatial orders: the flag alone
    (6, "mislabelled"),      # another order group's row at that frequency: another mode
])
def test_an_aliased_order_is_found_only_in_its_alias_class(n_spatial, status):
    """An order above N/2 is found by a row flagged aliased whose spatial order is the
    truth order's alias class (n mod N, folded): the same-direction crowd converging under
    the sidewall resonance puts a row of every order group within 0.3 % of the paper's
    n = 34 at 167.3 Hz, and a row of group 4 is not the n = 34 mode."""
    g = {"frequency_hz": 300.0, "n": 20, "branch": "opposite", "zeta": 0.02, "expected": True, "aliased": True,
         "alias_class": 14, "foreign": False, "valid": True, "crowd": False}
    row = {"frequency_hz": 300.2, "damping_ratio": 0.02, "n": 14, "branch": "opposite", "aliased": True,
           "n_spatial": n_spatial}
    s = score_modes([g], [row], [{"frequency_hz": 300.0}])
    assert s["detail"][0]["status"].startswith(status)


@pytest.mark.parametrize("n, candidates, branch, read", [
    (32, [], "opposite", True),          # the truth's order
    (38, [32, 38], "opposite", True),    # among the crowd's candidates
    (100, [], "opposite", False),        # flagged, but a far alias: found, not read
    (32, [], "same", False),             # the other branch: found, not read
])
def test_an_aliased_order_found_is_read_right_only_with_its_order_and_branch(n, candidates, branch, read):
    """The ruler finds an order above N/2 by the flag; whether the row also names the
    truth's order (its n or a candidate) and branch is counted apart."""
    g = {"frequency_hz": 877.9, "n": 32, "branch": "opposite", "zeta": 0.02, "expected": True, "aliased": True,
         "alias_class": 2, "foreign": False, "valid": True, "crowd": False}
    row = {"frequency_hz": 877.91, "damping_ratio": 0.02, "n": n, "branch": branch, "aliased": True, "n_spatial": 2,
           "n_candidates": candidates}
    s = score_modes([g], [row], [{"frequency_hz": 877.9}])
    assert (s["found"], s["aliased_found"], s["aliased_read"]) == (1, 1, int(read))


@pytest.mark.parametrize("n, branch, aliased, status", [
    (1, "same", False, "found"),          # the rim's order, read on either branch
    (1, "opposite", False, "found"),
    (33, "same", True, "mislabelled"),    # its order misread as an alias of the grid
    (2, "same", False, "mislabelled"),
])
def test_a_free_rims_mode_is_found_by_its_order_on_either_branch(n, branch, aliased, status):
    """The generators' "rim" label (the rim's share of the kinetic energy) cannot be read
    from a test without the masses; the order can."""
    g = {"frequency_hz": 78.9, "n": 1, "branch": "rim", "zeta": 0.02, "expected": True, "aliased": False,
         "foreign": False, "valid": True, "crowd": False}
    row = {"frequency_hz": 78.95, "damping_ratio": 0.02, "n": n, "branch": branch, "aliased": aliased}
    s = score_modes([g], [row], [{"frequency_hz": 78.9}])
    assert s["detail"][0]["status"].startswith(status)


def test_matrix_covers_every_level_of_every_factor():
    cases = matrix()
    for g in ("ring", "paper"):
        mine = [c for c in cases if c.generator == g]
        for factor, levels in FACTORS.items():
            assert {getattr(c, factor) for c in mine} >= set(levels), (g, factor)
        phys = {p for c in mine for p in c.physics.split("+")}
        assert phys >= set(PHYSICS[g])
        assert any("+" in c.physics for c in mine)  # effects in pairs
    assert len({c.seed for c in cases}) == len(cases)
    assert matrix() == cases  # seeded


def test_held_out_levels_are_none_of_the_matrix():
    """The held-out set-ups share no level with the matrix but the form and faults (which
    have no other), and their record length sets the line spacing."""
    cases = held_out_levels(6)
    assert held_out_levels(6) == cases  # seeded
    for factor in ("sample_rate", "n_points", "n_hits", "noise"):
        assert not set(HELD_OUT_LEVELS[factor]) & set(FACTORS[factor]), factor
        assert not {getattr(c, factor) for c in cases} & set(FACTORS[factor]), factor
    assert not {c.seed for c in cases} & {c.seed + off for c in matrix() for off in (0, 1000, 2000, 3000)}
    for c in cases[:3]:
        assert config_for(c).n_samples == round(c.record_s * c.sample_rate)
    assert {c.record_s for c in cases} <= set(HELD_OUT_LEVELS["record_s"]) and 2.0 not in HELD_OUT_LEVELS["record_s"]


def test_another_tyre_changes_the_tyre_only():
    """``--tyre car``: the same cases (levels, physics, seeds) made of another tyre, named
    apart; each ring variant switches on the same physics (the same parameters) as on
    GL073A, with the car's values; run is given the car's dimensions and masses."""
    truck, car = matrix(), matrix(tyre="car")
    assert [dataclasses.replace(c, tyre="gl073a") for c in car] == truck
    assert all(c.tyre == "car" and c.name.startswith(f"{c.generator}[car]:") for c in car)
    assert [dataclasses.replace(c, tyre="gl073a") for c in held_out_levels(3, tyre="car")] == held_out_levels(3)
    for name, values in RING_VARIANTS.items():
        assert set(TYRES["car"].ring_variants[name]) == set(values), name
    ring = config_for(Case(generator="ring", tyre="car", physics="sidewall_coupling+mass")).ring
    assert (ring.R, ring.sidewall_T, ring.masses) == (0.30, 1.2e3, ((45.0, 0.05),))
    paper = config_for(Case(generator="paper", tyre="car", physics="added_mass+rim"))
    assert (paper.params.R, paper.params.m_w, paper.effects) == (0.30, 10.0, {"added_mass": {"m_a": 0.05}})
    nom = nominal_params(Case(tyre="car"))
    assert (nom.R, nom.b, nom.rhoA, nom.m_s) == (0.30, 0.16, 2.39, 1.38)
    assert nominal_params(Case()) == config_for(Case(generator="paper")).params  # GL073A: run's default
    with pytest.raises(ValueError, match="allowed: gl073a, car"):
        matrix(tyre="bicycle")


@pytest.fixture(scope="module")
def car(tmp_path_factory):
    """A passenger-car tyre (``TYRES["car"]``: a third of the truck's radius, 8 × less tread
    mass; no rule of the modal stage was measured on it) from the finite-element ring through
    ``run``, at the matrix's reference set-up, on a seed no benchmark run uses."""
    return run_case(Case(generator="ring", tyre="car", seed=11, label="car"), tmp_path_factory.mktemp("car"))


def test_another_tyre_every_expected_mode_found_and_nothing_adopted(car):
    """On a tyre no rule was measured on: every expected mode within 0.3 % with its n and
    branch, at most 5 % spurious, the base fit at the noise and nothing adopted (the ring in
    the paper model's limit)."""
    assert car["status"] == "ok", car.get("error")
    assert car["expected"] >= 20
    assert car["found"] == car["expected"] and car["spurious"] <= 0.05 * car["adopted"]
    assert car["diagnosis_right"] and car["adopted_effects"] == []
    assert car["base_rms_pct"] <= 2 * 100 * 0.005


def test_faulty_cases_bounce_a_fifth_of_the_hits():
    case = Case(generator="paper", n_points=24, n_hits=5, faults="bounced+overload", seed=7)
    cfg = config_for(case)
    assert len(cfg.faults.double_hits) == 24 * 5 // 5
    assert len(cfg.faults.clipped) == 1
    assert not set(cfg.faults.double_hits) & {c[:2] for c in cfg.faults.clipped}


@pytest.fixture(scope="module")
def subset(tmp_path_factory):
    """One seeded case per generator through ``run``: 1,024 Hz, 24 points, 3 hits."""
    out = {}
    for g in ("ring", "paper"):
        case = Case(generator=g, sample_rate=1024.0, n_points=24, n_hits=3, noise=0.005, seed=11, label="subset")
        out[g] = run_case(case, tmp_path_factory.mktemp(g))
    return out


@pytest.mark.parametrize("generator", ["ring", "paper"])
def test_subset_runs_and_finds_modes_precisely(subset, generator):
    """What holds today: run completes, and the modes it labels right are within 0.01 % of
    the truth (the estimator is precise where it is right)."""
    r = subset[generator]
    assert r["status"] == "ok", r.get("error")
    assert r["expected"] >= 20
    assert r["found"] >= 0.5 * r["expected"]
    assert r["freq_err_median_pct"] < 0.01


@pytest.mark.parametrize("generator", ["ring", "paper"])
def test_subset_every_expected_mode_found(subset, generator):
    """Every expected mode found with its n and branch (the opposite branch's n = 0 and 1,
    0.15 % apart, both; a same-direction order one bandwidth from its alias not flagged as
    a crowd), and at most 5 % spurious."""
    r = subset[generator]
    assert r["found"] == r["expected"] and r["spurious"] <= 0.05 * r["adopted"]


@pytest.mark.parametrize("generator", ["ring", "paper"])
def test_subset_no_effect_adopts_nothing_and_fits_to_the_noise(subset, generator):
    """A test with no physics beyond the paper's model (the ring in its limit, clamped rim):
    nothing adopted, and the base fit's RMS within twice the noise level."""
    r = subset[generator]
    assert r["diagnosis_right"] and r["adopted_effects"] == []
    assert r["base_rms_pct"] <= 2 * 100 * 0.005


def test_a_split_the_damping_merges_is_one_mode_to_detectability():
    """The paper's 0.5 kg added mass splits each pair by less than ζ f (the generator's
    truth), so a test shows each pair as one mode: judged on those, the base model absorbs
    the mass within the noise (not detectable). Had the test resolved the pairs (each
    member its own group), the lowered members would show it: the verdict turns on the
    resolution alone."""
    case = next(c for c in matrix() if c.name == "paper:physics=added_mass")
    cfg = config_for(case)
    sim = simulate(cfg)
    pairs = {}
    for m in sim.truth["modes"]:
        if m["branch"] in ("same", "opposite") and m["n"] >= 1:
            pairs.setdefault((m["n"], m["branch"]), []).append((m["frequency_hz"], m["damping_ratio"]))
    split = [(max(f for f, _ in v) - min(f for f, _ in v)) / (v[0][1] * np.mean([f for f, _ in v]))
             for v in pairs.values() if len(v) == 2]
    assert len(split) > 20 and max(split) < 1.0  # split by less than ζ f: one peak
    groups = expected_groups(sim, cfg)
    params = cfg.params
    assert not detectable(case, groups, params)["detectable"]
    resolved = []
    for g in groups:
        if len(g["members"]) > 1 and max(g["members"]) - min(g["members"]) > 1e-6 * g["frequency_hz"]:
            resolved += [dict(g, members=[f], frequency_hz=f) for f in (min(g["members"]), max(g["members"]))]
        else:
            resolved.append(g)
    assert detectable(case, resolved, params)["detectable"]


def test_each_effect_of_a_pair_is_required_only_where_detectable():
    """Two effects in one test: each is required of the diagnosis unless the test cannot
    show it alone; its names stay allowed, and nothing else is."""
    phys = "tangential+added_mass"
    alone = {"tangential": True, "added_mass": False}
    assert diagnosis_right(phys, ["tangential"], alone)
    assert diagnosis_right(phys, ["tangential", "added_mass"], alone)
    assert not diagnosis_right(phys, [], alone)
    assert not diagnosis_right(phys, ["added_mass"], alone)
    assert not diagnosis_right(phys, ["tangential", "b"], alone)
    assert not diagnosis_right(phys, ["tangential"], True)  # both detectable: both required
    assert diagnosis_right(phys, [], False)


@pytest.mark.parametrize("f_row, status", [
    (402.85, "found"),       # at the lower member: 0.28 % below the pair's mean, but that member
    (402.64, "found"),       # 0.05 % from the lower member, 0.33 % from the mean
    (405.09, "found"),       # at the upper member
    (403.97, "found"),       # at the mean (the pair read as one mode)
    (401.10, "missed"),      # 0.44 % below the lower member: neither
])
def test_a_split_pair_is_found_at_either_member_or_at_its_mean(f_row, status):
    """An added mass splits each order's cos/sin pair (the ring's n = 16 opposite at 402.848
    and 405.085 Hz, 0.55 % apart at ζ = 2 %): the ruler takes a pair split by less than ζ f
    as one truth mode, and a row at either member is that mode."""
    g = {"frequency_hz": 403.9665, "members": [402.848, 405.085], "n": 16, "branch": "opposite", "zeta": 0.02,
         "expected": True, "aliased": False, "foreign": False, "valid": True, "crowd": False}
    row = {"frequency_hz": f_row, "damping_ratio": 0.02, "n": 16, "branch": "opposite", "aliased": False}
    s = score_modes([g], [row], [{"frequency_hz": 402.848}, {"frequency_hz": 405.085}])
    assert s["detail"][0]["status"] == status
    if status == "found":
        assert s["freq_err_median_pct"] <= 0.06


def test_crowd_does_not_depend_on_where_the_generator_stops():
    """The paper's generator lists orders up to n_max; a tyre has them all. With 48 points
    the same-direction n = 24 (166.6 Hz, ζ ≈ 3.8 %) and its alias n = 72 lie 1.2 Hz apart
    under the branch's asymptote, a fifteenth of a bandwidth: a crowd whether or not n = 72
    is listed. The ruler's verdict on every listed order must be the same with n_max = 60
    (n = 72 left out) as with n_max = 80 (n = 72 in the truth and the FRFs)."""
    base = SimulationConfig(model="paper", n_points=48, n_hits=1, sample_rate=1024.0, n_samples=1024,
                            noise=0.005, seed=5, n_max=60)
    short = expected_groups(simulate(base), base)
    full_cfg = dataclasses.replace(base, n_max=80)
    full = {(g["n"], g["branch"]): g["crowd"] for g in expected_groups(simulate(full_cfg), full_cfg)}
    assert {(g["n"], g["branch"]): g["crowd"] for g in short} == {k: full[k] for k in
                                                                 ((g["n"], g["branch"]) for g in short)}
    n24 = next(g for g in short if g["n"] == 24 and g["branch"] == "same")
    assert n24["crowd"] and not n24["expected"]
