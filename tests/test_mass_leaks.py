"""``benchmarks/mass_leaks.py`` against the exact coupled solution of the paper's model.

The point mass in modal coordinates of the uncoupled model (unit modal masses) is the
generalised eigenproblem ``diag(ω²) q = ω'² (I + m_a p pᵀ) q`` with p the modes' tread
displacement at θ_a; its eigenvectors are the exact mixing of the orders. The script's
first-order coefficients must agree with it where they are small (the same-direction
crowd) and the doc's claim that they fail for the opposite n = 0…2 (coefficients ≳ 0.25,
the orders closer than the mass's coupling) must hold on the generator's own model."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import eigh

from tiremodal_cli.tyre.solve import observation, solve_modes
from tiremodal_cli.workflow.validation import Case, config_for

_spec = importlib.util.spec_from_file_location("mass_leaks", Path(__file__).parents[1] / "benchmarks" / "mass_leaks.py")
ml = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ml)

CASE = Case(generator="paper", physics="added_mass", label="physics=added_mass")


@pytest.fixture(scope="module")
def exact():
    """Uncoupled modes, their tread displacement at the mass and the exact coupled eigenvectors."""
    cfg = config_for(CASE)
    v = ml.EFFECT.resolve(cfg.effects["added_mass"])
    m0 = solve_modes(cfg.params, n_max=cfg.n_max, effects={})
    p = observation(m0.dofs, "tread", v["theta_a"]) @ m0.shapes.T
    w2 = (2 * np.pi * m0.freq_hz) ** 2
    lam, Q = eigh(np.diag(w2), np.eye(len(w2)) + v["m_a"] * np.outer(p, p))
    return m0, Q, np.sqrt(lam) / (2 * np.pi)


def _exact_coeff(m0, Q, r, s):
    """Component of uncoupled mode s in the coupled mode that is mostly mode r, relative to r's."""
    k = int(np.argmax(np.abs(Q[r])))  # the coupled mode with the largest share of mode r
    return Q[s, k] / Q[r, k]


def _index(m0, f_hz):
    return int(np.argmin(np.abs(m0.freq_hz - f_hz) + 1e3 * (np.asarray(m0.harmonic) != "cos")))


def test_first_order_matches_exact_where_small(exact):
    m0, Q, _ = exact
    rows = [r for r in ml.first_order(CASE, (150.0, 166.0)) if r["branch"] == "same"]
    assert len(rows) >= 10
    for row in rows:
        r = _index(m0, row["frequency_hz"])
        for n, branch, f_s, c in row["coupled"][:1]:
            assert abs(c) < 0.05
            assert _exact_coeff(m0, Q, r, _index(m0, f_s)) == pytest.approx(c, rel=0.15)


def test_first_order_fails_for_the_opposite_cluster(exact):
    m0, Q, _ = exact
    rows = {r["n"]: r for r in ml.first_order(CASE, (180.0, 200.0)) if r["branch"] == "opposite"}
    r0, (n1, _, f1, c01) = _index(m0, rows[0]["frequency_hz"]), rows[0]["coupled"][0]
    assert n1 == 1 and abs(c01) > 0.25
    # the exact mixing is no longer c: the near-degenerate n = 0 and 1 mix beyond first order
    exact01 = _exact_coeff(m0, Q, r0, _index(m0, f1))
    assert abs(exact01 - c01) > 0.2 * abs(c01)


def test_leak_free_keeps_only_the_dominant_order():
    cfg = config_for(CASE)
    m = solve_modes(cfg.params, n_max=cfg.n_max, effects=cfg.effects)
    dof_n = np.array([d[1] for d in m.dofs])
    free = ml.leak_free(m, 0.0)
    outside = dof_n[None, :] != m.n[:, None]
    assert np.all(free.shapes[outside] == 0)
    assert np.array_equal(free.shapes[~outside], m.shapes[~outside])
    # the generator's mass really mixes the orders: some modes carry ≥ 10 % outside their order
    share = (m.shapes ** 2 * outside).sum(1) / (m.shapes ** 2).sum(1)
    assert share.max() > 0.1
    assert np.array_equal(ml.leak_free(m, 1.0).shapes, m.shapes)
