"""Stabilization diagram and automatic selection of the physical poles.

Each order's in-band poles with positive damping below ``zeta_max`` are compared with the
previous order's: a pole is *stable* when some pole there lies within ``tol_freq``
(relative frequency), ``tol_damping`` (relative damping) and ``tol_mac`` (MAC of the
shapes). Stable poles are then clustered across orders: a pole joins the cluster whose
mean shape it matches best (MAC ≥ ``cluster_mac``) within ``cluster_freq`` of the
cluster's median frequency, at most one pole per order; clusters seen at fewer than
``min_count`` orders, with implausible damping, or with inconsistent shapes (mean MAC
to the cluster's shape below ``cluster_mac``) are rejected as computational. One
representative per cluster: the member closest to the cluster's median frequency and
damping. Every decision is kept (``Cluster.reason``) so the choice can be explained.

**An order group of one reference** (a grid's orders 0 and N/2, whose sine column vanishes;
session 52) is swept without the shape test (``StabilizationOptions.shapes`` off). There a
pole's shape is its residues in the group's two or three principal responses, fitted at each
order beside that order's other poles over the whole band; a weak mode's (5–10 × the noise)
changes from order to order with the poles the sweep spends on the noise beside it, not with
the mode: the 34-point paper membrane's in-phase n = 51 at 325.7 Hz (group 17) stood within
0.3 % in frequency and 5 % in damping at 33 of the 39 orders, with MACs of 0.05–0.99 between
consecutive orders — 6 "stable" poles whose mean MAC to their mean shape was 0.76, rejected as
inconsistent. Without the shapes, the damping ratio tells two poles of one frequency apart in
the clustering (a noise pole's damping drifts over the orders: the car ring's 704.7 Hz in its
group 0, ζ 1.8 → 0.7 % over orders 30–40, six "stable" poles at six scattered orders, pooled
by frequency alone and adopted — a spurious row). Measured on the matrices: docs/lsce.md,
"Session 52".
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.special

from tiremodal_cli.modal.lsce import Band, OrderPoles
from tiremodal_cli.modal.mac import mac

__all__ = ["StabilizationOptions", "StablePole", "Cluster", "Diagram", "stabilize"]


@dataclass(frozen=True)
class StabilizationOptions:
    """Tolerances (fractions) of the stability test and the clustering."""

    tol_freq: float = 0.01
    tol_damping: float = 0.05
    tol_mac: float = 0.98
    zeta_max: float = 0.2
    cluster_freq: float = 0.01
    cluster_mac: float = 0.9
    min_count: int | None = None  # default: 15 % of the orders swept, at least 3
    #: False: no shape test — the poles alone decide (as with one-component shapes), and a
    #: pole joins a cluster only where its damping ratio agrees with the cluster's mean within
    #: ``tol_damping`` (what the stability test asks of two orders). For an order group of one
    #: reference (:func:`~tiremodal_cli.modal.guard.guarded_diagram`): module doc.
    shapes: bool = True


@dataclass
class StablePole:
    order: int
    s: complex
    freq_hz: float
    damping_ratio: float
    shape: np.ndarray  # reduced (principal-space) amplitudes
    status: str  # "stable", "f", "fd", "fv", "new"
    participation: np.ndarray | None = None  # poly-reference participation factors


@dataclass
class Cluster:
    """Stable poles across orders that are one mode (or a computational artefact)."""

    members: list = field(default_factory=list)
    orders: set = field(default_factory=set)
    adopted: bool = False
    reason: str = ""
    representative: StablePole | None = None
    std_hz: float | None = None  # a pole fitted, not swept (modal.beside): its standard error

    @property
    def freq_hz(self) -> float:
        return float(np.median([m.freq_hz for m in self.members]))

    @property
    def damping_ratio(self) -> float:
        return float(np.median([m.damping_ratio for m in self.members]))

    @property
    def frequency_std_hz(self) -> float:
        """The scatter of its poles' frequencies over the model orders (Hz; sample standard
        deviation, 0 for a single pole): the frequency's uncertainty as the sweep sees it."""
        if self.std_hz is not None:
            return self.std_hz
        f = np.array([m.freq_hz for m in self.members])
        return float(np.std(f, ddof=1)) if f.size > 1 else 0.0

    def mean_shape(self):
        ref = self.members[0].shape
        acc = np.zeros_like(ref)
        for m in self.members:
            ph = np.vdot(m.shape, ref)  # align phases before adding
            acc = acc + m.shape * (np.conj(ph) / abs(ph) if abs(ph) > 0 else 1)
        return acc

    def to_dict(self) -> dict:
        f = np.array([m.freq_hz for m in self.members])
        z = np.array([m.damping_ratio for m in self.members])
        return {"frequency_hz": self.freq_hz, "damping_ratio": self.damping_ratio,
                "n_poles": len(self.members), "orders": [m.order for m in self.members],
                "frequency_spread_pct": float(100 * (f.max() - f.min()) / np.median(f)),
                "frequency_std_hz": self.frequency_std_hz,
                "damping_spread_pct": float(100 * (z.max() - z.min()) / max(np.median(z), 1e-12)),
                "adopted": self.adopted, "reason": self.reason,
                "representative_order": None if self.representative is None else self.representative.order}


