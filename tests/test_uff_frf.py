"""FRFs from another system (UFF 58, function type 4) through run → report.

The must-show test of #17: a Testlab-style file (header 151, units 164, geometry 15, FRFs
in g with coherence, one channel mounted pointing −Z, i.e. sign-flipped with direction code
−3) written from the FRFs of a run on the bundled sample, taken through ``run`` and
``report``: the same modes and the same fit as the run on the time records.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.frffile import read_frf
from tiremodal_cli.io.frfuff import read_frf_uff

from conftest import run_cli

pyuff = pytest.importorskip("pyuff")

G = 9.80665
SAMPLE = Path(__file__).resolve().parents[1] / "sample_data" / "gl073a_sim.h5"
#: radii of the Testlab geometry's rings, m (any: only the angles and the tread circle matter)
RADII = {"tread": 0.32, "sidewall": 0.25, "rim": 0.2}


def _common(x, **kw):
    d = dict(binary=0, load_case_id=0, abscissa_spacing=1, abscissa_min=float(x[0]),
             abscissa_inc=float(x[1] - x[0]), abscissa_spec_data_type=18, abscissa_len_unit_exp=0,
             abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0, ordinate_len_unit_exp=1,
             ordinate_force_unit_exp=0, ordinate_temp_unit_exp=0, orddenom_len_unit_exp=0,
             orddenom_force_unit_exp=1, orddenom_temp_unit_exp=0, z_axis_spec_data_type=0, z_axis_len_unit_exp=0,
             z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0, z_axis_value=0.0, abscissa_axis_units_lab="Hz",
             z_axis_axis_units_lab="NONE", id2="", id3="23-Nov-26 04:00:00", id4="gl073a", id5="", x=x)
    d.update(kw)
    return d


def write_testlab_uff(path, r, *, flip="sidewall", geometry=True, header=True, plane="xy", tilt=0.0):
    """Write FRFs ``r`` as Simcenter Testlab exports them: 151 header, 164 units (SI),
    15 nodes (points 101…, sensors 1…), per FRF a dataset 58 in g/N and its coherence;
    the ``flip`` channel mounted pointing −Z (direction −3, values negated)."""
    sets = []
    if header:
        sets += [pyuff.prepare_151(model_name="gl073a", description="tyre modal test", db_app="Simcenter Testlab",
                                   date_db_created="23-Nov-26", time_db_created="04:00:00", version_db1=0,
                                   version_db2=0, file_type=0, date_db_saved="23-Nov-26", time_db_saved="04:00:00",
                                   program="Simcenter Testlab 2019.1", date_db_written="23-Nov-26",
                                   time_db_written="04:00:00"),
                 pyuff.prepare_164(units_code=1, units_description="SI - mks (Newton)", temp_mode=2, length=1.0,
                                   force=1.0, temp=1.0, temp_offset=273.15)]
    pn = 101 + np.arange(r.point_angle.size)
    cn = 1 + np.arange(len(r.channel_name))
    if geometry:
        rr = np.array([RADII[loc] for loc in r.channel_location])
        c = np.r_[RADII["tread"] * np.cos(r.point_angle), rr * np.cos(r.channel_angle)]
        d = np.r_[RADII["tread"] * np.sin(r.point_angle), rr * np.sin(r.channel_angle)]
        k = c.size
        axial = tilt * c  # tilt ≠ 0: the points leave the plane
        x, y, z = {"xy": (c, d, axial), "zx": (d, axial, c)}[plane]  # zx: the wheel's axis along y
        sets.append(pyuff.prepare_15(node_nums=np.r_[pn, cn], def_cs=np.zeros(k, int), disp_cs=np.zeros(k, int),
                                     color=np.ones(k, int), x=x, y=y, z=z))
    for ic, loc in enumerate(r.channel_location):
        sg = -1 if loc == flip else 1
        for ip in range(pn.size):
            c = _common(r.freq_hz, rsp_ent_name=f"{loc}:1", rsp_node=int(cn[ic]), rsp_dir=3 * sg,
                        ref_ent_name=f"tread:{ip + 1}", ref_node=int(pn[ip]), ref_dir=3)
            sets.append(pyuff.prepare_58(func_type=4, ordinate_spec_data_type=12, orddenom_spec_data_type=13,
                                         ordinate_axis_units_lab="g", orddenom_axis_units_lab="N", id1="FRF",
                                         data=sg * r.H[ic, ip] / G, **c))
            sets.append(pyuff.prepare_58(func_type=9, ordinate_spec_data_type=0, orddenom_spec_data_type=0,
                                         ordinate_axis_units_lab="NONE", orddenom_axis_units_lab="NONE",
                                         id1="Coherence", data=r.coherence[ic, ip].astype(float), **c))
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return Path(path)


@pytest.fixture(scope="session")
def uff_runs(tmp_path_factory):
    """The sample run from its time records, a Testlab-style UFF of its FRFs, and the run
    and report of that file. Both runs without the exponential window: a UFF file does not
    say which window its FRFs carry, so damping can only be compared on unwindowed FRFs;
    and with the same lsce band (the time-data run's own, from coherence and force
    spectrum: a UFF file has no force spectrum)."""
    d = tmp_path_factory.mktemp("uff_runs")
    res = run_cli(["run", SAMPLE, "-o", d / "orig", "--no-exp-window", "--json"])
    assert res.exit_code == 0, res.output
    orig = json.loads(res.output)
    band = json.loads(__import__("h5py").File(d / "orig" / "modal.h5", "r").attrs["meta"])["band_hz"]
    uff = write_testlab_uff(d / "testlab.uff", read_frf(d / "orig" / "frf.h5"))
    res = run_cli(["run", uff, "-o", d / "uff", "--band", band[0], band[1], "--json"])
    assert res.exit_code == 0, res.output
    res2 = run_cli(["report", d / "uff"])
    assert res2.exit_code == 0, res2.output
    return {"dir": d, "orig": orig, "uff": json.loads(res.output), "file": uff,
            "report": d / "uff" / "report.html"}


def _modes(folder):
    with open(folder / "modes.csv", newline="") as f:
        return list(csv.DictReader(f))


@pytest.mark.slow  # 15-110 s: a whole test through the modal stage; run with `pytest -m slow` (README)
def test_testlab_uff_gives_the_same_modes_and_fit(uff_runs):
    """Same modes: every mode of the time-data run is found again with its frequency within
    1e-6 and damping within 1e-4 (relative) and the same n and branch; no other mode
    appears. (At n = N/2 the sine component is sampled at its zeros and that order's reading
    turns on the points' angles to 1e-7 rad: the geometry's six digits give it because points
    within their rounding of a uniform grid are put on it, uffgeometry.snap_to_uniform_grid.)
    Same fit: identify's and the final model's parameters within one standard error of
    each other, the same effect adopted, the RMS errors after apart by < 0.01 % (points)."""
    d, a, b = uff_runs["dir"], uff_runs["orig"], uff_runs["uff"]
    ma, mb = _modes(d / "orig"), _modes(d / "uff")
    assert len(ma) >= 30 and len(ma) == len(mb)
    assert any(m["n"] and int(m["n"]) == a["n_points"] // 2 for m in ma)  # the order N/2 is in it
    for x, y in zip(ma, mb):
        assert float(y["frequency_hz"]) == pytest.approx(float(x["frequency_hz"]), rel=1e-6)
        assert float(y["damping_ratio"]) == pytest.approx(float(x["damping_ratio"]), rel=1e-4)
        assert (y["n"], y["branch"]) == (x["n"], x["branch"])
    assert b["adopted_effects"] == a["adopted_effects"] == ["sidewall_membrane"]
    for key in ("identified", "augmented_parameters"):
        for k, v in a[key].items():
            w = b[key][k]
            assert abs(w["value"] - v["value"]) < min(v["std_error"], w["std_error"]), (key, k, v, w)
    # RMS errors after: both at the noise level, apart by less than a tenth of run's noise floor (0.1 %)
    assert abs(b["rms_after_pct"] - a["rms_after_pct"]) < 0.01 and b["rms_after_pct"] < 0.1
    # what was read, stated: g → m/s² (× 9.80665), the flipped sidewall, geometry from 15
    src = b["frf_source"]
    assert src["unit_in_file"] == "g/N" and src["to_si"] == pytest.approx(G)
    assert src["sign_flipped"] == ["2:-3"] and src["geometry"] == "the nodes of dataset 15"
    assert b["starts_at"] == "lsce" and src["header"]["program"].startswith("Simcenter Testlab")


def test_uff_frfs_are_the_run_frfs_in_si(uff_runs):
    """The file read back: the FRFs equal the time-data run's (to the 12 digits pyuff
    writes), the flipped channel positive outwards again, locations from the entity names,
    angles from the geometry to its six significant digits."""
    r0 = read_frf(uff_runs["dir"] / "orig" / "frf.h5")
    r = read_frf_uff(uff_runs["file"])
    np.testing.assert_allclose(r.H, r0.H, rtol=0, atol=1e-10 * np.abs(r0.H).max())
    assert r.channel_location == r0.channel_location
    np.testing.assert_allclose(np.angle(np.exp(1j * (r.point_angle - r0.point_angle))), 0, atol=1e-5)


def test_report_says_the_pipeline_started_at_lsce(uff_runs):
    text = uff_runs["report"].read_text(encoding="utf-8")
    assert "the pipeline started at lsce" in text
    assert "g/N in the file, × 9.80665" in text and "2:-3" in text


def test_run_without_geometry_or_mapping_is_one_line_exit_2(tmp_path, exact_sim):
    from tiremodal_cli.frf.estimate import FRFOptions, compute_frf

    r = compute_frf(exact_sim.measurement, FRFOptions(band_hz=(0.0, 300.0)))
    path = write_testlab_uff(tmp_path / "nogeo.uff", r, geometry=False)
    res = run_cli(["run", path, "-o", tmp_path / "out"])
    assert res.exit_code == 2
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "nothing says where the impact points are" in lines[0] and "--mapping" in lines[0]
    assert not (tmp_path / "out").exists()


def test_mapping_places_the_points_when_the_file_does_not(tmp_path, exact_sim):
    """The same file with a mapping's [points] and [channels]: read with those angles."""
    from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
    from tiremodal_cli.io.ingest import load_channel_map

    r = compute_frf(exact_sim.measurement, FRFOptions(band_hz=(0.0, 300.0)))
    path = write_testlab_uff(tmp_path / "nogeo.uff", r, geometry=False)
    mp = tmp_path / "mapping.toml"
    mp.write_text("[points]\n" + "".join(f'"{101 + i}" = {np.rad2deg(a):.9f}\n' for i, a in enumerate(r.point_angle))
                  + "[channels]\n" + "".join(f'"{i + 1}:3" = {{ name = "{n}", location = "{loc}", angle_deg = '
                                             f'{np.rad2deg(a):.9f} }}\n' for i, (n, loc, a) in
                                             enumerate(zip(r.channel_name, r.channel_location, r.channel_angle))))
    ch, pts = load_channel_map(mp)
    got = read_frf_uff(path, channels=ch, points=pts, require_geometry=True)
    np.testing.assert_allclose(got.point_angle, r.point_angle, atol=1e-9)
    assert got.channel_name == r.channel_name and got.meta["uff"]["geometry"] == "the mapping's [points]"
    live = [i for i, n in enumerate(r.channel_name) if n not in r.dead_channels]
    np.testing.assert_allclose(got.H[live], r.H[live], rtol=0, atol=1e-10 * np.nanmax(np.abs(r.H)))


