"""The power and the bias of a rank-one (poly-reference) window test for the unfound orders of
a test whose circumferential orders mix: a measurement for the estimator that issue #14's mass
class needs, not a pass of the tool (docs/lsce.md, "Session 47").

    python benchmarks/validation.py --only 'ring:physics=sidewall_coupling+mass' --keep /tmp/k --no-docs --out /tmp/k.jsonl
    python benchmarks/rank_one_windows.py /tmp/k 'ring:physics=sidewall_coupling+mass' [--start truth:0.002]
        [--nulls 3] [--oracle-pairs] [--free-half-widths 0.3] [--lo HZ --hi HZ]

(``RANK_ONE_MAX_NFEV`` sets the solver's evaluations per fit, 50 by default. Run one process
per core with ``OMP_NUM_THREADS=1``: two processes with default BLAS threads on two cores ran
10–20 × slower.)

*The model.* In the points' circumferential harmonics (the complete grid's cos kθ, sin kθ,
normalised: an orthonormal transform, so white noise stays white), every FRF row (channel c,
harmonic column k) of a window of lines is

    H_ck(ω) = (iω)^q Σ_r [ l_rc ψ_rk / (iω − λ_r) + conj(l_rc ψ_rk) / (iω − conj λ_r) ]
              + a_ck (iω)^(q−2) + b_ck (iω)^q,

each mode's residues rank one (participation l_r over the channels, shape ψ_r over the
harmonics: the model of ``crlb_polyref.py``), with ψ_r free on every harmonic for the
table's modes (a mass makes each mode show on every order: its copies) and on its own
order's columns for a proposal. ψ and the residual terms a, b (complex) are linear and are
eliminated by least squares; the poles near the proposal and every l are moved by
``scipy.optimize.least_squares`` (trf) with Kaufman's variable-projection Jacobian
(scipy has no variable-projection solver with a bilinear inner problem; written here).

*The test.* For an order the table does not hold, at its branch's dispersion (or at the
truth × (1 + offset) with ``--start truth:OFFSET``, to separate the test from the proposal):
the window's lines within 4 half-power half-widths, fitted without the proposal (H0, the
table's modes within 0.3 half-widths free) and with it (H1, its pole free within half a
half-width). Each channel is weighted by H0's residual power; the gain is
ΔE / σ̂² over the 1 − α/K quantile of χ²(2 (columns + channels − 1) + 2) (α = 10⁻³, K the
window's lines), σ̂² H1's residual variance per real degree of freedom. *Nulls*: the same
proposal in order groups where the truth has no order within 3 half-widths (what the test
gains where there is nothing of that order). *Round 2*: every proposal that passed
(gain > 1, not on its box's edge) is fitted again with all the others in the model.
``--oracle-pairs`` adds to the table the truth's strong modes (tread amplitude > 0.05) that
no table row lies within a line of — the split-pair members the table reports as one row.
"""

from __future__ import annotations

import argparse
import csv
import os
import sys
from pathlib import Path

import numpy as np
import scipy.optimize
import scipy.special

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from tiremodal_cli.io.frffile import read_frf  # noqa: E402
from tiremodal_cli.modal.spatial import grid_design  # noqa: E402
from tiremodal_cli.tyre.simulate import simulate  # noqa: E402
from tiremodal_cli.workflow.validation import config_for  # noqa: E402

