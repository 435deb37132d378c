"""Mode shapes out (tiremodal_cli/export.py): UFF 15/82/55 read back by pyuff, CSV, physics."""

import dataclasses

import numpy as np
import pytest

from tiremodal_cli.errors import DataFormatError
from tiremodal_cli.io.export import RING_BASE, nodes_csv, shape_set, shapes_csv, write_uff
from tiremodal_cli.frf.estimate import FRFOptions, compute_frf
from tiremodal_cli.modal.modes import ModalOptions, modal_table_from_frf


@pytest.fixture(scope="module")
def table(exact_sim):
    r = compute_frf(exact_sim.measurement, FRFOptions(band_hz=(0.0, 640.0)))
    t, _ = modal_table_from_frf(r, ModalOptions(band_hz=(40.0, 300.0)))
    return t


def test_rings_and_scaling(table):
    s = shape_set(table, radii_m={"tread": 0.65, "sidewall": 0.45, "rim": 0.25})
    n_p = table.point_angle.size
    assert s.node.size == 3 * n_p and s.left_out == ()
    assert set(s.node[:n_p]) == set(RING_BASE["tread"] + 1 + table.point_index)
    np.testing.assert_allclose(np.hypot(s.xyz_m[:, 0], s.xyz_m[:, 1]), [0.65] * n_p + [0.45] * n_p + [0.25] * n_p)
    np.testing.assert_allclose(np.max(np.abs(s.radial[:, :n_p]), axis=1), 1.0)


def test_shapes_are_the_tyres_orders_and_branches(table):
    """A mode classified n, branch: its tread ring lies in the span of cos nθ and sin nθ
    (share of its energy > 0.99: a standing or, for a degenerate pair, travelling wave of
    order n), and its sidewall ring moves with the tread (same) or against it
    (opposite): the sign of Re(sidewall / tread) at the largest tread value. Checked on the
    modes that stand clear of their neighbours (no other table mode within one half-power
    bandwidth 2ζf), where the estimated shape is not a mixture."""
    s = shape_set(table)
    n_p = table.point_angle.size
    th = np.asarray(table.point_angle)
    checked = 0
    for k in range(table.n_modes):
        n, b = int(table.n[k]), table.branch[k]
        f = table.frequency_hz[k]
        clear = np.sum(np.abs(table.frequency_hz - f) < 2 * table.damping_ratio[k] * f) == 1
        if b not in ("same", "opposite") or not 1 <= n < n_p / 2 or not clear:
            continue
        u = s.radial[k, :n_p]
        basis = np.stack([np.cos(n * th), np.sin(n * th)], axis=1).astype(complex)
        fit = basis @ np.linalg.lstsq(basis, u, rcond=None)[0]
        share = np.vdot(fit, fit).real / np.vdot(u, u).real
        assert share > 0.99, (k, n, b, share)
        j = np.argmax(np.abs(s.radial[k, :n_p]))
        ratio = (s.radial[k, n_p + j] / s.radial[k, j]).real
        assert (ratio > 0) == (b == "same"), (k, n, b, ratio)
        checked += 1
    assert checked >= 4


def test_uff_read_back_by_pyuff_equals_the_modal_table(table, tmp_path):
    pyuff = pytest.importorskip("pyuff")
    s = shape_set(table)
    path = tmp_path / "shapes.uff"
    write_uff(path, s)
    sets = pyuff.UFF(str(path)).read_sets()
    kinds = [d["type"] for d in sets]
    assert kinds.count(15) == kinds.count(2411) == 1 and kinds.count(82) == 3 and kinds.count(55) == table.n_modes
    for kind in (15, 2411):
        nodes = next(d for d in sets if d["type"] == kind)
        np.testing.assert_allclose(nodes["x"], s.xyz_m[:, 0], atol=1e-6)
        np.testing.assert_allclose(nodes["y"], s.xyz_m[:, 1], atol=1e-6)
    n_p = table.point_angle.size
    tread = table.shapes[:, list(table.channel_location).index("tread"), :]
    for k, d in enumerate(x for x in sets if x["type"] == 55):
        assert list(d["node_nums"]) == list(s.node)
        radial = np.asarray(d["r1"]) * np.cos(s.angle_rad) + np.asarray(d["r2"]) * np.sin(s.angle_rad)
        # UFF 55 stores values as E13.5: equal to the table's residues to that precision
        want = tread[k] / tread[k][np.argmax(np.abs(tread[k]))]
        np.testing.assert_allclose(radial[:n_p], want, atol=2e-5)
        # the eigenvalue carries the table's (window-corrected) frequency and damping
        lam = complex(d["eig"])
        assert abs(lam) / (2 * np.pi) == pytest.approx(table.frequency_hz[k], rel=1e-5)
        assert -lam.real / abs(lam) == pytest.approx(table.damping_ratio[k], rel=1e-4)
    traces = [d for d in sets if d["type"] == 82]
    assert all(t["nodes"][0] == t["nodes"][-1] for t in traces)  # closed rings


