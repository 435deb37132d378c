"""Evidence the diagnosis weighs besides the fitted modes (issue #15, session 8): an
unexplained n = 1 mode in the cavity band counts in the residual; a split pair testifies
for a lumped mass only when the mass's fit reproduces it; a rim mass the modes do not
determine is said to be so, with the combination they do determine."""

import numpy as np

from tiremodal_cli.diagnose.candidates import split_evidence
from tiremodal_cli.diagnose.loop import DiagnoseOptions, diagnose
from tiremodal_cli.tyre.frequencies import model_frequencies
from tiremodal_cli.tyre.model import TyreParameters

NS = list(range(0, 11)) * 2
BR = ["same"] * 11 + ["opposite"] * 11


def _rows(p, effects=None, keep=lambda n, b: True):
    f = model_frequencies(p, NS, BR, effects)
    return [{"frequency_hz": float(x), "n": n, "branch": b} for x, n, b in zip(f, NS, BR)
            if np.isfinite(x) and keep(n, b)]


def test_an_unexplained_cavity_band_mode_counts_in_the_residual():
    """The seed model's own modes are at the noise; one more mode with an n = 1 pattern in
    the cavity band (read as n = 33 on 34 points, out of its branch's order, as lsce reads
    the ring's cavity mode) that no model mode explains puts the residual above the noise.
    A row labelled n = 1 of a branch no other row holds may be that branch's own n = 1, out
    of order: it is not counted."""
    p = TyreParameters()
    rows = _rows(p)
    opt = DiagnoseOptions(max_effects=0)
    assert not diagnose(rows, p, opt).residual_before["exceeds_noise"]
    cav = {"frequency_hz": 128.4, "n": 33, "branch": "same", "n_spatial": 1, "in_order": False}
    d = diagnose(rows + [cav], p, opt)
    band = d.residual_before["unexplained_band_modes"]
    assert [round(b["frequency_hz"], 1) for b in band] == [128.4] and band[0]["z"] > 100
    assert d.residual_before["exceeds_noise"]
    no_opp = [r for r in rows if not (r["n"] == 1 and r["branch"] == "opposite")]
    alone = {"frequency_hz": 128.4, "n": 1, "branch": "opposite", "n_spatial": 1, "in_order": False}
    d2 = diagnose(no_opp + [alone], p, opt)
    assert d2.residual_before["unexplained_band_modes"] == []
    assert not d2.residual_before["exceeds_noise"]


def test_an_n1_mode_of_a_flat_branch_is_no_cavity():
    """Unexplained modes of several orders within one half-power bandwidth are a structural
    branch the model lacks (a resonance of the sidewall alone, flat over n); the cavity
    couples to n = 1 only, so that branch's n = 1 member is not the cavity's evidence (the
    ring's sidewall shear: n = 1 … 6 at 93.6–98.3 Hz, ζ = 2 %). The same n = 1 row alone
    still is."""
    p = TyreParameters()
    rows = _rows(p)
    opt = DiagnoseOptions(max_effects=0)
    one = {"frequency_hz": 128.4, "n": 33, "branch": "same", "n_spatial": 1, "in_order": False,
           "damping_ratio": 0.02}
    others = [{"frequency_hz": 126.5, "n": 32, "branch": "same", "n_spatial": 2, "in_order": False,
               "damping_ratio": 0.02},
              {"frequency_hz": 128.43, "n": 30, "branch": "same", "n_spatial": 4, "in_order": False,
               "damping_ratio": 0.02}]
    assert diagnose(rows + [one] + others, p, opt).residual_before["unexplained_band_modes"] == []
    band = diagnose(rows + [one], p, opt).residual_before["unexplained_band_modes"]
    assert [round(b["frequency_hz"], 1) for b in band] == [128.4]
    far = [dict(o, frequency_hz=o["frequency_hz"] - 8.0) for o in others]  # 2ζf = 5.1 Hz: not one frequency
    band = diagnose(rows + [one] + far, p, opt).residual_before["unexplained_band_modes"]
    assert [round(b["frequency_hz"], 1) for b in band] == [128.4]