TAU = 2 * np.pi
ALPHA = 1e-3
WINDOW_HALF_WIDTHS = 4.0
#: the table's poles moved with the proposal: those within this many half-widths of it (0: every
#: pole inside the window's lines; measured worse: the fit stops in local minima, gains < 0)
FREE_HALF_WIDTHS = 0.3
#: the solver's function evaluations per fit (each evaluation one linear solve per harmonic pattern)
MAX_NFEV = int(os.environ.get("RANK_ONE_MAX_NFEV", 50))
BOX_HALF_WIDTHS = 0.5
#: with ``RANK_ONE_SHOWN`` > 0, each table mode's shape is free only on the harmonics where its
#: peak reaches that many times the window's residual level (the poly-reference bound's model
#: uses the noise's: ``crlb_polyref.py``); 0, on every harmonic
SHOWN_LEVEL = float(os.environ.get("RANK_ONE_SHOWN", 0))
#: a round-2 row closer than this share of its half-width to a table row is that row's duplicate
#: (the summary's count; chosen, not derived: 2.5 lines at ζ = 2 % and 500 Hz)
GUARD_HALF_WIDTHS = 0.25
#: with every pole of the window free (``--free-half-widths 0``), the table's poles' box
TABLE_BOX_HALF_WIDTHS = float(os.environ.get("RANK_ONE_TABLE_BOX", 0.5))
FORM_Q = {"receptance": 0, "mobility": 1, "accelerance": 2}


