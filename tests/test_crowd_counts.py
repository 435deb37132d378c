"""The counts of ``benchmarks/crowds.py`` (how right the modal table's crowd flags are), on
a table and truth groups written here: each row counted against the truth mode of its
branch whose order aliases onto the row's spatial order on the N points, within 0.3 %."""

import importlib.util
import sys
from pathlib import Path

_bench = Path(__file__).parents[1] / "benchmarks"
sys.path.insert(0, str(_bench))
_spec = importlib.util.spec_from_file_location("crowds", _bench / "crowds.py")
crowds = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(crowds)


def _g(f, n, crowd, branch="same"):
    return {"frequency_hz": f, "n": n, "branch": branch, "crowd": crowd, "valid": True}


def _row(f, n, n_spatial, crowd, branch="same"):
    return {"frequency_hz": str(f), "n": str(n), "n_spatial": str(n_spatial), "branch": branch,
            "crowd": "True" if crowd else "False"}


def test_each_flag_against_the_truth_crowd_of_its_alias_class():
    # 34 points: n = 23 aliases onto 11; the truth's n = 12 is a crowd, n = 11 and n = 5 are not
    groups = [_g(159.41, 11, False), _g(161.13, 12, True), _g(98.3, 5, False), _g(166.47, 23, False)]
    rows = [_row(159.40, 11, 11, True),        # flagged, the truth's order alone: false
            _row(161.12, 12, 12, False),       # not flagged, the truth's a crowd: missed
            _row(98.31, 5, 5, False),          # right without a flag
            _row(166.50, 23, 11, False),       # matched through its spatial order 11 (34 - 23)
            _row(300.0, 7, 7, True),           # no truth mode within 0.3 %: not counted
            _row(161.10, 12, 12, True, "opposite")]  # another branch: not counted
    counts, wrong = crowds.crowd_counts(groups, rows, 34)
    assert counts == {"right": 0, "right_alone": 2, "false": 1, "missed": 1}
    assert [(w[1]["n"], w[2]) for w in wrong] == [(11, "false"), (12, "missed")]
    counts, _ = crowds.crowd_counts(groups, [_row(161.12, 12, 12, True)], 34)
    assert counts["right"] == 1
