"""ingest: UFF 58 time records and CSV folders into the measurement layout."""

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from tiremodal_cli.io.ingest.csv import read_csv_folder
from tiremodal_cli.io.ingest.uff import read_uff_time, write_uff_time
from tiremodal_cli.io.measurement import read_measurement
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

from conftest import run_cli


@pytest.fixture(scope="module")
def sim():
    return simulate(SimulationConfig(n_points=8, n_hits=2, n_samples=256, sample_rate=1000.0, noise=0.01,
                                     seed=5)).measurement


def test_uff_round_trip_through_cli(tmp_path, sim):
    files, mapping = write_uff_time(tmp_path / ".", sim)
    assert len(files) == 8
    (tmp_path / "map.toml").write_text(
        "[points]\n" + "".join(f'"{k}" = {v!r}\n' for k, v in mapping["points"].items()) + "[channels]\n"
        + "".join(f'"{k}" = {{ name = "{c["name"]}", location = "{c["location"]}", angle_deg = {c["angle_deg"]} }}\n'
                  for k, c in mapping["channels"].items()))
    before = [f.read_bytes() for f in files]
    res = run_cli(["ingest", tmp_path, "-o", tmp_path / "m.h5", "--mapping", tmp_path / "map.toml"])
    assert res.exit_code == 0, res.output
    m = read_measurement(tmp_path / "m.h5")
    assert_array_equal(m.force, sim.force.astype(float))
    assert_array_equal(m.response, sim.response.astype(float))
    assert_allclose(m.point_angle, sim.point_angle, atol=1e-12)
    assert m.sample_rate == 1000.0 and m.channel_location == sim.channel_location
    assert [f.read_bytes() for f in files] == before


def test_uff_channel_options_and_errors(tmp_path, sim):
    write_uff_time(tmp_path, sim)
    chans = {"1:3": ("tread", "tread", 0.0), "2:3": ("sidewall", "sidewall", 0.0)}
    from tiremodal_cli.errors import DataFormatError

    with pytest.raises(DataFormatError, match="response 3:3 is not in the channel mapping"):
        read_uff_time([tmp_path], chans)
    res = run_cli(["ingest", tmp_path, "-o", tmp_path / "m.h5", "--channel", "1:3=tread,tread,0",
                   "--channel", "2:3=sidewall,sidewall,0", "--channel", "3:3=rim,rim,0"])
    assert res.exit_code == 0, res.output
    m = read_measurement(tmp_path / "m.h5")
    assert_allclose(m.point_angle, 2 * np.pi * np.arange(8) / 8)  # uniform without [points]
    res = run_cli(["ingest", tmp_path, "-o", tmp_path / "n.h5"])
    assert res.exit_code == 2 and "needs the channels" in res.stderr
    res = run_cli(["ingest", tmp_path, "-o", tmp_path / "n.h5", "--channel", "1:3=tread,hub,0"])
    assert res.exit_code == 2 and "location 'hub'" in res.stderr
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "x.uff").write_text("this is not a universal file\n")
    res = run_cli(["ingest", bad, "-o", tmp_path / "n.h5", "--channel", "1:3=t,tread,0"])
    assert res.exit_code == 2 and len(res.stderr.strip().splitlines()) == 1


def _write_csv(folder, sim, stacked):
    folder.mkdir()
    t = np.arange(sim.n_samples) / sim.sample_rate
    head = "time_s,force_N," + ",".join(sim.channel_name)
    for p in range(sim.n_points):
        rows = []
        for h in range(sim.n_hits):
            block = np.column_stack([t, sim.force[p, h], sim.response[p, h].T])
            if stacked:
                rows.append(np.column_stack([np.full(t.size, h + 1), block]))
            else:
                np.savetxt(folder / f"point{p + 1:02d}_hit{h + 1}.csv", block, delimiter=",", header=head,
                           comments="", fmt="%.9g")
        if stacked:
            np.savetxt(folder / f"point{p + 1}.csv", np.vstack(rows), delimiter=",", header="hit," + head,
                       comments="", fmt="%.9g")
    (folder / "channels.csv").write_text("name,location,angle_deg\n" + "".join(
        f"{n},{loc},0\n" for n, loc in zip(sim.channel_name, sim.channel_location)))


@pytest.mark.parametrize("stacked", [False, True])
def test_csv_folder_both_layouts(tmp_path, sim, stacked):
    _write_csv(tmp_path / "csv", sim, stacked)
    res = run_cli(["ingest", tmp_path / "csv", "-o", tmp_path / "m.h5", "--json"])
    assert res.exit_code == 0, res.output
    m = read_measurement(tmp_path / "m.h5")
    assert_allclose(m.response, sim.response, rtol=1e-6, atol=1e-6 * np.abs(sim.response).max())
    assert m.sample_rate == pytest.approx(1000.0) and m.n_hits == 2 and m.n_points == 8


def test_csv_errors(tmp_path, sim):
    _write_csv(tmp_path / "csv", sim, False)
    (tmp_path / "csv" / "channels.csv").unlink()
    m = run_cli(["ingest", tmp_path / "csv", "-o", tmp_path / "m.h5"])
    assert m.exit_code == 2 and "channel column 'tread' has no location" in m.stderr
    (tmp_path / "csv" / "point01_hit2.csv").unlink()
    with pytest.raises(Exception, match="different numbers of hits"):
        read_csv_folder(tmp_path / "csv", {n: (n, "tread", 0.0) for n in sim.channel_name})


def test_bundled_uff_sample_is_the_bundled_measurement(tmp_path):
    """sample_data/uff (UFF 58, binary) ingests to exactly sample_data/gl073a_sim.h5."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1] / "sample_data"
    res = run_cli(["ingest", root / "uff", "-o", tmp_path / "m.h5", "--mapping", root / "uff" / "mapping.toml",
                   "--json"])
    assert res.exit_code == 0, res.output
    a, b = read_measurement(tmp_path / "m.h5"), read_measurement(root / "gl073a_sim.h5")
    assert_array_equal(a.force, b.force.astype(float))
    assert_array_equal(a.response, b.response.astype(float))
    assert_allclose(a.point_angle, b.point_angle, atol=1e-9)
    assert a.sample_rate == b.sample_rate and a.channel_name == b.channel_name


def test_csv_non_number_names_the_files_line_and_column(tmp_path):
    """A bad cell is named by the file's own line (1-based, the header is line 1) and the
    column's number and name (numpy counts data rows from 0)."""
    d = tmp_path / "csv"
    d.mkdir()
    (d / "point1_hit1.csv").write_text("time_s,force_N,a1\n0,1,2\n0.001,abc,3\n")
    from tiremodal_cli.errors import DataFormatError

    with pytest.raises(DataFormatError, match=r"line 3, column 2 \('force_N'\): 'abc' is not a number"):
        read_csv_folder(d, {"a1": ("a1", "tread", 0.0)})