def test_an_n1_row_beside_a_crowd_is_no_cavity():
    """A crowd (lsce: several orders alias onto one spatial order within a bandwidth) is a
    flat branch too. The passenger-car tyre's in-phase branch crowds at 303 Hz, inside its
    cavity band: a test with no cavity read its n = 35 (36 points) as n = 1 opposite at
    302.9 Hz, not in a crowd itself, beside crowd rows of other orders 0.2–1.3 Hz below, and
    the diagnosis adopted a cavity with no coupling on it. Beside those rows it is no
    evidence; alone it still is."""
    p = TyreParameters(R=0.30, b=0.16, P0=2.2e5, rhoA=2.39, m_s=1.38, EI=5.0, k_r1=3.0e6, k_r2=2.0e6)
    rows = [r for r in _rows(p) if not (r["branch"] == "same" and r["n"] >= 8)]  # the crowd's clear orders
    opt = DiagnoseOptions(max_effects=0)
    one = {"frequency_hz": 302.908, "n": 1, "branch": "opposite", "n_spatial": 1, "in_order": True,
           "damping_ratio": 0.0199}
    crowd = [{"frequency_hz": f, "n": n, "branch": "same", "n_spatial": n, "in_order": True, "damping_ratio": 0.02,
              "crowd": True} for f, n in ((301.87, 14), (302.39, 9), (302.62, 5), (302.73, 2))]
    assert diagnose(rows + [one] + crowd, p, opt).residual_before["unexplained_band_modes"] == []
    band = diagnose(rows + [one], p, opt).residual_before["unexplained_band_modes"]
    assert [round(b["frequency_hz"], 1) for b in band] == [302.9]


def _pairs(p, effects):
    """Every order's two members (the model's lower and upper) as rows of one (n, branch)."""
    rows = []
    for mem in ("lower", "upper"):
        f = model_frequencies(p, NS, BR, effects, members=[mem] * len(NS))
        rows += [{"frequency_hz": float(x), "n": n, "branch": b} for x, n, b in zip(f, NS, BR)
                 if np.isfinite(x) and n >= 2]
    return rows


def test_a_split_the_mass_reproduces_is_its_evidence():
    """A 0.5 kg mass on the paper's tyre splits every pair (n ≥ 2): the mass is adopted, and
    its fit reproduces the measured splittings within their uncertainty."""
    p = TyreParameters()
    rows = _pairs(p, {"added_mass": {"m_a": 0.5}})
    d = diagnose(rows, p, DiagnoseOptions(candidates=("added_mass",), max_effects=1))
    assert d.adopted == ("added_mass",)
    mass = next(c for c in d.candidates if c.adopted)
    pairs, missing = split_evidence(mass, d.options)
    assert missing is None and sum(q["real"] and q["explained"] for q in pairs) >= 5
    assert abs(mass.parameters["added_mass.m_a"]["value"] / 0.5 - 1) < 0.01


def test_a_split_no_mass_reproduces_is_no_evidence():
    """Two orders read as one split pair (n = 9's mode labelled n = 10, 2.4 % below n = 10,
    as lsce read the paper's crowded same branch): a point mass splits a pair by a fraction
    of a per cent there, so no mass fit reproduces it and the pair is no evidence."""
    p = TyreParameters()
    rows = _rows(p)
    f9 = next(r["frequency_hz"] for r in rows if r["n"] == 9 and r["branch"] == "same")
    rows.append({"frequency_hz": f9, "n": 10, "branch": "same"})
    rows = [r for r in rows if not (r["n"] == 9 and r["branch"] == "same")]
    d = diagnose(rows, p, DiagnoseOptions(candidates=("added_mass",), max_effects=1))
    mass = next(c for c in d.candidates if c.name == "added_mass")
    assert mass.fit is not None and not mass.adopted
    pairs, missing = split_evidence(mass, d.options)
    assert missing is not None and not any(q["real"] and q["explained"] for q in pairs)
    assert mass.reason.startswith("no evidence") or "F-test" in mass.reason


def test_a_rim_mass_the_modes_cannot_see_is_undetermined():
    """A 60 kg rim on a 1e6 N/m fixture: with the tread's n = 1 modes measured, the rim mass
    and the fixture are determined (the profile's confidence set is the optimum alone);
    with only the rim mode, any mass on a line k_f = k_0 + m_w (2π f_w)² fits, f_w the rim
    mode's frequency: both are listed as undetermined and the line is reported."""
    p = TyreParameters(m_w=60.0)
    eff = {"rim_fixture": {"k_f": 1.0e6}}
    f_rim = float(model_frequencies(p, [1], ["same"], eff, meas_hz=[5.0])[0])
    rim_row = {"frequency_hz": f_rim, "n": 1, "branch": "same"}
    opt = DiagnoseOptions(candidates=("rim_fixture",), rim="free", max_effects=1)
    full = diagnose(_rows(p, eff) + [rim_row], TyreParameters(m_w=1000.0), opt)
    assert full.adopted == ("rim_fixture",) and full.rim_profile["determined"]
    assert abs(full.augmented.parameters.m_w / 60 - 1) < 1e-3 and "m_w" not in full.augmented.undetermined
    only = diagnose(_rows(p, eff, keep=lambda n, b: n != 1) + [rim_row], TyreParameters(m_w=1000.0), opt)
    prof = only.rim_profile
    assert not prof["determined"] and min(prof["inside"]) < 10 and max(prof["inside"]) > 1e4
    assert {"m_w", "rim_fixture.k_f"} <= set(only.augmented.undetermined)
    assert abs(prof["ridge"]["f_w_hz"] / f_rim - 1) < 1e-3
    assert "not unique" in only.verdict and only.to_dict()["rim_mass_profile"]["determined"] is False


