"""Split pairs where the orders mix (:mod:`tiremodal_cli.modal.mass_splits`): a lumped mass
splits every anti-phase order by about one fraction; a pair split far beyond it is a blend.

The truth is the generators' (the finite-element ring's and the paper model's eigenmodes with
a lumped mass), not the estimator's."""

from types import SimpleNamespace

import numpy as np
import pytest

from tiremodal_cli.modal.mass_splits import SPLIT_MAX_RATIO, outlying_splits
from tiremodal_cli.tyre.simulate import simulate
from tiremodal_cli.workflow.validation import config_for, matrix


def _truth_pairs(tyre: str, name: str):
    """The generator's opposite-branch modes of n ≥ 2 with a mass: (freq Hz, classes), every
    order's two members a split pair."""
    case = next(c for c in matrix(tyre=tyre) if c.name == name)
    modes = [m for m in simulate(config_for(case)).truth["modes"] if m["branch"] == "opposite" and m["n"] >= 2]
    modes.sort(key=lambda m: (m["n"], m["frequency_hz"]))
    by_n = {}
    for m in modes:
        by_n.setdefault(m["n"], []).append(m)
    f, classes = [], []
    for n, members in sorted(by_n.items()):
        assert len(members) == 2, (n, members)  # the mass splits each order's cos/sin pair
        for m in members:
            f.append(m["frequency_hz"])
            classes.append(SimpleNamespace(n=n, branch="opposite", pair=n, splitting_hz=None))
    return np.array(f), classes


CASES = [("gl073a", "ring:physics=mass"), ("car", "ring[car]:physics=mass"),
         ("gl073a", "paper:physics=added_mass"), ("car", "paper[car]:physics=added_mass")]


@pytest.mark.parametrize("tyre, name", CASES)
def test_a_mass_splits_every_anti_phase_order_by_about_one_fraction(tyre, name):
    """The module's premise on the generators' eigenmodes: no anti-phase pair of n ≥ 2 is split
    by more than the ideal ring's bound 5/3 times the median splitting (measured 1.08–1.14), so
    the rule flags none of the truth's pairs."""
    f, classes = _truth_pairs(tyre, name)
    rel = np.abs(f[0::2] - f[1::2]) / (0.5 * (f[0::2] + f[1::2]))
    assert rel.size >= 10 and np.all(rel > 0)
    assert rel.max() < 5 / 3 * np.median(rel)
    assert not outlying_splits(classes, f, np.ones(f.size)).any()


@pytest.mark.parametrize("tyre, name", CASES[:2])
def test_a_member_blended_with_the_order_below_is_the_one_flagged(tyre, name):
    """One order's lower member read halfway to the order below's upper member (a blend with
    that mode's copy in its order group) and weaker than its partner: flagged, and nothing else;
    read at 0.9 × its partner's splitting instead (within the mass's fraction), not flagged."""
    f, classes = _truth_pairs(tyre, name)
    sig = np.full(f.size, 0.6)
    k = 2 * 8  # the lower member of the ninth pair (n = 10)
    blended = f.copy()
    blended[k] = 0.5 * (f[k] + f[k - 1])
    sig[k] = 0.2
    flagged = outlying_splits(classes, blended, sig)
    assert np.flatnonzero(flagged).tolist() == [k]
    mild = f.copy()
    mild[k] = f[k + 1] - 0.9 * SPLIT_MAX_RATIO * (f[k + 1] - f[k])
    assert not outlying_splits(classes, mild, sig).any()


def test_too_few_pairs_or_the_other_branch_are_not_judged():
    """Two pairs give no median to judge by; in-phase pairs (the truth splits only n = 2, 3
    there) are never judged."""
    f = np.array([100.0, 100.5, 200.0, 210.0])
    two = [SimpleNamespace(n=n, branch="opposite", pair=n) for n in (3, 3, 4, 4)]
    assert not outlying_splits(two, f, np.ones(4)).any()
    f6 = np.array([100.0, 100.5, 150.0, 150.75, 200.0, 210.0])
    same = [SimpleNamespace(n=n, branch="same", pair=n) for n in (3, 3, 4, 4, 5, 5)]
    assert not outlying_splits(same, f6, np.ones(6)).any()
    opposite = [SimpleNamespace(n=n, branch="opposite", pair=n) for n in (3, 3, 4, 4, 5, 5)]
    assert np.flatnonzero(outlying_splits(opposite, f6, np.array([1, 1, 1, 1, 0.5, 1]))).tolist() == [4]