class RankOne:
    """The window's model (module doc) for poles ``s0`` (m,), rad/s, with ``allowed`` (m, n_k)
    harmonic columns per mode; ``free_pole`` moves in a box of ``box`` half-widths about s0."""

    def __init__(self, freq, Y, s0, allowed, q, L0, free_pole, box=BOX_HALF_WIDTHS):
        self.freq, self.Y, self.s0, self.q = freq, Y, np.asarray(s0, dtype=complex), q
        self.n_c, self.n_k, self.K = Y.shape
        self.m = self.s0.size
        self.L0 = np.array(L0, dtype=complex)
        self.ref = np.argmax(np.abs(self.L0), axis=1)  # the channel whose l is held (the scale)
        self.others = [[c for c in range(self.n_c) if c != self.ref[r]] for r in range(self.m)]
        self.fp = np.asarray(free_pole, dtype=int)
        self.box = box
        self.jw = 1j * TAU * np.asarray(freq, dtype=float)
        g1, g2 = self.jw ** (q - 2), self.jw**q
        self.res_cols = np.stack([g1, 1j * g1, g2, 1j * g2], axis=1)
        self.patterns = {}
        for k in range(self.n_k):
            self.patterns.setdefault(tuple(allowed[:, k]), []).append(k)
        self._cache = None

    def x0(self):
        return np.concatenate([np.zeros(2 * self.fp.size)] + [
            np.concatenate([self.L0[r, self.others[r]].real, self.L0[r, self.others[r]].imag]) for r in range(self.m)])

    def unpack(self, th):
        npf = self.fp.size
        s = self.s0.copy()
        hw = -self.s0.real[self.fp]
        s[self.fp] = self.s0.real[self.fp] * np.exp(th[npf:2 * npf]) + 1j * (self.s0.imag[self.fp] + th[:npf] * hw)
        L = self.L0.copy()
        rest = th[2 * npf:].reshape(self.m, 2, self.n_c - 1)
        for r in range(self.m):
            L[r, self.others[r]] = rest[r, 0] + 1j * rest[r, 1]
        return s, L

    def _inner(self, s, L):
        jw, q, n_c, K = self.jw[:, None], self.q, self.n_c, self.K
        a, b = jw**q / (jw - s[None, :]), jw**q / (jw - np.conj(s)[None, :])
        A_re = (L.T[:, None, :] * a[None] + np.conj(L).T[:, None, :] * b[None]).reshape(n_c * K, self.m)
        A_im = (1j * L.T[:, None, :] * a[None] - 1j * np.conj(L).T[:, None, :] * b[None]).reshape(n_c * K, self.m)
        R = np.zeros((n_c * K, 4 * n_c), dtype=complex)
        for c in range(n_c):
            R[c * K:(c + 1) * K, 4 * c:4 * c + 4] = self.res_cols
        psi = np.zeros((self.m, self.n_k), dtype=complex)
        resid = np.zeros((n_c, self.n_k, K), dtype=complex)
        blocks = []
        for pat, ks in self.patterns.items():
            use = np.flatnonzero(pat)
            G = np.concatenate([A_re[:, use], A_im[:, use], R], axis=1)
            Gr = np.concatenate([G.real, G.imag], axis=0)
            Q, _ = np.linalg.qr(Gr)
            Yk = self.Y[:, ks, :].transpose(0, 2, 1).reshape(n_c * K, len(ks))
            Yr = np.concatenate([Yk.real, Yk.imag], axis=0)
            x = np.linalg.lstsq(Gr, Yr, rcond=None)[0]
            rr = Yr - Gr @ x
            psi[np.ix_(use, ks)] = x[:use.size] + 1j * x[use.size:2 * use.size]
            resid[:, ks, :] = (rr[:n_c * K] + 1j * rr[n_c * K:]).reshape(n_c, K, len(ks)).transpose(0, 2, 1)
            blocks.append((ks, Q))
        return a, b, psi, resid, blocks

    def residual(self, th):
        s, L = self.unpack(th)
        self._cache = (th.copy(), s, L, self._inner(s, L))
        r = self._cache[3][3]
        return np.concatenate([r.real.ravel(), r.imag.ravel()])

    def _derivatives(self, s, L, a, b, psi):
        """(parameter index, the model's derivative (n_c, n_k, K)) with ψ held (Kaufman)."""
        jw, q, npf = self.jw[:, None], self.q, self.fp.size
        ap, bp = jw**q / (jw - s[None, :]) ** 2, jw**q / (jw - np.conj(s)[None, :]) ** 2
        out = []
        for i, r in enumerate(self.fp):
            Lp = L[r][:, None, None] * psi[r][None, :, None]
            hw, sig = -self.s0[r].real, -s[r].real
            out.append((i, 1j * hw * (Lp * ap[None, None, :, r] - np.conj(Lp) * bp[None, None, :, r])))
            out.append((npf + i, -sig * (Lp * ap[None, None, :, r] + np.conj(Lp) * bp[None, None, :, r])))
        col = 2 * npf
        for r in range(self.m):
            ps = psi[r][:, None]
            for part in (1, 1j):
                for c in self.others[r]:
                    d = np.zeros((self.n_c, self.n_k, self.K), dtype=complex)
                    d[c] = part * ps * a[None, :, r] + np.conj(part * ps) * b[None, :, r]
                    out.append((col, d))
                    col += 1
        return out

    def jac(self, th):
        if self._cache is None or not np.array_equal(self._cache[0], th):
            self.residual(th)
        _, s, L, (a, b, psi, _, blocks) = self._cache
        n_c, K = self.n_c, self.K
        J = np.zeros((2, n_c, self.n_k, K, th.size))
        for j, d in self._derivatives(s, L, a, b, psi):
            for ks, Q in blocks:
                V = d[:, ks, :].transpose(0, 2, 1).reshape(n_c * K, len(ks))
                Vr = np.concatenate([V.real, V.imag], axis=0)
                P = Q @ (Q.T @ Vr) - Vr
                J[0, :, ks, :, j] = P[:n_c * K].reshape(n_c, K, len(ks)).transpose(2, 0, 1)
                J[1, :, ks, :, j] = P[n_c * K:].reshape(n_c, K, len(ks)).transpose(2, 0, 1)
        return J.reshape(-1, th.size)

    def solve(self, max_nfev=None):
        max_nfev = max_nfev or MAX_NFEV
        npf = self.fp.size
        nL = self.x0().size - 2 * npf
        box = np.broadcast_to(np.asarray(self.box, dtype=float), (npf,))
        lb = np.concatenate([-box, np.full(npf, -np.log(3)), np.full(nL, -np.inf)])
        sol = scipy.optimize.least_squares(self.residual, self.x0(), jac=self.jac, bounds=(lb, -lb),
                                           x_scale="jac", max_nfev=max_nfev, method="trf")
        s, L = self.unpack(sol.x)
        r = self.residual(sol.x)
        edge = float(np.max(np.abs(sol.x[:npf]) / box)) if npf else 0.0
        return s, L, float(r @ r), edge


