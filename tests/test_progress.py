"""-q silences run's progress, -v adds tiremodal's own messages (not other libraries'),
and run's stage bar shows on a terminal only."""

from __future__ import annotations

import logging

import pytest

from tiremodal_cli.measurement import write_measurement

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
    assert piped.stderr == ""  # a log gets no bar


def test_v_speaks_for_tiremodal_not_for_other_libraries(meas, tmp_path, monkeypatch):
    res = _run(meas, tmp_path / "a", "-v", tty=False, monkeypatch=monkeypatch)
    assert "tiremodal: INFO: run: lsce" in res.stderr
    # another library's info (matplotlib's, h5py's …) stays out of -v and -vv
    res = run_cli(["-vv", "info", meas])
    assert res.exit_code == 0
    logging.getLogger("matplotlib.font_manager").info("font cache rebuilt")
    logging.getLogger("matplotlib").debug("noise")
    assert logging.getLogger("matplotlib").getEffectiveLevel() >= logging.WARNING
    assert logging.getLogger("tiremodal_cli.x").getEffectiveLevel() == logging.DEBUG
