"""MAC: its algebra, and the mac command's AutoMAC, cross, analytic and model comparisons."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from tiremodal_cli.frf.estimate import compute_frf
from tiremodal_cli.io.frffile import write_frf
from tiremodal_cli.modal.mac import mac, mac_matrix, subspace_mac
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.simulate import SimulationConfig, simulate

from conftest import run_cli


def test_mac_algebra(rng):
    a = rng.standard_normal(10) + 1j * rng.standard_normal(10)
    assert mac(a, (2 - 3j) * a) == pytest.approx(1.0)
    b = rng.standard_normal(10)
    b -= (b @ a.real) / (a.real @ a.real) * a.real
    assert mac(a.real, b) == pytest.approx(0.0, abs=1e-12)
    A = rng.standard_normal((4, 10))
    M = mac_matrix(A)
    assert_allclose(np.diag(M), 1.0)
    assert_allclose(M, M.T)
    th = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    S = subspace_mac(np.cos(3 * (th - 0.4))[None], [np.vstack([np.cos(3 * th), np.sin(3 * th)]),
                                                    np.vstack([np.cos(2 * th), np.sin(2 * th)])])
    assert_allclose(S, [[1.0, 0.0]], atol=1e-12)


@pytest.fixture(scope="module")
def modal(tmp_path_factory):
    d = tmp_path_factory.mktemp("mac")
    s = simulate(SimulationConfig(n_points=16, n_hits=2, sample_rate=1024.0, n_samples=2048, noise=0.005, seed=6,
                                  params=TyreParameters(m_w=1000.0)))
    write_frf(d / "f.h5", compute_frf(s.measurement))
    assert run_cli(["lsce", d / "f.h5", "-o", d / "m.h5", "--band", 45, 150]).exit_code == 0
    (d / "p.toml").write_text("[params]\nm_w = 1000.0\n")
    return d


def test_automac_is_diagonal(modal):
    """Different n are orthogonal on the ring, except orders the 16-point grid aliases
    onto each other (n and 16 − n look the same)."""
    from tiremodal_cli.io.modalfile import read_modal

    d = json.loads(run_cli(["mac", modal / "m.h5", "--json"]).stdout)
    M = np.array(d["mac"])
    assert_allclose(np.diag(M), 1.0, atol=1e-9)
    t = read_modal(modal / "m.h5")
    alias = t.n_spatial[:, None] == t.n_spatial[None, :]
    assert M[~alias].max() < 0.2
    # the text names each mode's closest other mode (not itself) and the largest pair
    text = run_cli(["mac", modal / "m.h5"]).stdout.splitlines()
    off = np.where(np.eye(len(M), dtype=bool), -1, M)
    assert f"largest off-diagonal {off.max():.3f} (" in text[0]
    assert all("closest other" in ln for ln in text[1:]) and len(text) == len(M) + 1


def test_analytic_and_model_mac(modal, tmp_path):
    d = json.loads(run_cli(["mac", modal / "m.h5", "--analytic", 8, "--json"]).stdout)
    M = np.array(d["mac"])
    best = M.argmax(axis=1)
    from tiremodal_cli.io.modalfile import read_modal

    t = read_modal(modal / "m.h5")
    assert np.all(best == t.n_spatial) and np.all(M.max(axis=1) > 0.95)
    res = run_cli(["mac", modal / "m.h5", "--model", modal / "p.toml", "--json", "--plot", tmp_path / "m.png",
                   "--csv", tmp_path / "m.csv"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    M = np.array(d["mac"])
    for i in range(len(M)):
        col = d["columns"][int(M[i].argmax())]
        if t.n[i] == t.n_spatial[i]:  # aliased orders match their alias equally well
            assert f"n={t.n[i]} {t.branch[i]}" in col and M[i].max() > 0.95
    assert (tmp_path / "m.png").stat().st_size > 1000 and (tmp_path / "m.csv").read_text().startswith("mode,")


def test_cross_mac_needs_same_geometry(modal, tmp_path):
    d = json.loads(run_cli(["mac", modal / "m.h5", modal / "m.h5", "--json"]).stdout)
    assert_allclose(np.diag(np.array(d["mac"])), 1.0, atol=1e-9)
    s = simulate(SimulationConfig(n_points=12, n_hits=1, sample_rate=1024.0, n_samples=2048, seed=6,
                                  params=TyreParameters(m_w=1000.0)))
    write_frf(tmp_path / "f.h5", compute_frf(s.measurement))
    run_cli(["lsce", tmp_path / "f.h5", "-o", tmp_path / "m.h5", "--band", 45, 150])
    res = run_cli(["mac", modal / "m.h5", tmp_path / "m.h5"])
    assert res.exit_code == 2 and "geometry differs" in res.stderr