def initial_participation(freq, Y, s, allowed, q):
    """Each mode's l: the leading left singular vector of its residues fitted per channel."""
    R = np.zeros((s.size, Y.shape[0], Y.shape[1]), dtype=complex)
    for c in range(Y.shape[0]):
        R[:, c, :] = RankOne(freq, Y[c:c + 1], s, allowed, q, np.ones((s.size, 1)), [])._inner(
            s, np.ones((s.size, 1)))[2]
    return np.array([np.linalg.svd(R[r][:, allowed[r]], full_matrices=False)[0][:, 0] for r in range(s.size)])


def harmonics(r):
    """The live channels' FRFs on the complete grid's normalised harmonics: (n_c, n_k, K), names."""
    D, names = grid_design(r.point_angle)
    live = np.isfinite(r.H).all(axis=(1, 2))
    return np.einsum("pk,cpf->ckf", D / np.linalg.norm(D, axis=0), r.H[live]), names


def table(run_dir):
    """The table's modes: poles in the FRFs' frame (the exponential window's decay put back)."""
    r = read_frf(run_dir / "frf.h5")
    rows = list(csv.DictReader(open(run_dir / "modes.csv")))
    f = np.array([float(m["frequency_hz"]) for m in rows])
    z = np.array([float(m["damping_ratio"]) for m in rows])
    s = TAU * f * (-z + 1j * np.sqrt(1 - z**2)) - (1 / r.exp_tau_s if r.exp_tau_s else 0)
    return r, s, rows


def dispersion(rows, branch):
    """The branch's f(n) from the table's clear rows (both confidences ≥ 0.5): the longest chain
    rising in n and f whose steps stay under 3 × the median step (a misread row breaks it)."""
    pts = sorted((int(m["n"]), float(m["frequency_hz"]), float(m["damping_ratio"])) for m in rows
                 if m["branch"] == branch and float(m["n_confidence"]) >= 0.5 and float(m["branch_confidence"]) >= 0.5)
    if len(pts) < 2:
        return None
    steps = [(b[1] - a[1]) / (b[0] - a[0]) for a, b in zip(pts[:-1], pts[1:]) if b[0] > a[0]]
    cap = 3 * max(float(np.median(steps)), 0.0) if steps else np.inf
    best, prev = [1] * len(pts), [-1] * len(pts)
    for i, (ni, fi, _) in enumerate(pts):
        for j, (nj, fj, _) in enumerate(pts[:i]):
            if nj < ni and fj < fi and (fi - fj) / (ni - nj) <= cap and best[j] + 1 > best[i]:
                best[i], prev[i] = best[j] + 1, j
    i, chain = int(np.argmax(best)), []
    while i >= 0:
        chain.append(pts[i])
        i = prev[i]
    chain.sort()
    return np.array([c[0] for c in chain]), np.array([c[1] for c in chain]), np.array([c[2] for c in chain])


def proposals(rows, band, truth, offset):
    """(f, n, branch, ζ) of every order inside a branch's clear range that the table does not hold;
    at the truth × (1 + offset) when ``offset`` is given."""
    out = []
    for br in ("same", "opposite"):
        d = dispersion(rows, br)
        if d is None:
            continue
        nn, ff, zz = d
        held = {int(m["n"]) for m in rows if m["branch"] == br}
        for n in range(int(nn[0]) + 1, int(nn[-1])):
            f, z = float(np.interp(n, nn, ff)), float(np.interp(n, nn, zz))
            if offset is not None and (n, br) in truth:
                f = truth[n, br] * (1 + offset)
            if n not in held and band[0] < f * (1 - WINDOW_HALF_WIDTHS * z) and f * (1 + WINDOW_HALF_WIDTHS * z) < band[1]:
                out.append((f, n, br, z))
    return sorted(out)