def test_the_cavity_gets_a_round_of_its_own_past_max_effects():
    """A membrane (T_s = 2e4 N) and an air cavity (f_c = 125 Hz, γ = 0.3) on the paper's
    tyre, the cavity mode read as n = 33 on 34 points: with ``max_effects`` = 1 the membrane
    is adopted first, and the cavity mode — which no structural effect can explain — still
    earns the air cavity a round, in which it is adopted."""
    p = TyreParameters()
    eff = {"sidewall_membrane": {"T_s": 2.0e4}, "air_cavity": {"f_cavity_hz": 125.0, "gamma": 0.3}}
    rows = _rows(p, eff)
    f_cav = float(model_frequencies(p, [1], ["cavity"], eff)[0])
    rows.append({"frequency_hz": f_cav, "n": 33, "branch": "same", "n_spatial": 1, "in_order": False})
    opt = DiagnoseOptions(candidates=("sidewall_membrane", "air_cavity"), max_effects=1)
    d = diagnose(rows, p, opt)
    assert d.adopted == ("sidewall_membrane", "air_cavity")
    assert [c.name for c in d.candidates if c.round == 2] == ["air_cavity"]
    assert abs(d.cavity_modes[0]["frequency_hz"] / f_cav - 1) < 1e-9


def test_a_rim_mass_on_a_flat_ridge_stays_where_the_current_model_has_it():
    """With only the rim mode among the n = 1 modes, the rim mode's frequency fixes
    √(k_f / m_w)-like combinations only (the profile above): whatever path a search takes
    along that ridge, the adopted fit keeps m_w at the current model's value (the 1,000 kg
    given) and says so; with the tread's n = 1 modes it is determined (60 kg) and not held."""
    p = TyreParameters(m_w=60.0)
    eff = {"rim_fixture": {"k_f": 1.0e6}}
    f_rim = float(model_frequencies(p, [1], ["same"], eff, meas_hz=[5.0])[0])
    rim_row = {"frequency_hz": f_rim, "n": 1, "branch": "same"}
    opt = DiagnoseOptions(candidates=("rim_fixture",), rim="free", max_effects=1)
    only = diagnose(_rows(p, eff, keep=lambda n, b: n != 1) + [rim_row], TyreParameters(m_w=1000.0), opt)
    rim = next(c for c in only.candidates if c.name == "rim_fixture")
    assert rim.held is not None and rim.held.startswith("m_w = 1000")
    assert abs(only.augmented.parameters.m_w / 1000.0 - 1) < 1e-6
    # the rim's frequency on its supports is what the modes fix: the model's rim mode there
    f_model = float(model_frequencies(only.augmented.parameters, [1], ["same"], only.augmented.effects,
                                      meas_hz=[f_rim])[0])
    assert abs(f_model / f_rim - 1) < 1e-4
    full = diagnose(_rows(p, eff) + [rim_row], TyreParameters(m_w=1000.0), opt)
    assert next(c for c in full.candidates if c.name == "rim_fixture").held is None


def test_two_effects_are_both_adopted_whichever_comes_first():
    """Two effects on one tyre are separable: a sidewall membrane (∝ n²) and a stretching
    belt (n = 0) are both adopted when the membrane is the stronger (it comes first) and
    when it is the weaker (the belt comes first), and so are tangential coupling and the
    belt; the order the candidates are listed in changes nothing."""
    p = TyreParameters()
    cases = [({"sidewall_membrane": {"T_s": 2.0e4}, "extensible_belt": {"EA": 2.0e6}}, "sidewall_membrane"),
             ({"sidewall_membrane": {"T_s": 2.0e3}, "extensible_belt": {"EA": 5.0e5}}, "extensible_belt"),
             ({"tangential": {"c_t": 0.5, "k_t": 1.0e6}, "extensible_belt": {"EA": 1.0e6}}, "tangential")]
    for eff, first in cases:
        rows = _rows(p, eff)
        for order in (tuple(eff), tuple(eff)[::-1]):
            d = diagnose(rows, p, DiagnoseOptions(candidates=order, max_effects=2))
            assert set(d.adopted) == set(eff) and d.adopted[0] == first, (eff, order, d.adopted)
            assert d.augmented.rms_error_pct < 0.01