def _one_frf(path, data, *, spec, num, den, units164=None):
    x = np.arange(32, dtype=float)
    sets = [] if units164 is None else [pyuff.prepare_164(units_code=2, units_description="mm-N", temp_mode=2,
                                                          length=units164[0], force=units164[1], temp=1.0,
                                                          temp_offset=273.15)]
    sets.append(pyuff.prepare_58(func_type=4, ordinate_spec_data_type=spec, orddenom_spec_data_type=13,
                                 ordinate_axis_units_lab=num, orddenom_axis_units_lab=den, id1="FRF",
                                 data=data, **_common(x, rsp_ent_name="x", rsp_node=1, rsp_dir=3, ref_ent_name="y",
                                                      ref_node=101, ref_dir=3)))
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


@pytest.mark.parametrize("spec,num,den,units164,form,factor", [
    (11, "mm/s", "N", None, "mobility", 1e-3),          # velocity in mm/s per N
    (12, "m/s^2/N", "NONE", None, "accelerance", 1.0),  # one label holding both
    (12, "g", "lbf", None, "accelerance", G / 4.4482216152605),
    (8, "NONE", "NONE", (1000.0, 1.0), "receptance", 1e-3),  # dataset 164: mm, N
    (12, "", "", None, "accelerance", 1.0),             # nothing says: SI, stated as assumed
])
def test_units_to_si(tmp_path, spec, num, den, units164, form, factor):
    data = (1.0 + 2.0j) * np.ones(32)
    r = read_frf_uff(_one_frf(tmp_path / "a.uff", data, spec=spec, num=num, den=den, units164=units164))
    assert r.form == form
    np.testing.assert_allclose(r.H[0, 0], factor * data, rtol=1e-9)
    assert r.meta["uff"]["to_si"] == pytest.approx(factor)
    if not num and units164 is None:
        assert r.meta["uff"]["from"].startswith("assumed SI")


