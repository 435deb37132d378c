"""Modal assurance criterion (Allemang & Brown 1982).

``MAC(a, b) = |aᴴ b|² / ((aᴴ a)(bᴴ b))``, for complex shapes; 1 for proportional shapes,
0 for orthogonal ones. Shapes are rows: ``(n_modes, n_dof)``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mac", "mac_matrix", "subspace_mac"]


def mac(a, b) -> float:
    """MAC of two shape vectors (any shape; flattened)."""
    a = np.ravel(a)
    b = np.ravel(b)
    den = np.vdot(a, a).real * np.vdot(b, b).real
    return float(abs(np.vdot(a, b)) ** 2 / den) if den > 0 else 0.0


def mac_matrix(A, B=None) -> np.ndarray:
    """MAC between every row of A and every row of B (AutoMAC when B is None).

    Parameters
    ----------
    A : (n_a, n_dof) array ; B : (n_b, n_dof) array, optional

    Returns
    -------
    (n_a, n_b) ndarray in [0, 1]
    """
    A = np.atleast_2d(np.asarray(A))
    B = A if B is None else np.atleast_2d(np.asarray(B))
    if A.shape[1] != B.shape[1]:
        from tiremodal_cli.errors import ParameterError

        raise ParameterError(f"shapes have {A.shape[1]} and {B.shape[1]} degrees of freedom; "
                             "MAC needs the same")
    num = np.abs(A.conj() @ B.T) ** 2
    den = np.outer(np.sum(np.abs(A) ** 2, axis=1), np.sum(np.abs(B) ** 2, axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1), 0.0)


def subspace_mac(A, bases) -> np.ndarray:
    """MAC of each row of A with a subspace (the largest MAC with any vector in it).

    ``bases`` is a list of (k_j, n_dof) arrays; returns (n_a, len(bases)). For the span of
    cos nθ and sin nθ this is the share of a shape in order n at its best orientation.
    """
    A = np.atleast_2d(np.asarray(A))
    out = np.zeros((A.shape[0], len(bases)))
    for j, B in enumerate(bases):
        Q, _ = np.linalg.qr(np.atleast_2d(B).T.astype(complex))
        proj = A.conj() @ Q
        out[:, j] = np.sum(np.abs(proj) ** 2, axis=1) / np.maximum(np.sum(np.abs(A) ** 2, axis=1), np.finfo(float).tiny)
    return out