@dataclass(frozen=True)
class Diagram:
    """All candidate poles per order with their stability status, and the clusters."""

    poles: list  # list of StablePole (every in-band candidate of every order)
    clusters: list  # list of Cluster
    orders: list

    def selected(self) -> list:
        return sorted((c for c in self.clusters if c.adopted), key=lambda c: c.representative.freq_hz)


def _shapes(band: Band, s, max_lines: int = 128):
    """Residues of the candidate poles in the principal responses, for the MAC test.

    A complex least-squares fit on ≤ 128 lines of the band with the basis 1/(iω − s_r) of
    the candidates and a constant (the rest), solved through its normal equations: cheap,
    and a fit in frequency keeps close poles apart better than the impulse responses'
    Vandermonde system. (The final shapes come from the full LSFD, :mod:`.lsfd`.)
    """
    if len(s) == 0:
        return np.zeros((0, band.prf.shape[0]), dtype=complex)
    k = max(1, band.freq_hz.size // max_lines)
    jw = 2j * np.pi * band.freq_hz[::k, None]
    A = np.concatenate([1.0 / (jw - np.asarray(s)[None, :]), np.ones_like(jw)], axis=1)
    A /= np.linalg.norm(A, axis=0)
    G = A.conj().T @ A
    G[np.diag_indices_from(G)] += 1e-12 * np.trace(G).real / G.shape[0]  # keep it positive definite
    rhs = A.conj().T @ band.prf[:, ::k].T
    try:
        x = scipy.linalg.cho_solve(scipy.linalg.cho_factor(G, check_finite=False), rhs, check_finite=False)
    except (scipy.linalg.LinAlgError, ValueError):
        x = scipy.linalg.lstsq(A, band.prf[:, ::k].T, lapack_driver="gelsy")[0]
    return x[:len(s)]


def _candidates(op: OrderPoles, band: Band, zeta_max: float):
    k = band.freq_hz.size  # the band's top: its K lines' span (width_hz also holds a guard's lines)
    f_hi = band.f_lo + k * ((band.freq_hz[-1] - band.freq_hz[0]) / max(k - 1, 1))
    keep = (op.freq_hz >= band.f_lo) & (op.freq_hz <= f_hi) & (op.damping_ratio > 0) & \
        (op.damping_ratio < zeta_max) & (np.abs(op.z) < 1)
    return np.flatnonzero(keep)


def _statuses(op: OrderPoles, idx, shapes, prev, opt) -> list[str]:
    """Each candidate pole's status against the previous order's nearest pole: "stable"
    (frequency, damping and shape within tolerance), "fd", "fv", "f", or "new" (its
    frequency moved, or the first order)."""
    if not prev or not len(idx):
        return ["new"] * len(idx)
    f, z = op.freq_hz[idx], op.damping_ratio[idx]
    pf = np.array([q.freq_hz for q in prev])
    pz = np.array([q.damping_ratio for q in prev])
    j = np.argmin(np.abs(pf[None, :] - f[:, None]), axis=1)
    ok_f = np.abs(pf[j] - f) <= opt.tol_freq * f
    ok_d = np.abs(pz[j] - z) <= opt.tol_damping * z
    ok_v = _row_mac(np.array([np.ravel(prev[i].shape) for i in j]).reshape(len(idx), -1),
                    np.reshape(shapes, (len(idx), -1))) >= opt.tol_mac
    return ["new" if not ok_f[k] else "stable" if ok_d[k] and ok_v[k] else "fd" if ok_d[k] else "fv" if ok_v[k]
            else "f" for k in range(len(idx))]


def _row_mac(A, B) -> np.ndarray:
    """:func:`mac` of each row of ``A`` with the same row of ``B`` ((k, d) each), in one
    array call (the status of every pole of an order; ~12,000 scalar calls on the sample)."""
    num = np.abs(np.einsum("ij,ij->i", A.conj(), B)) ** 2
    den = np.einsum("ij,ij->i", A.conj(), A).real * np.einsum("ij,ij->i", B.conj(), B).real
    return np.divide(num, den, out=np.zeros(len(num)), where=den > 0)


def stabilize(band: Band, sweep_result: list[OrderPoles], opt: StabilizationOptions = StabilizationOptions()) -> Diagram:
    """Stability status of every candidate pole, clustering and selection."""
    poles, prev = [], None
    for op in sweep_result:
        idx = _candidates(op, band, opt.zeta_max)
        # poly-reference poles carry participation vectors: those tell the members of a
        # split pair apart where a shape fitted per order would mix them
        shapes = (op.participation[idx] if op.participation is not None else _shapes(band, op.s[idx])
                  if opt.shapes else np.ones((len(idx), 1), dtype=complex))
        status = _statuses(op, idx, shapes, prev, opt)
        cur = [StablePole(op.order, complex(op.s[i]), float(op.freq_hz[i]), float(op.damping_ratio[i]),
                          shapes[k], status[k], None if op.participation is None else op.participation[i])
               for k, i in enumerate(idx)]
        poles.extend(cur)
        prev = cur
    orders = [op.order for op in sweep_result]
    min_count = opt.min_count if opt.min_count is not None else max(3, int(round(0.15 * len(orders))))
    line_hz = float(band.freq_hz[1] - band.freq_hz[0]) if band.freq_hz.size > 1 else np.inf
    clusters = _joined(_cluster([p for p in poles if p.status == "stable"], opt), opt, line_hz)
    for c in clusters:
        _judge(c, opt, min_count)
    _drop_duplicates(clusters, opt)
    return Diagram(poles=poles, clusters=clusters, orders=orders)


def _shape_informative(c) -> bool:
    """True when a cluster's shapes have more than one component: only then can a MAC tell
    two modes apart (with one reference and one response every MAC is 1)."""
    return np.size(c.members[0].shape) > 1


def _drop_duplicates(clusters, opt):
    """Of two adopted clusters that are one mode, keep the one stable at more orders.

    Where the shapes can differ (more than one component: several references, or
    participation vectors), two clusters within ``cluster_freq`` whose MAC is ≥
    ``cluster_mac`` are one mode. With one-component shapes every MAC is 1 and is no
    evidence: the poles decide, and two clusters are one mode only when the second lies
    in the first's half-power band (|Δf| ≤ ζ f of the more persistent one).
    """
    adopted = sorted((c for c in clusters if c.adopted), key=lambda c: -len(c.members))
    kept = []
    for c in adopted:
        twin = None
        for k in kept:
            if _shape_informative(k):
                if (abs(k.freq_hz - c.freq_hz) > opt.cluster_freq * c.freq_hz
                        or mac(k.mean_shape(), c.mean_shape()) < opt.cluster_mac):
                    continue
            elif abs(k.freq_hz - c.freq_hz) > k.damping_ratio * k.freq_hz:
                continue
            twin = k
            break
        if twin is None:
            kept.append(c)
        else:
            c.adopted = False
            c.reason = (f"duplicate of the mode at {twin.freq_hz:.3f} Hz: within its half-power band "
                        f"(stable at {len(twin.members)} orders against {len(c.members)})")


def _cluster(stable, opt):
    clusters: list[Cluster] = []
    means: list[np.ndarray] = []
    f_mean = []  # running mean frequency of each cluster (a cheap stand-in for the median)
    z_mean = []  # and damping ratio: with no shapes (``opt.shapes`` off) it is what tells poles apart
    for p in sorted(stable, key=lambda q: (q.freq_hz, q.order)):
        best, best_mac = None, opt.cluster_mac
        fm = np.asarray(f_mean)
        near = np.flatnonzero(np.abs(fm - p.freq_hz) <= opt.cluster_freq * p.freq_hz) if fm.size else []
        # the best-matching shape (MAC ≥ cluster_mac); among equal MACs — with one reference
        # every MAC is 1 — the nearest cluster in frequency
        best_key = (best_mac - 1e-9, -np.inf)
        for ci in near:
            c = clusters[ci]
            if p.order in c.orders or (not opt.shapes and abs(p.damping_ratio - z_mean[ci]) > opt.tol_damping * z_mean[ci]):
                continue
            key = (round(mac(means[ci], p.shape), 9), -abs(fm[ci] - p.freq_hz))
            if key > best_key:
                best, best_key = ci, key
        if best is None:
            clusters.append(Cluster(members=[p]))
            clusters[-1].orders = {p.order}
            means.append(p.shape.copy())
            f_mean.append(p.freq_hz)
            z_mean.append(p.damping_ratio)
        else:
            c = clusters[best]
            ph = np.vdot(p.shape, means[best])
            means[best] = means[best] + p.shape * (np.conj(ph) / abs(ph) if abs(ph) > 0 else 1)
            f_mean[best] += (p.freq_hz - f_mean[best]) / (len(c.members) + 1)
            z_mean[best] += (p.damping_ratio - z_mean[best]) / (len(c.members) + 1)
            c.members.append(p)
            c.orders.add(p.order)
    return clusters


#: probability that one pole's two clusters are kept apart by the test of their frequencies
#: (:func:`_joined`; as the merge's ``SAME_POLE_ALPHA``)
JOIN_ALPHA = 1e-3


def _joined(clusters: list, opt, line_hz: float = np.inf) -> list:
    """Clusters of a single-reference sweep that are one pole split by their shapes, joined.

    Two clusters are one pole when no model order holds both (two modes coexist at the
    orders that resolve them), each is pinned — its frequencies' scatter over the orders at
    most one line ``line_hz``, the own-peak rule's (c): a test of means is no evidence of
    one pole where the poles wander (a one-hit test's sloppy clusters, 2 + 2 poles at
    300.2 ± 1.8 and 300.1 ± 1.1 Hz, would pass it) — their member frequencies' ranges
    overlap and a Welch test of their mean frequencies does not tell them apart at
    :data:`JOIN_ALPHA` (a cluster of one pole: against the other's prediction interval),
    and their median damping ratios agree within ``tol_damping``. The clustering keeps them apart when the MAC of a member
    to the other's mean shape falls under ``cluster_mac``, which a participation vector
    with one component near its noise does as it drifts over the orders (session 36: a
    20-point ring's same-direction n = 40 at 468.93 Hz in its group 0, poles at
    468.82–468.98 Hz over nine orders, split 5 + 4 by MACs of 0.89 — each cluster under the
    count a stable mode needs). The test keeps a lumped mass's split pair apart: its
    members' clusters overlap in range where the weaker scatters, 481.11 ± 0.33 Hz over
    7 orders against 483.73 ± 0.18 Hz over 4, but are 17 standard errors apart. Clusters of
    a poly-reference sweep (participation vectors over the cos and sin references) are left
    apart: there a participation that differs is the orientation of the other member of a
    degenerate pair at the same frequency (an added mass's unsplit pairs: clusters 0.001 Hz
    apart at disjoint orders, MAC 0.3–0.97 — joined, the pair's fit lost a member and the
    ring's added mass went undiagnosed).
    """
    if any(c.members[0].participation is not None for c in clusters):
        return clusters  # participation vectors: two orientations of one pair at one frequency
    out = sorted(clusters, key=lambda c: min(m.freq_hz for m in c.members))
    i = 0
    while i < len(out):
        a, j = out[i], i + 1
        a_hi = max(m.freq_hz for m in a.members)
        while j < len(out) and min(m.freq_hz for m in out[j].members) <= a_hi:
            b = out[j]
            za, zb = a.damping_ratio, b.damping_ratio
            if (a.orders & b.orders or abs(za - zb) > opt.tol_damping * max(za, zb)
                    or not _one_frequency(a, b, line_hz)):
                j += 1
                continue
            a.members += b.members
            a.orders |= b.orders
            a_hi = max(a_hi, max(m.freq_hz for m in b.members))
            del out[j]
        i += 1
    return out


def _one_frequency(a: Cluster, b: Cluster, line_hz: float = np.inf) -> bool:
    """Whether two clusters' pole frequencies can be one pole's (:func:`_joined`)."""
    fa, fb = (np.array([m.freq_hz for m in c.members]) for c in (a, b))
    if fa.size < fb.size:
        fa, fb = fb, fa
    if fa.size < 2:
        return False  # two single poles: nothing to judge a scatter by
    sa = np.std(fa, ddof=1)
    if sa == 0 or sa > line_hz or (fb.size > 1 and np.std(fb, ddof=1) > line_hz):
        return False  # no scatter to judge by, or a pole the data do not pin
    # Welch's test by hand with scipy.special's Student t: scipy.stats costs the pipeline's
    # start 0.4 s (issue 19) for this one p-value
    if fb.size == 1:  # one pole against the other cluster's prediction interval
        t, dof = abs(fb[0] - fa.mean()) / (sa * np.sqrt(1 + 1 / fa.size)), fa.size - 1.0
    else:
        va, vb = sa**2 / fa.size, np.var(fb, ddof=1) / fb.size
        t = abs(fa.mean() - fb.mean()) / np.sqrt(va + vb)
        dof = (va + vb) ** 2 / (va**2 / (fa.size - 1) + vb**2 / (fb.size - 1))
    return bool(2 * scipy.special.stdtr(dof, -t) >= JOIN_ALPHA)


def _judge(c: Cluster, opt, min_count):
    f = np.array([m.freq_hz for m in c.members])
    z = np.array([m.damping_ratio for m in c.members])
    fm, zm = np.median(f), np.median(z)
    score = np.abs(f - fm) / fm + np.abs(z - zm) / max(zm, 1e-12)
    c.representative = c.members[int(np.argmin(score))]
    shape = c.mean_shape()
    consistency = float(np.mean([mac(shape, m.shape) for m in c.members]))
    if len(c.members) < min_count:
        c.reason = f"computational: stable at {len(c.members)} orders (< {min_count})"
    elif not 0 < zm < opt.zeta_max:
        c.reason = f"implausible damping ratio {zm:.4f}"
    elif consistency < opt.cluster_mac:
        c.reason = f"inconsistent shapes across orders (mean MAC {consistency:.3f} < {opt.cluster_mac})"
    else:
        c.adopted = True
        c.reason = f"stable at {len(c.members)} orders, shape consistency {consistency:.3f}"