def missed_proposals(record, rows, band, offset):
    """(f, n, branch, ζ) of every mode the validation record (one line of validation.py's
    ``--out``) scores missed or mislabelled, at its truth × (1 + offset), with its branch's median
    table damping: what the joint fit could do from a good start where no dispersion reaches."""
    out = []
    for d in record["detail"]:
        if d["status"] == "missed" or d["status"].startswith("mislabelled"):
            zs = [float(m["damping_ratio"]) for m in rows if m["branch"] == d["branch"]]
            z = float(np.median(zs)) if zs else 0.02
            f = d["frequency_hz"] * (1 + offset)
            if band[0] < f * (1 - WINDOW_HALF_WIDTHS * z) and f * (1 + WINDOW_HALF_WIDTHS * z) < band[1]:
                out.append((f, int(d["n"]), d["branch"], z))
    return sorted(out)


def window_test(r, Hh, names, s_all, f_c, z_c, groups, extra=(), free_half_widths=FREE_HALF_WIDTHS):
    """The proposal at ``f_c`` tested in each order group of ``groups`` (module doc): a list of
    dict(g, gain, f, z, edge)."""
    q = FORM_Q[r.form]
    hw_c = z_c * f_c
    lo, hi = f_c - WINDOW_HALF_WIDTHS * hw_c, f_c + WINDOW_HALF_WIDTHS * hw_c
    wl = (r.freq_hz >= lo) & (r.freq_hz <= hi)
    freq, Y = r.freq_hz[wl], Hh[:, :, wl]
    Y = Y / np.sqrt(np.mean(np.abs(Y) ** 2, axis=(1, 2)))[:, None, None]
    f_all, hw_all = s_all.imag / TAU, -s_all.real / TAU
    s0 = s_all[(f_all + 2 * hw_all >= lo) & (f_all - 2 * hw_all <= hi)]
    allowed = np.ones((s0.size, Y.shape[1]), dtype=bool)
    ex = [(se, ge) for se, ge in extra if lo <= se.imag / TAU <= hi]
    if ex:
        s0 = np.concatenate([s0, [se for se, _ in ex]])
        allowed = np.vstack([allowed] + [np.array([nm[0] == ge for nm in names])[None] for _, ge in ex])
    free = np.flatnonzero(np.abs(s0.imag / TAU - f_c) <= free_half_widths * (-s0.real / TAU)) if free_half_widths \
        else np.flatnonzero((s0.imag / TAU >= lo) & (s0.imag / TAU <= hi))
    L0 = initial_participation(freq, Y, s0, allowed, q)
    tbox = TABLE_BOX_HALF_WIDTHS if not free_half_widths else BOX_HALF_WIDTHS
    s_h0, L0, _, _ = RankOne(freq, Y, s0, allowed, q, L0, free, tbox).solve()
    res = RankOne(freq, Y, s_h0, allowed, q, L0, [])._inner(s_h0, L0)[3]
    Y = Y / np.sqrt(np.mean(np.abs(res) ** 2, axis=(1, 2)))[:, None, None]
    s_h0, L0, E0, _ = RankOne(freq, Y, s_h0, allowed, q, L0, free, tbox).solve()
    if SHOWN_LEVEL:  # each table mode free only on the harmonics it shows (the bound's model)
        psi = RankOne(freq, Y, s_h0, allowed, q, L0, [])._inner(s_h0, L0)[2]
        peak = np.abs(L0).max(axis=1)[:, None] * np.abs(psi) * (np.abs(s_h0) ** q / -s_h0.real)[:, None]
        shown = peak >= SHOWN_LEVEL
        shown[np.arange(s_h0.size), np.argmax(peak, axis=1)] = True
        allowed = allowed & shown
        s_h0, L0, E0, _ = RankOne(freq, Y, s_h0, allowed, q, L0, free, tbox).solve()
    w = TAU * f_c
    sc = complex(-z_c * w, w * np.sqrt(1 - z_c**2))
    out = []
    for g in groups:
        cand = np.array([nm[0] == g for nm in names])
        s1, al1 = np.append(s_h0, sc), np.vstack([allowed, cand[None]])
        L1 = np.vstack([L0, initial_participation(freq, Y, s1, al1, q)[-1:]])
        box = np.append(np.full(free.size, TABLE_BOX_HALF_WIDTHS if not free_half_widths else BOX_HALF_WIDTHS),
                        BOX_HALF_WIDTHS)
        s_h1, L1, E1, edge = RankOne(freq, Y, s1, al1, q, L1, np.append(free, s1.size - 1), box).solve()
        edge = float(abs(s_h1[-1].imag - sc.imag) / (BOX_HALF_WIDTHS * -sc.real))
        p1 = 2 * al1.sum() + 4 * Y.shape[0] * Y.shape[1] + 2 * L1.size
        sig2 = E1 / (2 * Y.size - p1)
        thr = scipy.special.chdtri(2 * (int(cand.sum()) + Y.shape[0] - 1) + 2, ALPHA / freq.size)
        out.append({"g": g, "gain": (E0 - E1) / sig2 / thr, "f": s_h1[-1].imag / TAU,
                    "z": -s_h1[-1].real / abs(s_h1[-1]), "edge": edge})
    return out


