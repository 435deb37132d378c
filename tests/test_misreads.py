"""Misread orders (:mod:`tiremodal_cli.modal.misreads`): a weak pole read at an order its
branch's dispersion contradicts is dropped; a strong one (a mode of another family) stays.

Truths used: within a branch the ring's frequencies rise with n (the dispersion the
classification checks); the paper generator's point mass (its truth modes, not the
estimator's) holds no mode between the same-direction crowd's top (167.7 Hz) and the
opposite n = 0 (183.8 Hz), where the order groups' blends sat (docs/lsce.md, "Misread
orders")."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from tiremodal_cli.io.modalfile import read_modal
from tiremodal_cli.modal.classify import Classification, classify
from tiremodal_cli.modal.misreads import MISREAD_MAX_SIGNIFICANCE, without_misreads
from tiremodal_cli.modal.modes import ModalResult
from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.validation import config_for, matrix, run_case
from tiremodal_cli.workflow.validation_scoring import TOLERANCE

LOCS = ("tread", "sidewall")


def _result(freqs, orders, sig, n_p=24, zeta=None):
    """A ModalResult of opposite-branch modes cos n θ (sidewall against the tread), ζ = 2 %
    unless given."""
    th = 2 * np.pi * np.arange(n_p) / n_p
    S = np.zeros((len(freqs), 2, n_p), complex)
    for r, n in enumerate(orders):
        S[r, 0] = np.cos(n * th)
        S[r, 1] = -0.5 * S[r, 0]
    k = len(freqs)
    res = ModalResult(freq_hz=np.array(freqs, float),
                      damping_ratio=np.full(k, 0.02) if zeta is None else np.array(zeta, float), poles=np.zeros(k, complex),
                      shapes=S, mpc=np.ones(k), significance=np.array(sig, float), group=np.array(orders),
                      fit_error=np.zeros((2, n_p)), synthesis=np.zeros((2, n_p, 4), complex),
                      band_freq_hz=np.arange(4.0), meta={"significance_in_group": [0.5] * k},
                      frequency_std_hz=np.zeros(k))
    return res, th


def _classifier(th):
    return lambda m: classify(m.freq_hz, m.shapes, th, LOCS, m.significance, m.damping_ratio,
                              m.meta.get("significance_in_group"))


def test_a_weak_mode_out_of_its_branchs_order_is_dropped_the_rest_reclassified():
    """n = 2, 3, 4, 5 rising, and an n = 1 reading at 175 Hz between n = 4 and 5, weak:
    a misread, dropped with its reason; the four others keep their orders, in order."""
    res, th = _result([150.0, 160.0, 170.0, 175.0, 180.0], [2, 3, 4, 1, 5], [0.6, 0.6, 0.6, 0.05, 0.6])
    out, classes = without_misreads(res, _classifier(th))
    assert out.freq_hz.tolist() == [150.0, 160.0, 170.0, 180.0]
    assert [c.n for c in classes] == [2, 3, 4, 5] and all(c.in_order for c in classes)
    assert out.meta["significance_in_group"] == [0.5] * 4 and out.shapes.shape[0] == 4
    assert len(out.rejected) == 1 and "misread order" in out.rejected[0]["reason"]
    assert out.rejected[0]["frequency_hz"] == 175.0


@pytest.mark.parametrize("sig", [MISREAD_MAX_SIGNIFICANCE, 0.5])
def test_a_strong_mode_out_of_order_is_another_family_and_stays(sig):
    """The same n = 1 reading explaining at least the level of the physical response: a
    mode of another family (a tangential n = 1 lifted above the low orders), kept and
    flagged out of order as before."""
    res, th = _result([150.0, 160.0, 170.0, 175.0, 180.0], [2, 3, 4, 1, 5], [0.6, 0.6, 0.6, sig, 0.6])
    out, classes = without_misreads(res, _classifier(th))
    assert out.freq_hz.size == 5 and not out.rejected
    assert [c.in_order for c in classes] == [True, True, True, False, True]


def test_a_weak_mode_out_of_order_narrower_than_its_neighbours_is_no_blend_and_stays():
    """The same weak n = 1 reading at ζ = 0.5 % between modes at 2 %: a blend of them
    would decay no slower than they do, so it is a mode of its own (a cavity's), kept."""
    res, th = _result([150.0, 160.0, 170.0, 175.0, 180.0], [2, 3, 4, 1, 5], [0.6, 0.6, 0.6, 0.05, 0.6],
                      zeta=[0.02, 0.02, 0.02, 0.005, 0.02])
    out, classes = without_misreads(res, _classifier(th))
    assert out.freq_hz.size == 5 and not out.rejected and not classes[3].in_order


@pytest.mark.parametrize("symmetric, mixed, kept_as", [(True, False, 1), (False, False, None), (True, True, 23)])
def test_a_weak_mode_of_another_family_on_a_symmetric_structure_stays(symmetric, mixed, kept_as):
    """A same-direction branch n = 1 … 6 (40–110 Hz) below an opposite one (180–230 Hz), and
    a second same n = 1 reading at 97 Hz, weak in the physical FRFs (10 %: beside stronger
    modes of other orders) but clear in its own order group. Its alias on 24 points, n = 23,
    would sit below the same branch's n = 6 at 110 Hz and below the opposite branch's n = 2
    … 6 as well: both branches contradict it, so it is a mode of another family at its spatial
    order. On a structure symmetric about its sensors (orders unmixed: no group holds another
    order's leak) it is kept as n = 1, out of order; without that symmetry it is dropped as a
    misread; with the orders mixed (a mass) its group's share is no evidence, and the walk
    reads it as the alias (not a misread: aliased readings are not judged)."""
    n_p = 24
    th = 2 * np.pi * np.arange(n_p) / n_p
    same = [(40.0, 1), (55.0, 2), (68.0, 3), (82.0, 4), (95.0, 5), (97.0, 1), (110.0, 6)]
    opp = [(180.0 + 10 * n, n) for n in range(1, 7)]
    modes = same + opp
    S = np.zeros((len(modes), 2, n_p), complex)
    for r, (_, n) in enumerate(modes):
        S[r, 0] = np.cos(n * th)
        S[r, 1] = (0.5 if r < len(same) else -0.5) * S[r, 0]
    k = len(modes)
    sig = np.array([0.10 if f == 97.0 else 0.6 for f, _ in modes])
    res = ModalResult(freq_hz=np.array([f for f, _ in modes]), damping_ratio=np.full(k, 0.02),
                      poles=np.zeros(k, complex), shapes=S, mpc=np.ones(k), significance=sig,
                      group=np.array([n for _, n in modes]), fit_error=np.zeros((2, n_p)),
                      synthesis=np.zeros((2, n_p, 4), complex), band_freq_hz=np.arange(4.0),
                      meta={"significance_in_group": [0.5] * k}, frequency_std_hz=np.zeros(k))

    def classes_of(m):
        return classify(m.freq_hz, m.shapes, th, LOCS, m.significance, m.damping_ratio,
                        m.meta.get("significance_in_group"), mixed=mixed)

    out, classes = without_misreads(res, classes_of, symmetric=symmetric)
    weak = [c for c, f in zip(classes, out.freq_hz) if f == 97.0]
    if kept_as is None:
        assert not weak and len(out.rejected) == 1 and "misread order" in out.rejected[0]["reason"]
    else:
        assert len(weak) == 1 and not out.rejected
        assert weak[0].n == kept_as and weak[0].aliased == (kept_as != 1)
        assert weak[0].other_family == (kept_as == 1) and not weak[0].in_order
    assert [(c.n, c.branch) for c, f in zip(classes, out.freq_hz) if f != 97.0] == \
        [(n, "same") for n in range(1, 7)] + [(n, "opposite") for n in range(1, 7)]


def test_a_weak_mode_whose_alias_only_its_read_branch_contradicts_stays_an_alias():
    """The weak reading of the test above moved to the opposite branch (at 215 Hz, between
    its n = 3 and 4, sidewall against the tread): the opposite branch contradicts its alias,
    but the same-direction branch lies wholly below it and does not. A mode weak in the
    physical FRFs has no branch reading to trust, so it is read as the alias n = 23, as
    before session 38 (a held-out ring with sidewall coupling: its same n = 35 at 418 Hz, 2 %
    of its band's response, read on the opposite branch)."""
    n_p = 24
    th = 2 * np.pi * np.arange(n_p) / n_p
    modes = [(40.0 + 14 * n, n, 0.5) for n in range(1, 7)] + [(180.0 + 10 * n, n, -0.5) for n in range(1, 7)]
    modes.insert(9, (215.0, 1, -0.5))
    S = np.zeros((len(modes), 2, n_p), complex)
    for r, (_, n, ratio) in enumerate(modes):
        S[r, 0] = np.cos(n * th)
        S[r, 1] = ratio * S[r, 0]
    sig = np.array([0.10 if f == 215.0 else 0.6 for f, _, _ in modes])
    cls = classify(np.array([f for f, _, _ in modes]), S, th, LOCS, sig, np.full(len(modes), 0.02),
                   [0.5] * len(modes))
    weak = cls[9]
    assert weak.aliased and weak.n == 23 and not weak.other_family


@pytest.mark.parametrize("symmetric, zeta_b, dropped", [(True, 0.035, True), (False, 0.035, False),
                                                         (True, 0.01, False)])
def test_a_split_pair_on_a_symmetric_structure_loses_its_weaker_broader_member(symmetric, zeta_b, dropped):
    """n = 2 … 5 rising at ζ 2 %, and a second n = 3 reading 3 Hz above the first, weak
    (5 % of the response). On a structure symmetric about its sensors cos and sin modes of
    one order share one frequency: broader than its partner (ζ 3.5 %) it is a blend,
    dropped, and the n = 3 at 160 Hz is no pair member. With the symmetry broken (a mass)
    the two are a split pair; narrower than its partner (ζ 1 %) it is a mode of its own."""
    res, th = _result([150.0, 160.0, 163.0, 170.0, 180.0], [2, 3, 3, 4, 5], [0.6, 0.6, 0.05, 0.6, 0.6],
                      zeta=[0.02, 0.02, zeta_b, 0.02, 0.02])
    out, classes = without_misreads(res, _classifier(th), symmetric=symmetric)
    if dropped:
        assert out.freq_hz.tolist() == [150.0, 160.0, 170.0, 180.0] and all(c.pair is None for c in classes)
        assert len(out.rejected) == 1 and "no split-pair member" in out.rejected[0]["reason"]
    else:
        assert out.freq_hz.size == 5 and not out.rejected
        assert classes[1].pair is not None and classes[1].pair == classes[2].pair


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_the_added_masss_blends_are_not_adopted(tmp_path):
    """The paper's point mass (0.5 kg): its order groups' blends at 170–183 Hz (6 of 50
    adopted until session 14, none within 0.3 % of a truth mode) are gone, dropped as
    misreads; nothing found is lost and the diagnosis stays right."""
    case = next(c for c in matrix() if c.name == "paper:physics=added_mass")  # the matrix's seed
    with threadpool_limits(1):  # as the matrix runs it (BLAS threads change the last digits)
        rec = run_case(case, tmp_path)
    assert rec["status"] == "ok"
    assert rec["spurious"] == 0 and rec["found"] >= 37 and rec["diagnosis_right"]
    dropped = [r["frequency_hz"] for r in read_modal(tmp_path / "run" / "modal.h5").rejected
               if "misread order" in r["reason"]]
    truth = np.array([m["frequency_hz"] for m in simulate(config_for(case)).truth["modes"]])
    blends = [f for f in dropped if 168.0 < f < 183.5]
    assert len(blends) >= 6 and all(np.min(np.abs(truth / f - 1)) > TOLERANCE for f in blends)


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_the_ring_sidewall_shears_weak_n1_is_read_as_n1(tmp_path):
    """The finite-element ring with sidewall shear (its truth, not the estimator's model):
    a second same-direction n = 1 at 98.32 Hz, 0.015 Hz from the branch's n = 4 and 10 % of
    the physical response there, was read as the alias n = 33 until session 38; it is found
    as n = 1, with every other expected mode, and the diagnosis stays right."""
    case = next(c for c in matrix() if c.name == "ring:physics=sidewall_shear")  # the matrix's seed
    with threadpool_limits(1):
        rec = run_case(case, tmp_path)
    assert rec["status"] == "ok" and rec["diagnosis_right"]
    n1 = [d for d in rec["detail"] if d["n"] == 1 and d["branch"] == "same" and 95 < d["frequency_hz"] < 100]
    assert len(n1) == 1 and n1[0]["status"] == "found"
    assert rec["found"] == rec["expected"] and rec["spurious"] == 0


@pytest.mark.parametrize("by_channels, crowd, dropped", [(True, True, True), (True, False, False),
                                                         (False, True, False)])
def test_a_crowds_blend_kept_apart_by_its_channel_shape_alone_is_dropped(by_channels, crowd, dropped):
    """A pole the merge kept apart by its channel shape alone (``meta["by_channels"]``) in a
    crowd of its alias class is a blend: dropped, once, with its reason; either condition
    alone keeps it (the channel rule's own modes off a crowd; a crowd's rows kept apart by
    their own groups' data or never merged). The others keep their readings (a blend's pole
    lies among the orders it stands for: the crowd test reads the dispersion through it)."""
    res, th = _result([150.0, 160.0, 170.0], [2, 10, 4], [0.6, 0.3, 0.6])
    res = dataclasses.replace(res, meta={**res.meta, "by_channels": [False, by_channels, False]})
    calls = []

    def fake(m):  # the crowd flag as a classification would give it: 160 Hz stands for n = 10, 24, 44
        calls.append(m.freq_hz.size)
        return [Classification(n=int(n), n_spatial=int(n), n_confidence=1.0, aliased=bool(crowd and f == 160.0),
                                branch="opposite", branch_confidence=1.0, crowd=bool(crowd and f == 160.0),
                                n_candidates=(10, 24, 44) if crowd and f == 160.0 else ())
                for f, n in zip(m.freq_hz, m.group)]

    out, classes = without_misreads(res, fake)
    assert out.freq_hz.tolist() == ([150.0, 170.0] if dropped else [150.0, 160.0, 170.0])
    assert len(out.rejected) == int(dropped) and len(classes) == out.freq_hz.size
    assert out.meta["by_channels"] == ([False, False] if dropped else [False, by_channels, False])
    if dropped:
        assert "crowd's blend" in out.rejected[0]["reason"] and "10 24 44" in out.rejected[0]["reason"]
        assert calls == [3]  # the others keep the reading the blend was part of
