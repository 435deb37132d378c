"""-q silences run's progress, -v adds tiremodal's own messages (not other libraries'),
and run's stage bar shows on a terminal only."""

from __future__ import annotations

import logging

import pytest

from tiremodal_cli.io.measurement import write_measurement
from tiremodal_cli.workflow.run_options import MANIFEST, OUTPUTS

from conftest import run_cli


@pytest.fixture(scope="module")
def meas(tmp_path_factory, noisy_sim):
    p = tmp_path_factory.mktemp("progress") / "m.h5"
    write_measurement(p, noisy_sim.measurement)
    return p


def _run(meas, out, *flags, tty: bool, monkeypatch):
    from tiremodal_cli.cli import options

    monkeypatch.setattr(options, "_tty", lambda: tty)
    import click._termui_impl

    monkeypatch.setattr(click._termui_impl, "isatty", lambda f: tty)  # click draws its bar on a terminal only
    res = run_cli([*flags, "run", meas, "-o", out, "--max-effects", 0, "--overwrite"])
    assert res.exit_code == 0, res.output
    return res


def test_run_shows_its_stages_on_a_terminal_and_nothing_with_q(meas, tmp_path, monkeypatch):
    res = _run(meas, tmp_path / "a", tty=True, monkeypatch=monkeypatch)
    # click redraws at most so often: the bar from 0/4 to 4/4 with a stage named on the way
    assert res.stderr.count("\rrun  [") >= 3 and "0/4" in res.stderr and "4/4  done" in res.stderr
    assert any(f"/4  {stage}" in res.stderr for stage in ("lsce", "identify", "diagnose"))
    quiet = _run(meas, tmp_path / "b", "-q", tty=True, monkeypatch=monkeypatch)
    assert quiet.stderr == ""
    assert quiet.stdout == res.stdout.replace(str(tmp_path / "a"), str(tmp_path / "b"))  # the data unchanged
    piped = _run(meas, tmp_path / "c", tty=False, monkeypatch=monkeypatch)
    # a log gets no bar, only what was written (stderr: for people; stdout stays the data)
    assert "\r" not in piped.stderr and piped.stderr.splitlines() == [f"wrote {tmp_path / 'c'}/: {', '.join(OUTPUTS)}, {MANIFEST}"]


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_v_speaks_for_tiremodal_not_for_other_libraries(meas, tmp_path, monkeypatch, caplog):
    """-v: tiremodal's INFO messages (the stages) are emitted, without it they are not; other
    libraries' INFO and DEBUG stay off even with -vv (their warnings only)."""
    caplog.set_level(logging.DEBUG)

    def stages():
        return [r for r in caplog.records if r.name == "tiremodal_cli.progress" and r.levelno == logging.INFO]

    _run(meas, tmp_path / "a", tty=False, monkeypatch=monkeypatch)
    assert stages() == []
    _run(meas, tmp_path / "b", "-v", tty=False, monkeypatch=monkeypatch)
    assert [r.getMessage() for r in stages()] == ["run: frf", "run: lsce", "run: identify", "run: diagnose"]
    assert run_cli(["-vv", "info", meas]).exit_code == 0
    assert logging.getLogger("tiremodal_cli.frf.estimate").isEnabledFor(logging.DEBUG)
    assert not logging.getLogger("matplotlib.font_manager").isEnabledFor(logging.INFO)
    assert not logging.getLogger("h5py").isEnabledFor(logging.INFO)