def truth_of(case_name, tyre, r, seed=None):
    """{(n, branch): f} of the case's truth modes; the strong modes' poles (tread amplitude > 0.05);
    every truth frequency. ``seed``: a held-out draw of ``validation.held_out_levels``."""
    from validation import held_out_levels, matrix
    cases = matrix(tyre=tyre) if seed is None else held_out_levels(12, seed=seed, tyre=tyre)
    c = next(c for c in cases if c.name == case_name)
    cfg = config_for(c)
    sim = simulate(cfg)
    tread = next(ch.name for ch in cfg.channels if ch.location == "tread")
    strong = []
    for m in sim.truth["modes"]:
        phi = np.asarray(m["shape_at_points"][tread])
        if np.abs(phi[0] if phi.ndim > 1 else phi).max() > 0.05:
            w, z = TAU * m["frequency_hz"], m["damping_ratio"]
            strong.append(complex(-z * w, w * np.sqrt(1 - z**2)) - (1 / r.exp_tau_s if r.exp_tau_s else 0))
    return ({(m["n"], m["branch"]): m["frequency_hz"] for m in sim.truth["modes"]}, np.array(strong),
            np.array([m["frequency_hz"] for m in sim.truth["modes"]]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("keep")
    ap.add_argument("case")
    ap.add_argument("--tyre", default="gl073a")
    ap.add_argument("--start", default="dispersion", help="dispersion, or truth:OFFSET")
    ap.add_argument("--nulls", type=int, default=3)
    ap.add_argument("--seed", type=int, default=None, help="a held-out draw's seed (validation.py --held-out-seed)")
    ap.add_argument("--guard", type=float, default=GUARD_HALF_WIDTHS)
    ap.add_argument("--record", help="validation.py --out file: propose the case's missed modes instead "
                                     "(at the truth × (1 + the --start truth: offset))")
    ap.add_argument("--oracle-pairs", action="store_true")
    ap.add_argument("--free-half-widths", type=float, default=FREE_HALF_WIDTHS)
    ap.add_argument("--lo", type=float, default=0.0)
    ap.add_argument("--hi", type=float, default=np.inf)
    a = ap.parse_args(argv)
    run_dir = Path(a.keep) / a.case.replace(":", "_").replace("=", "-").replace(" ", "").replace(",", "_") / "run"  # (validation._one)
    r, s_all, rows = table(run_dir)
    Hh, names = harmonics(r)
    N = len(r.point_angle)
    grp = lambda n: min(n % N, N - n % N)  # noqa: E731
    truth, strong, every = truth_of(a.case, a.tyre, r, a.seed)
    if a.oracle_pairs:
        f_all = s_all.imag / TAU
        add = [s for s in strong if np.min(np.abs(f_all - s.imag / TAU)) > r.freq_hz[1] - r.freq_hz[0]
               and r.freq_hz[1] < s.imag / TAU < r.freq_hz[-1]]
        print("oracle: the truth's strong modes no row stands for:", sorted(round(s.imag / TAU, 2) for s in add))
        s_all = np.concatenate([s_all, add])
    offset = float(a.start.split(":")[1]) if a.start.startswith("truth:") else None
    band = (r.freq_hz[1], r.freq_hz[-1])
    if a.record:  # the ruler's misses of this case, from a good start
        import json
        rec = next(json.loads(line) for line in open(a.record) if json.loads(line)["name"] == a.case)
        props = missed_proposals(rec, rows, band, offset or 0.0)
    else:
        props = proposals(rows, band, truth, offset)
    props = [p for p in props if a.lo <= p[0] <= a.hi]
    passed, null_gains = [], []
    rng = np.random.default_rng(0)
    for f, n, br, z in props:
        empty = [g for g in range(N // 2 + 1) if g != grp(n) and not any(
            abs(ft - f) <= 3 * z * f and grp(nt) == g for (nt, _), ft in truth.items())]
        nulls = list(rng.choice(empty, size=min(a.nulls, len(empty)), replace=False)) if empty else []
        res = window_test(r, Hh, names, s_all, f, z, [grp(n)] + nulls, free_half_widths=a.free_half_widths)
        t, x = truth.get((n, br), np.nan), res[0]  # (an order the generator does not list: nan)
        null_gains += [y["gain"] for y in res[1:]]
        print(f"n={n:3d} {br:8s} start {f:8.2f} truth {t:8.2f} fit {x['f']:8.2f} ({100 * (x['f'] - t) / t:+.2f} %) "
              f"gain {x['gain']:7.1f} edge {x['edge']:.2f} | nulls " + " ".join(f"{y['gain']:.1f}" for y in res[1:]),
              flush=True)
        if x["gain"] > 1 and x["edge"] < 0.9:
            w = TAU * x["f"]
            passed.append((n, br, z, complex(-x["z"] * w, w * np.sqrt(1 - x["z"] ** 2)), grp(n)))
    if null_gains:
        print(f"nulls: {len(null_gains)}, over 1: {sum(g > 1 for g in null_gains)}, max {max(null_gains):.1f}")
    final = []
    for i, (n, br, z, s, g) in enumerate(passed):  # round 2: every other passed proposal in the model
        x = window_test(r, Hh, names, s_all, s.imag / TAU, z, [g], [p[3:] for j, p in enumerate(passed) if j != i],
                        a.free_half_widths)[0]
        t = truth.get((n, br), np.nan)
        print(f"round 2 n={n:3d} {br:8s} truth {t:8.2f} fit {x['f']:8.2f} ({100 * (x['f'] - t) / t:+.2f} %) "
              f"gain {x['gain']:7.1f} edge {x['edge']:.2f}", flush=True)
        final.append((n, br, x, t))
    summary(final, s_all, truth, every, rows, a.guard)


def summary(final, s_table, truth, every, rows, guard):
    """What round 2's rows would do to the ruler's counts: a row is added when it passes and lies
    more than ``guard`` of its half-width from every table row (closer, it is a strong mode's
    duplicate: the weak mode cannot be told from it); it then finds its order (its truth within
    0.3 %, and no table row already does), stands for another truth mode only (within 0.3 % of
    another: not spurious to the ruler, wrong all the same) or is spurious (no truth within 0.3 %)."""
    f_tab = s_table.imag / TAU
    held = [float(m["frequency_hz"]) for m in rows]
    out = {"added": [], "finds": [], "already": [], "other_truth": [], "spurious": [], "duplicates": []}
    for n, br, x, t in final:
        if not (x["gain"] > 1 and x["edge"] < 0.9):
            continue
        if np.min(np.abs(f_tab - x["f"])) <= guard * x["z"] * x["f"]:
            out["duplicates"].append(n)
            continue
        out["added"].append(n)
        if t and abs(x["f"] / t - 1) <= 0.003:
            out["already" if any(abs(h / t - 1) <= 0.003 for h in held) else "finds"].append(n)
        elif np.any(np.abs(every / x["f"] - 1) <= 0.003):
            out["other_truth"].append(n)
        else:
            out["spurious"].append(n)
    print("summary " + " ".join(f"{k}={v}" for k, v in out.items()), flush=True)


if __name__ == "__main__":
    main()