def test_a_measured_n1_mode_of_a_free_rim_is_the_nearest_model_mode_whatever_its_label():
    """With a free rim the n = 1 block has three modes (rim, same, opposite); the modal
    stage reads a label from the sign of two motions, which the rim's motion mixes. Each
    measured n = 1 mode is matched to the model's nearest, so every labelling of the three
    true frequencies (from the full eigenproblem of ``solve_modes``) is reproduced exactly."""
    import itertools

    from tiremodal_cli.tyre.solve import solve_modes

    p = TyreParameters(m_w=60.0)
    m = solve_modes(p, n_max=1)
    f1 = sorted(float(f) for f, n, h in zip(m.freq_hz, m.n, m.harmonic) if n == 1 and h == "cos")
    assert len(f1) == 3
    for labels in itertools.product(("same", "opposite"), repeat=3):
        got = model_frequencies(p, [1, 1, 1], list(labels), meas_hz=f1)
        np.testing.assert_allclose(got, f1, rtol=1e-9)
        got_eff = model_frequencies(p, [1, 1, 1], list(labels), {"timoshenko": {"rhoI": 0.0, "c_s": 0.0}}, meas_hz=f1)
        np.testing.assert_allclose(got_eff, f1, rtol=1e-9)


def test_a_free_rims_mode_out_of_order_is_evidence_for_the_rim():
    """A 60 kg free rim: its mode reads as n = 1 "same" below the same branch's n = 1, out
    of the branch's dispersion order (as the modal stage flags it). The other orders do not
    see the rim. When the rim channel shows a free rim that row enters the fit, and the rim
    mass is found (60 kg, from a 1,000 kg start); without it nothing can be adopted."""
    truth = TyreParameters(m_w=60.0)
    f_rim = float(model_frequencies(truth, [1], ["same"], meas_hz=[1.0])[0])
    assert f_rim < float(model_frequencies(truth, [2], ["same"])[0])  # out of the branch's order
    rows = _rows(truth, keep=lambda n, b: n >= 2)
    rows.append({"frequency_hz": f_rim, "n": 1, "branch": "same", "in_order": False})
    start = TyreParameters(m_w=1000.0)
    free = diagnose(rows, start, DiagnoseOptions(candidates=("m_w", "b"), rim="free", max_effects=1))
    assert free.adopted == ("m_w",) and abs(free.augmented.parameters.m_w / 60 - 1) < 1e-3
    unknown = diagnose(rows, start, DiagnoseOptions(candidates=("m_w", "b"), max_effects=1))
    assert unknown.adopted == ()


def test_a_mass_the_sensors_cannot_split_is_said_not_told_from_a_uniform_one():
    """A 0.5 kg mass at the sensors' angle: the table holds each pair's lower member only
    (the other's node is at the sensors), no split pair testifies for the mass, and a
    uniform mass change (rhoA) fits the nearly uniform lowering (0.05–0.5 %) as well — by
    AICc better. When the modal stage found the orders mixed (a lumped asymmetry) the
    verdict says that one member per order does not tell the two apart; without that
    finding it does not."""
    p = TyreParameters()
    f = model_frequencies(p, NS, BR, {"added_mass": {"m_a": 0.5, "theta_a": 0.0}}, members=["lower"] * len(NS))
    rows = [{"frequency_hz": float(x), "n": n, "branch": b} for x, n, b in zip(f, NS, BR) if np.isfinite(x)]
    plain = diagnose(rows, p, DiagnoseOptions(candidates=("added_mass", "rhoA"), max_effects=1))
    mixed = diagnose(rows, p, DiagnoseOptions(candidates=("added_mass", "rhoA"), max_effects=1,
                                              orders_mix="300 of 574 tests find a mode's symmetric copy"))
    assert plain.adopted == mixed.adopted == ("rhoA",)
    assert "does not tell the two apart" in mixed.verdict and "300 of 574" in mixed.verdict
    assert "does not tell" not in plain.verdict
