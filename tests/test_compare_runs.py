"""``benchmarks/compare_runs.py``: a change that leaves the scorecard's counts as they were but
moves a case's fit is listed (session 13: a rule that scored the same modal tables put the
paper's failed-points case's final fit at 0.09 → 2.1 % RMS), and two identical runs list
nothing but their totals."""

import importlib.util
from pathlib import Path

_path = Path(__file__).parents[1] / "benchmarks" / "compare_runs.py"
_spec = importlib.util.spec_from_file_location("compare_runs", _path)
compare_runs = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(compare_runs)


def _rec(name, generator="paper", found=59, final=0.09, set_aside=5, effects=("timoshenko", "m_w")):
    return {"name": name, "case": {"generator": generator}, "expected": 65, "found": found, "mislabelled": 2,
            "missed": 4, "spurious": 1, "adopted": 69, "base_rms_pct": 17.35, "final_rms_pct": final,
            "set_aside": set_aside, "adopted_effects": list(effects), "diagnosis_right": True}


def test_a_moved_fit_with_the_same_counts_is_listed():
    before = {"a": _rec("a"), "b": _rec("b", generator="ring")}
    after = {"a": _rec("a", final=2.116, set_aside=8), "b": _rec("b", generator="ring")}
    lines = compare_runs.compare(before, after)
    assert lines[0].startswith("paper: ") and "found 59 → 59" in lines[0]
    assert lines[1].startswith("ring: ")
    (case,) = [ln for ln in lines if ln.startswith("a: ")]
    assert "final RMS 0.090 → 2.116 %" in case and "set_aside 5 → 8" in case and "found" not in case
    assert not any(ln.startswith("b: ") for ln in lines)


def test_identical_runs_give_only_their_totals_and_counts_and_effects_are_listed():
    runs = {"a": _rec("a")}
    assert len(compare_runs.compare(runs, runs)) == 1
    lines = compare_runs.compare(runs, {"a": _rec("a", found=60, effects=("timoshenko",))})
    assert lines[-1] == "a: found 59 → 60; effects ['timoshenko', 'm_w'] → ['timoshenko']"
    assert compare_runs.compare(runs, {"a": _rec("a", final=0.095)}) == compare_runs.compare(runs, runs)  # under 0.01
