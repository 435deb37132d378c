"""The Cramér–Rao bound of ``benchmarks/crlb.py`` checked against what it bounds: the
scatter of a least-squares fit of one mode over seeded noise draws (an efficient estimator
at high SNR reaches the bound), and that sharing the residues across the points (one
order per mode) can only add information."""

import importlib.util
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

_spec = importlib.util.spec_from_file_location("crlb", Path(__file__).parents[1] / "benchmarks" / "crlb.py")
crlb = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(crlb)

F0, Z0 = 100.0, 0.02  # Hz, damping ratio
FREQ = np.arange(96.0, 104.01, 0.5)  # ± 2 half-power half-widths at 0.5 Hz
W = 2 * np.pi * FREQ


def _model_fit(y, s):
    """(f, ζ) of the least-squares fit of one pole with a free residue and constant per
    FRF to y (M, L): the linear parameters by projection, (f, ζ) by scipy."""
    def resid(p):
        lam = crlb.pole(p[0], p[1])[0]
        G = np.concatenate([crlb.pole_basis(W, np.atleast_1d(lam)), np.ones((len(W), 1)),
                            1j * np.ones((len(W), 1))], axis=1)
        out = []
        for m in range(len(y)):
            Gr = crlb._real(G, s[m])
            yr = crlb._real(y[m][:, None], s[m])[:, 0]
            out.append(yr - Gr @ np.linalg.lstsq(Gr, yr, rcond=None)[0])
        return np.concatenate(out)
    return least_squares(resid, x0=[F0, Z0], x_scale=[0.1, 0.001]).x


def test_bound_matches_the_scatter_of_a_least_squares_fit():
    rng = np.random.default_rng(55)
    A = np.array([1.0, 0.6 - 0.3j, -0.4, 0.2j]) * 1e3  # residues of four FRFs
    lam = crlb.pole(F0, Z0)[0]
    clean = np.stack([crlb.pole_basis(W, np.atleast_1d(lam)) @ np.array([a.real, a.imag]) for a in A]) + 0.3
    s = np.full(clean.shape, 0.02 * np.max(np.abs(clean)))  # peak / noise 50 on the best FRF
    F = crlb.fisher_unstructured(W, np.array([F0]), np.array([Z0]), A[:, None], s)
    sigma = crlb.bound(F, np.array([1.0, 0.0]))  # σ of ln f
    noise = (rng.standard_normal((200,) + clean.shape) + 1j * rng.standard_normal((200,) + clean.shape)) * s / np.sqrt(2)
    f_hat = np.array([_model_fit(clean + n, s)[0] for n in noise])
    scatter = np.std(f_hat / F0 - 1, ddof=1)
    assert 1e-5 < sigma < 1e-2  # a bound in the regime where the fit is linear
    print(f"scatter {scatter:.3e}, bound {sigma:.3e}, ratio {scatter / sigma:.3f}")
    assert abs(scatter / sigma - 1) < 0.2
    assert abs(np.mean(f_hat) / F0 - 1) < 3 * sigma / np.sqrt(200) + 0.2 * sigma  # unbiased


def test_one_order_per_mode_adds_information():
    """Two close modes of orders 2 and 3 on 12 points: the structured bound (residues
    u cos nθ + v sin nθ) is at most the unstructured one (every residue free)."""
    rng = np.random.default_rng(7)
    theta = 2 * np.pi * np.arange(12) / 12
    f, z = np.array([100.0, 100.8]), np.array([Z0, Z0])
    shapes = np.stack([np.cos(2 * theta + 0.3), np.cos(3 * theta - 0.5)], axis=-1) * (1 + 0.2 * rng.random(2))
    A = 1e3 * np.array([1.0, 0.5 - 0.2j])[:, None, None] * shapes[None]  # (2 channels, 12 points, 2 modes)
    s = np.full((2, 12, len(W)), 1.0)
    Fu = crlb.fisher_unstructured(W, f, z, A.reshape(24, 2), s.reshape(24, -1))
    Fs = crlb.fisher_structured(W, f, z, [{2}, {3}], theta, A, s)
    g = np.array([1.0, 0, 0, 0])
    assert crlb.bound(Fs, g) <= crlb.bound(Fu, g) * (1 + 1e-9)
    assert crlb._purity(A[:, :, 0], theta, {2}) > 0.999