def test_csv_forms(table):
    s = shape_set(table)
    lines = nodes_csv(s).splitlines()
    assert lines[0] == "node,ring,angle_deg,x_m,y_m,z_m" and len(lines) == 1 + s.node.size
    rows = shapes_csv(s).splitlines()
    assert len(rows) == 1 + table.n_modes * s.node.size


def test_dead_channel_is_left_out_with_its_reason(table):
    shapes = table.shapes.copy()
    shapes[:, list(table.channel_location).index("rim"), :] = 0
    s = shape_set(dataclasses.replace(table, shapes=shapes))
    assert "rim" not in s.ring and len(s.left_out) == 1 and "dead channel" in s.left_out[0]
    shapes[:, list(table.channel_location).index("tread"), :] = np.nan
    with pytest.raises(DataFormatError, match="no tread channel"):
        shape_set(dataclasses.replace(table, shapes=shapes))


def test_mode_gif_moves_and_stays_small(table):
    import io

    from PIL import Image

    from tiremodal_cli.plots import mode_gif

    s = shape_set(table)
    k = int(np.argmax(table.mpc))
    data = mode_gif(s, k, frames=8)
    im = Image.open(io.BytesIO(data))
    assert im.format == "GIF" and im.n_frames == 8 and im.size == (144, 144)
    frames = []
    for i in (0, 2):  # a quarter period apart: the rings have moved
        im.seek(i)
        frames.append(np.asarray(im.convert("L"), dtype=float))
    assert np.mean(np.abs(frames[0] - frames[1])) > 0.5
    assert len(data) < 150_000  # 34 modes stay well under a 10 MB report


def test_export_command(table, tmp_path):
    from conftest import run_cli

    from tiremodal_cli.io.modalfile import write_modal

    modal = tmp_path / "modal.h5"
    write_modal(modal, table, input_file="x", input_sha256="0" * 64)
    before = modal.read_bytes()
    res = run_cli(["export", modal, "-o", tmp_path / "shapes", "--format", "csv", "--radius", "tread=0.6"])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "shapes").iterdir()) == ["nodes.csv", "shapes.csv"]
    assert "0.6," in (tmp_path / "shapes" / "nodes.csv").read_text().splitlines()[1]
    res = run_cli(["export", modal, "-o", tmp_path / "shapes"])  # exists, no --overwrite
    assert res.exit_code == 2 and "--overwrite" in res.output
    res = run_cli(["export", tmp_path, "-o", tmp_path / "inside"])
    assert res.exit_code == 2 and "inside the input" in res.output
    assert not (tmp_path / "inside").exists() and modal.read_bytes() == before
    assert not [p for p in tmp_path.iterdir() if ".partial." in p.name]


def test_read_back_by_sdynpy(table, tmp_path):
    """SDynPy (a heavy install: Qt, VTK, PyVista; not in the test extra) reads the nodes
    (from UFF 2411), the trace lines and every shape with its frequency and damping."""
    sdpy = pytest.importorskip("sdynpy", reason="SDynPy is not installed (pip install sdynpy)")
    from sdynpy.fileio import sdynpy_uff

    s = shape_set(table)
    write_uff(tmp_path / "shapes.uff", s)
    d = sdynpy_uff.readuff(str(tmp_path / "shapes.uff"))
    geo = sdpy.Geometry.from_uff(d)
    shapes = sdpy.ShapeArray.from_uff(d)
    assert geo.node.size == s.node.size and shapes.size == table.n_modes
    np.testing.assert_allclose(shapes.frequency, table.frequency_hz, rtol=1e-5)
    np.testing.assert_allclose(shapes.damping, table.damping_ratio, rtol=1e-4)
