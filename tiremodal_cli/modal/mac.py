"""Modal assurance criterion (Allemang & Brown 1982).

``MAC(a, b) = |aᴴ b|² / ((aᴴ a)(bᴴ b))``, for complex shapes; 1 for proportional shapes,
0 for orthogonal ones. Shapes are rows: ``(n_modes, n_dof)``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tiremodal_cli.errors import ParameterError

__all__ = ["mac", "mac_matrix", "subspace_mac", "analytic_bases", "model_bases", "shape_labels"]


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


def analytic_bases(point_angle, n_max: int) -> list[np.ndarray]:
    """The circumferential orders' shapes over the points, for :func:`subspace_mac`.

    Parameters
    ----------
    point_angle : (n_points,) array, rad
    n_max : int

    Returns
    -------
    list of n_max + 1 arrays: (1, n_points) for n = 0 (ones), (2, n_points) for n ≥ 1
    (cos nθ, sin nθ)
    """
    th = np.asarray(point_angle, dtype=float)
    return [np.ones((1, th.size))] + [np.vstack([np.cos(n * th), np.sin(n * th)]) for n in range(1, n_max + 1)]


def model_bases(modes, t, f_max: float, observe: Callable) -> tuple[list[str], list[np.ndarray]]:
    """Residue shapes of a model's modes as the test sees them: sensor × point.

    Members of one (n, branch) (cos and sin) form one subspace, for :func:`subspace_mac`.

    Parameters
    ----------
    modes : the model's modes (``tiremodal_cli.tyre.model.solve_modes``): ``freq_hz``,
        ``n``, ``branch``, ``dofs``, ``shapes``
    t : ModalTable        the test: its channels' locations and angles, its points' angles
    f_max : float, Hz     the modes up to this frequency
    observe : callable(dofs, location, angle_rad) → (n_dofs,) row
        how a sensor at a location and angle sees the model's dofs
        (``tiremodal_cli.tyre.model.observation``; passed in, as the modal stage does not
        import the tyre model, a later stage)

    Returns
    -------
    labels : list of str ; bases : list of (k, n_channels · n_points) arrays
    """
    groups = {}
    for r in np.flatnonzero(modes.freq_hz <= f_max):
        key = (int(modes.n[r]), modes.branch[r])
        rows = []
        for loc, ang in zip(t.channel_location, t.channel_angle):
            c_out = observe(modes.dofs, loc, ang) @ modes.shapes[r] if loc in ("tread", "sidewall", "rim") else 0.0
            c_in = np.array([observe(modes.dofs, "tread", a) @ modes.shapes[r] for a in t.point_angle])
            rows.append(c_out * c_in)
        groups.setdefault(key, []).append((modes.freq_hz[r], np.concatenate(rows)))
    labels, bases = [], []
    for (n, b), members in sorted(groups.items(), key=lambda kv: kv[1][0][0]):
        vecs = [v for _, v in members if np.linalg.norm(v) > 0]
        if vecs:
            labels.append(f"model {members[0][0]:.1f} Hz n={n} {b}")
            bases.append(np.array(vecs))
    return labels, bases


def shape_labels(t) -> list[str]:
    """One label per mode of a ModalTable: its frequency, and n and branch when classified."""
    return [f"{f:.1f} Hz" + (f" n={n} {b}" if n >= 0 else "") for f, n, b in zip(t.frequency_hz, t.n, t.branch)]