@pytest.mark.parametrize("spec,num,msg", [(11, "g", "is a accelerance unit"), (12, "furlong/s^2", "not one tiremodal")])
def test_units_that_contradict_or_are_unknown_are_refused(tmp_path, spec, num, msg):
    path = _one_frf(tmp_path / "a.uff", np.ones(32, complex), spec=spec, num=num, den="N")
    with pytest.raises(DataFormatError, match=msg.split(" a ")[-1]):
        read_frf_uff(path)


def test_info_reads_uff_frfs(uff_runs):
    res = run_cli(["info", uff_runs["file"], "--json"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.output)
    assert d["format"] == "UFF 58 FRFs" and d["unit_in_file"] == "g/N" and d["n_points"] == 34
    assert d["sign_flipped"] == ["2:-3"]


def test_batch_runs_a_folder_of_uff_frfs(uff_runs, tmp_path):
    """A campaign folder holding a test as UFF FRFs: batch runs it from lsce (not as time
    records), with the same modes as run."""
    import shutil

    (tmp_path / "camp" / "t1").mkdir(parents=True)
    shutil.copy(uff_runs["file"], tmp_path / "camp" / "t1" / "frfs.uff")
    (tmp_path / "fast.toml").write_text(f"[run]\nband = {json.dumps(json.loads(json.dumps(_band(uff_runs))))}\n")
    res = run_cli(["batch", tmp_path / "camp", "-o", tmp_path / "out", "--config", tmp_path / "fast.toml", "--json"])
    assert res.exit_code == 0, res.output
    man = json.loads((tmp_path / "out" / "t1" / "run.json").read_text())
    assert man["summary"]["starts_at"] == "lsce" and man["summary"]["modes_found"] == uff_runs["uff"]["modes_found"]


def _band(uff_runs):
    import h5py

    with h5py.File(uff_runs["dir"] / "uff" / "modal.h5", "r") as h:
        return json.loads(h.attrs["meta"])["band_hz"]


def test_geometry_in_another_plane_and_off_any_plane(tmp_path, exact_sim):
    """A wheel whose axis is y (the tyre in the ZX plane): the same angles, about that axis.
    Points that lie in no coordinate plane: one line saying so, and what is allowed."""
    from tiremodal_cli.frf.estimate import FRFOptions, compute_frf

    r = compute_frf(exact_sim.measurement, FRFOptions(band_hz=(0.0, 300.0)))
    got = read_frf_uff(write_testlab_uff(tmp_path / "zx.uff", r, plane="zx"))
    np.testing.assert_allclose(np.angle(np.exp(1j * (got.point_angle - r.point_angle))), 0, atol=1e-5)
    np.testing.assert_allclose(np.angle(np.exp(1j * (got.channel_angle - r.channel_angle))), 0, atol=1e-5)
    with pytest.raises(DataFormatError, match="do not lie in one coordinate plane"):
        read_frf_uff(write_testlab_uff(tmp_path / "tilt.uff", r, tilt=0.2))


def test_points_on_a_rounded_uniform_grid_are_put_on_it_and_hand_marked_ones_are_not():
    """Six significant digits (dataset 15) of a uniform 34-point grid from 10°: the angles come
    back exactly uniform; a grid marked by hand (1 mm errors on a 0.65 m radius) stays as
    measured."""
    from tiremodal_cli.io.uffgeometry import snap_to_uniform_grid as _uniform_grid

    N, R = 34, 0.65
    th = np.deg2rad(10) + 2 * np.pi * np.arange(N) / N
    rounded = {k + 1: (float(np.arctan2(float(f"{R * np.sin(t):.5e}"), float(f"{R * np.cos(t):.5e}"))), R)
               for k, t in enumerate(th)}
    got = np.array([v[0] for v in _uniform_grid(rounded, list(range(1, N + 1))).values()])
    # exactly uniform (the spacing 2π/N to rounding); the grid's start within the file's rounding
    np.testing.assert_allclose(np.angle(np.exp(1j * np.diff(got))), 2 * np.pi / N, atol=1e-12)
    assert abs(np.angle(np.exp(1j * (got[0] - th[0])))) < 1e-6
    assert max(abs(rounded[k + 1][0] - np.angle(np.exp(1j * th[k]))) for k in range(N)) > 1e-8  # it was off
    rng = np.random.default_rng(3)
    marked = {k + 1: (float(t + rng.normal(0, 1e-3 / R)), R) for k, t in enumerate(th)}
    assert _uniform_grid(marked, list(range(1, N + 1))) == marked


def test_our_own_uff_export_is_read_back_without_a_mapping(tmp_path, exact_sim):
    """``frf --uff`` writes dataset 15 with the points and sensors at their angles: the
    file reads back (as run and lsce read it) with the test's point angles, and the
    channels' locations from their names."""
    from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
    from tiremodal_cli.io.frfuff import write_frf_uff
    from tiremodal_cli.workflow.pipeline import read_uff_test

    r = compute_frf(exact_sim.measurement, FRFOptions(band_hz=(0.0, 300.0)))
    back, _ = read_uff_test([write_frf_uff(tmp_path / "own.uff", r)])
    d = np.angle(np.exp(1j * (back.point_angle - r.point_angle)))
    assert np.max(np.abs(d)) < 1e-5  # dataset 15 holds six significant digits
    assert back.channel_location == r.channel_location
    assert np.allclose(back.H, r.H, rtol=1e-4, atol=1e-6 * np.abs(r.H).max())
