"""The classes of ``benchmarks/spurious.py`` (what a validation case's spurious modes are),
on a table and a truth written here: distances in half-power half-widths of the truth."""

import importlib.util
from pathlib import Path

import pytest

_spec = importlib.util.spec_from_file_location("spurious", Path(__file__).parents[1] / "benchmarks" / "spurious.py")
spurious = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(spurious)

# two truth modes of ζ = 2 %: half-power half-widths 2 Hz (100 Hz) and 4 Hz (200 Hz)
TRUTH = [{"frequency_hz": 100.0, "damping_ratio": 0.02, "n": 3, "branch": "opposite"},
         {"frequency_hz": 200.0, "damping_ratio": 0.02, "n": 8, "branch": "opposite"}]


@pytest.mark.parametrize("rows, expected", [
    ([100.1], []),                                # within 0.3 %: not spurious
    ([100.8], ["biased"]),                        # 0.4 half-widths off, t not reported
    ([100.0, 100.8], ["copy"]),                   # the same, t reported by another row
    ([102.0], ["between"]),                       # 1 half-width
    ([150.0], ["far"]),                           # 12.5 half-widths from both
    ([199.0, 200.0, 206.0], ["copy", "between"]),  # 0.25 and 1.5 half-widths of the 200 Hz mode
])
def test_classes_by_half_widths_of_the_nearest_truth_mode(rows, expected):
    out = spurious.classify_spurious([{"frequency_hz": f} for f in rows], TRUTH)
    assert [s["class"] for s in out] == expected
