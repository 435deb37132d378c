"""``benchmarks/confidence.py``: which table rows are readings of a truth branch and order,
and the calibration bins, on rows and truth written here."""

import importlib.util
from pathlib import Path

import pytest

_spec = importlib.util.spec_from_file_location("confidence", Path(__file__).parents[1] / "benchmarks" / "confidence.py")
confidence = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(confidence)

TRUTH = [{"frequency_hz": 100.0, "n": 3, "branch": "opposite"},
         {"frequency_hz": 200.0, "n": 8, "branch": "same"},
         {"frequency_hz": 200.4, "n": 2, "branch": "opposite"},  # 0.2 % from the n = 8 same
         {"frequency_hz": 300.0, "n": 2, "branch": "cavity"}]


def _row(f, branch="opposite", n=3, aliased=False):
    return {"frequency_hz": str(f), "branch": branch, "branch_confidence": "0.8", "n": str(n),
            "n_confidence": "1.0", "n_aliased": str(aliased)}


@pytest.mark.parametrize("f, kept", [
    (100.2, True),    # within 0.3 % of one opposite mode
    (100.5, False),   # 0.5 % off every truth mode
    (200.2, False),   # within 0.3 % of a same and an opposite mode: no one branch
    (300.0, False),   # a cavity mode: no branch label for it
])
def test_a_reading_needs_truth_of_one_labelled_branch(f, kept):
    assert (confidence.reading(_row(f), TRUTH) is not None) is kept


def test_a_reading_carries_the_truths_branch_and_orders():
    r = confidence.reading(_row(100.2, branch="same", n=5, aliased=True), TRUTH)
    assert (r["truth_branch"], r["truth_n"], r["branch"], r["n"], r["aliased"]) == ("opposite", [3], "same", 5, True)


def test_a_row_without_a_branch_is_no_reading():
    assert confidence.reading(_row(100.2, branch=""), TRUTH) is None


def test_calibration_bins_count_and_share():
    out = confidence.calibration([0.2, 0.3, 0.95, 1.0, 1.0], [True, False, True, True, False])
    assert [(lo, n) for lo, _, n, _, _ in out] == [(0.0, 2), (0.9, 1), (0.99, 2)]
    assert [share for *_, share in out] == [0.5, 1.0, 0.5]
