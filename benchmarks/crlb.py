"""The ruler's resolvable range: the Cramér–Rao lower bound of each truth mode's frequency.

    python benchmarks/crlb.py /tmp/m0.jsonl /tmp/m0 [--only CASE] [--out crlb.jsonl]

For every expected truth mode of a validation case (``expected_groups``), the bound σ_f
on the frequency of any unbiased estimator, given the test's noise and the mode's
neighbours, from the Fisher information of the pole–residue FRF model

    H_cp(ω) = Σ_k [A_kcp / (iω − λ_k) + A*_kcp / (iω − λ*_k)] + B_cp,
    λ_k = 2π f_k (−ζ_k + i √(1 − ζ_k²)),

over a local window: the mode's half-power band [f (1 − ζ), f (1 + ζ)] (``--widen`` ×
the half-width) widened to the bands of the recorded truth modes that overlap it; the
model holds every recorded truth mode whose band overlaps the window (their f and ζ are
nuisance parameters) and a complex constant B_cp per FRF (what the modes outside the
window leave in it). *Recorded*: the mode's peak receptance |A|/ζω at its best FRF is at
least the noise floor there (SNR ≥ 1); a mode below the noise on every FRF carries no
information on its own pole and enters as known (the ring's ~700 high orders of the
same branch converging on 167.8 Hz are mostly such; modelling them free would make the
unstructured window all nuisance).

*Noise.* Each record's DFT line carries the sensor noise of the generator: white, std
``noise`` × the channel's RMS over the test (force: × the force's RMS), so complex
variance n_s σ² per line. H1 over the hits of point p then errs, to first order, by
(δY − H δX)/X, of variance s²_cp(f) = n_s (σ_c² + |H_cp|² σ_F²) / Σ_h |X_ph(f)|², with
X_ph the DFT of hit h's force (its pulse width, amplitude, bounce and the anti-alias
filter, from the truth's record of the hits). The FRF form does not change the bound:
receptance, mobility and accelerance differ by the known factor (iω)^k on each line,
which scales data and noise alike; the bound is computed on receptance.

*Residues,* two ways:

* ``unstructured`` — every A_kcp (and B_cp) free: linear parameters eliminated by
  projection, so the information on θ = (ln f_k, ln ζ_k) is Σ_cp J_cpᵀ (I − P_G) J_cp
  (whitened, real and imaginary parts stacked; G the pole basis and the constant);
* ``structured`` — as the tool may assume one order per mode: A_kcp = u_kc cos nθ_p +
  v_kc sin nθ_p (u, v complex per mode and channel; a degenerate cos/sin pair of one
  frequency is one pole with both columns), which shares the residues across points.

A pair of one n and branch split by less than ζ f is one truth group (the ruler's); its
bound is that of its members' mean frequency (∇gᵀ F⁻¹ ∇g). The Jacobian is taken at the
truth (residues from the generator's shapes at the points and channels, A = φ_c φ_p /
2iω_d, as ``tyre.solve.frf``), so the bound is exact for the structured model only when
the truth's shape at the points is one order: ``purity`` reports the share of the
residues' energy in the order's cos/sin columns.

Per case the script prints how many expected modes have 3 σ_f > 0.3 % f under each model,
the tool's errors on the found modes in units of σ_f (an efficient estimator's |error|/σ
has median 0.67), and every missed or mislabelled mode and every ``biased`` spurious row
(``benchmarks/spurious.py``) with σ_f / f and the tool's error in σ_f.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import scipy.signal

from tiremodal_cli.tyre.simulate import half_sine_spectrum, simulate
from tiremodal_cli.workflow.validation import Case, config_for
from tiremodal_cli.workflow.validation_scoring import TOLERANCE, expected_groups, read_modes



def _load(name):
    spec = importlib.util.spec_from_file_location(name, Path(__file__).with_name(f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


spurious = _load("spurious")
polyref = _load("crlb_polyref")


# ----------------------------------------------------------------------------- the bound
def pole(f_hz, zeta):
    """λ = 2π f (−ζ + i √(1 − ζ²)) (rad/s) and its derivatives by ln f and ln ζ."""
    f_hz, zeta = np.asarray(f_hz, float), np.asarray(zeta, float)
    lam = 2 * np.pi * f_hz * (-zeta + 1j * np.sqrt(1 - zeta**2))
    d_lnf = lam
    d_lnz = 2 * np.pi * f_hz * zeta * (-1 - 1j * zeta / np.sqrt(1 - zeta**2))
    return lam, d_lnf, d_lnz


def pole_basis(w, lam):
    """(L, 2K) complex: the response of pole k to Re A_k (column 2k) and Im A_k (2k + 1).

    Parameters
    ----------
    w : (L,) rad/s
    lam : (K,) complex poles, rad/s
    """
    a = 1 / (1j * w[:, None] - lam[None, :])
    b = 1 / (1j * w[:, None] - np.conj(lam)[None, :])
    return np.stack([a + b, 1j * (a - b)], axis=-1).reshape(len(w), -1)


def jacobian(w, lam, d_lnf, d_lnz, A):
    """∂H/∂(ln f_k, ln ζ_k) at residues A: (..., L, 2K) complex.

    Parameters
    ----------
    w : (L,) rad/s; lam, d_lnf, d_lnz : (K,) complex; A : (..., K) complex residues
    """
    a2 = 1 / (1j * w[:, None] - lam[None, :]) ** 2  # (L, K)
    b2 = 1 / (1j * w[:, None] - np.conj(lam)[None, :]) ** 2
    A = np.asarray(A)[..., None, :]
    cols = [A * a2 * d + np.conj(A) * b2 * np.conj(d) for d in (d_lnf, d_lnz)]
    return np.stack(cols, axis=-1).reshape(*A.shape[:-2], len(w), -1)


def _real(Z, s):
    """Whitened real form: Z (..., L, m) complex over noise std s (..., L) of a circular
    complex line (E|n|² = s²) → (..., 2L, m), each row of unit noise variance."""
    Zw = Z / (s[..., None] / np.sqrt(2))
    return np.concatenate([Zw.real, Zw.imag], axis=-2)


def _projected_info(Jr, Gr):
    """Σ over the leading axes of Jᵀ (I − P_G) J, G's range by SVD (rank-revealing)."""
    U, sv, _ = np.linalg.svd(Gr, full_matrices=False)
    tol = sv.max(axis=-1, keepdims=True) * max(Gr.shape[-2:]) * np.finfo(float).eps
    U = U * (sv > tol)[..., None, :]
    JU = np.swapaxes(U, -1, -2) @ Jr
    F = np.swapaxes(Jr, -1, -2) @ Jr - np.swapaxes(JU, -1, -2) @ JU
    return F.reshape(-1, *F.shape[-2:]).sum(axis=0)


def fisher_unstructured(w, f_hz, zeta, A, s, background=True):
    """Fisher information on (ln f_k, ln ζ_k) with every residue (and a constant per FRF) free.

    Parameters
    ----------
    w : (L,) rad/s
    f_hz, zeta : (K,) the poles' natural frequencies (Hz) and damping ratios
    A : (M, K) complex residues of the M FRFs at the truth
    s : (M, L) std of each FRF line's complex noise (same units as H)
    background : bool — a free complex constant per FRF

    Returns
    -------
    (2K, 2K) ndarray, order (ln f_1, ln ζ_1, ln f_2, …)
    """
    lam, dlf, dlz = pole(f_hz, zeta)
    G = pole_basis(w, lam)
    if background:
        G = np.concatenate([G, np.ones((len(w), 1)), 1j * np.ones((len(w), 1))], axis=1)
    J = jacobian(w, lam, dlf, dlz, A)
    return _projected_info(_real(J, s), _real(np.broadcast_to(G, (len(A),) + G.shape), s))


def fisher_structured(w, f_hz, zeta, orders, theta, A, s, background=True):
    """As :func:`fisher_unstructured`, the residues one order per pole and channel:
    A_kcp = u_kc cos nθ_p + v_kc sin nθ_p (every order of ``orders[k]``).

    Parameters
    ----------
    orders : list of K sets of int; theta : (P,) point angles, rad
    A : (C, P, K) complex; s : (C, P, L)
    """
    lam, dlf, dlz = pole(f_hz, zeta)
    B = pole_basis(w, lam).reshape(len(w), len(lam), 2)
    cols = []
    for k, ns in enumerate(orders):
        for n in sorted(ns):
            for trig in (np.cos(n * theta), np.sin(n * theta)):
                if np.max(np.abs(trig)) > 1e-9:
                    cols.append(trig[:, None, None] * B[None, :, k, :])  # (P, L, 2)
    P, L = len(theta), len(w)
    if background:
        eye = np.eye(P)[:, None, :, None] * np.array([1.0, 1j])[None, None, None, :]
        cols.append(np.broadcast_to(eye, (P, L, P, 2)).reshape(P, L, 2 * P))
    G = np.concatenate(cols, axis=-1)  # (P, L, m)
    J = jacobian(w, lam, dlf, dlz, A)  # (C, P, L, 2K)
    Gr = np.stack([_real(G, s[c]).reshape(-1, G.shape[-1]) for c in range(len(A))])
    Jr = np.stack([_real(J[c], s[c]).reshape(-1, J.shape[-1]) for c in range(len(A))])
    return _projected_info(Jr, Gr)


def bound(F, grad):
    """σ of gᵀθ from information F (pseudo-inverse: a nuisance pole with no information
    does not couple). ``grad`` (2K,). inf when the target has no information."""
    C = np.linalg.pinv(F, rcond=1e-12, hermitian=True)
    v = float(grad @ C @ grad)
    idx = np.flatnonzero(grad)
    if v <= 0 or np.any(np.diag(F)[idx] <= 1e-12 * max(np.max(np.diag(F)), 1e-300)):
        return float("inf")
    return float(np.sqrt(v))


# ----------------------------------------------------------------------------- a case
def force_power(cfg, truth, freq):
    """Σ_h |X_ph(f)|², (P, n_f): each hit's force DFT as the generator made it (its pulse
    width and amplitude, a bounce, the front end's 8th-order Butterworth at 0.4 fs)."""
    fs = cfg.sample_rate
    aa = np.ones(len(freq))
    if cfg.anti_alias:
        z, p, k = scipy.signal.butter(8, 2 * np.pi * 0.4 * fs, analog=True, output="zpk")
        aa = np.abs(scipy.signal.freqs_zpk(z, p, k, worN=2 * np.pi * freq)[1])
    index = truth["point_index_in_file"]
    X2 = np.zeros((len(index), len(freq)))
    for hit in truth["hits"]:
        spec = half_sine_spectrum(freq, hit["width_s"], hit["amplitude_n"])
        if "double_hit" in hit:
            d = hit["double_hit"]
            spec = spec * (1 + d["relative_amplitude"] * np.exp(-2j * np.pi * freq * d["delay_s"]))
        X2[index[str(hit["point"])]] += np.abs(spec * aa * fs) ** 2
    return X2


def noise_std(cfg, sim):
    """Std of each H1 line's complex error, on receptance: (C, P, n_f) in m/N (lines at
    0 Hz inf). First order in the noise: n_s (σ_c² + |H|² σ_F²) / Σ_h |X|², σ the
    generator's white noise (``noise`` × the noise-free RMS of the channel or force)."""
    m = sim.measurement
    k = np.sqrt(1 + cfg.noise**2)  # the records hold signal + noise of std noise × RMS
    r_rms = np.sqrt(np.mean(np.asarray(m.response, float) ** 2, axis=(0, 1, 3))) / k
    f_rms = np.sqrt(np.mean(np.asarray(m.force, float) ** 2)) / k
    X2 = force_power(cfg, sim.truth, sim.freq_hz)
    var = cfg.n_samples * cfg.noise**2 * ((r_rms**2)[:, None, None] + np.abs(sim.frf) ** 2 * f_rms**2)
    w2 = (2 * np.pi * sim.freq_hz) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.sqrt(var / X2[None]) / np.where(w2 > 0, w2, 0.0)


def residues(cfg, truth):
    """(C, P, n_modes) complex receptance residues of the truth modes, A = φ_c φ_p / 2iω_d
    (channels at their angle, the hammer on the tread at each point)."""
    ang = np.asarray(truth["point_angle_rad"])
    tread = next(c.name for c in cfg.channels if c.location == "tread")
    out = np.zeros((len(cfg.channels), len(ang), len(truth["modes"])), complex)
    for k, mode in enumerate(truth["modes"]):
        wd = 2 * np.pi * mode["frequency_hz"] * np.sqrt(1 - mode["damping_ratio"] ** 2)
        phi_p = np.asarray(mode["shape_at_points"][tread])
        for c, ch in enumerate(cfg.channels):
            i0 = int(np.argmin(np.abs(np.angle(np.exp(1j * (ang - ch.angle_rad))))))
            out[c, :, k] = mode["shape_at_points"][ch.name][i0] * phi_p / (2j * wd)
    return out


def window(members, zeta, tf, tz, seen, widen=1.0):
    """The local window (Hz) of a group and the truth modes it models (bool (n_modes,)):
    the half-power band widened to every band of a mode the test records (``seen``: peak
    at or above the noise floor on some FRF) overlapping it; modelled, every recorded
    truth mode whose band overlaps the window."""
    lo, hi = min(members) * (1 - widen * zeta), max(members) * (1 + widen * zeta)
    blo, bhi = tf * (1 - widen * tz), tf * (1 + widen * tz)
    over = (blo <= hi) & (bhi >= lo) & seen
    lo, hi = min(lo, blo[over].min(initial=lo)), max(hi, bhi[over].max(initial=hi))
    return lo, hi, (blo <= hi) & (bhi >= lo) & seen


#: Relative split below which two truth modes are one pole (a degenerate cos/sin pair whose
#: frequencies differ by the eigensolver's round-off): 1e-6, a thousandth of the resolution
#: of any record here (0.5 Hz lines ≥ 2.5e-4 f up to 2 kHz).
MERGE = 1e-6


def poles_of(idx, truth):
    """The distinct poles of the modelled truth modes ``idx``: modes of one frequency (a
    degenerate cos/sin pair) are one pole. Returns (f, ζ, orders, member lists)."""
    f, z, orders, members = [], [], [], []
    for k in idx:
        m = truth["modes"][k]
        j = next((j for j, fj in enumerate(f) if abs(fj / m["frequency_hz"] - 1) < MERGE), None)
        if j is None:
            f.append(m["frequency_hz"]), z.append(m["damping_ratio"]), orders.append(set()), members.append([])
            j = len(f) - 1
        orders[j].add(int(m["n"]))
        members[j].append(k)
    return np.array(f), np.array(z), orders, members


def context(cfg, sim):
    """What every group's bound reads of a simulated case."""
    truth = sim.truth
    s = noise_std(cfg, sim)
    live = np.all(s[:, :, 1:] > 0, axis=(1, 2))  # a channel that records nothing (a clamped rim) holds no information
    A, s = residues(cfg, truth)[live], s[live]
    tf = np.array([m["frequency_hz"] for m in truth["modes"]])
    tz = np.array([m["damping_ratio"] for m in truth["modes"]])
    line = np.abs(sim.freq_hz[None, :] - tf[:, None]).argmin(axis=1)
    peak = np.abs(A) / (tz * 2 * np.pi * tf)  # (C, P, K): a pole pair's peak receptance |A| / ζω
    snr = np.max(peak / s[:, :, line], axis=(0, 1))
    return {"truth": truth, "freq": sim.freq_hz, "A": A, "s": s, "snr": snr, "polyref": _polyref_context(truth, A, s, snr, sim.freq_hz),
            "theta": np.asarray(truth["point_angle_rad"]),
            "tf": np.array([m["frequency_hz"] for m in truth["modes"]]),
            "tz": np.array([m["damping_ratio"] for m in truth["modes"]])}


def _polyref_context(truth, A, s, snr, freq):
    """The recorded truth poles as the poly-reference bound takes them (``crlb_polyref``):
    each pole's residues (C, P) summed over its members and split into rank one, the
    channels' noise the RMS over the points, and a cache of bounds by pole."""
    idx = np.flatnonzero(snr >= 1)
    f, z, _, pm = poles_of(idx, truth)
    lam = pole(f, z)[0]
    L, P = [], []
    for ks in pm:
        u, sv, vh = np.linalg.svd(A[:, :, ks].sum(axis=-1), full_matrices=False)
        L.append(u[:, 0] * sv[0])
        P.append(vh[0])
    line = freq > 0
    return {"members": pm, "freq": freq[line], "lam": lam, "L": np.array(L), "P": np.array(P),
            "noise": np.sqrt(np.mean(s[:, :, line] ** 2, axis=1)), "theta": np.asarray(truth["point_angle_rad"]),
            "cache": {}}


def polyref_bound(k, ctx) -> float:
    """σ_f / f of truth mode ``k``'s pole under the poly-reference model (rank-one residues,
    shapes on the harmonics they show above the noise: ``crlb_polyref``); inf for a mode
    below the noise on every FRF."""
    pr = ctx["polyref"]
    j = next((j for j, ks in enumerate(pr["members"]) if k in ks), None)
    if j is None:
        return np.inf
    if j not in pr["cache"]:
        pr["cache"][j] = float(polyref.frequency_bounds(pr["freq"], pr["lam"], pr["L"], pr["P"], pr["noise"],
                                                        point_angle_rad=pr["theta"], form="receptance",
                                                        targets=[j])[j])
    return pr["cache"][j]


def _purity(A, theta, orders):
    """Share of the residues' energy over the points (all channels) in the cos/sin columns
    of the pole's orders: 1 when the truth's shape is one order on the grid."""
    T = np.stack([t(n * theta) for n in sorted(orders) for t in (np.cos, np.sin)], axis=1)
    proj = T @ np.linalg.lstsq(T, A.T, rcond=None)[0]  # (P, C)
    tot = np.sum(np.abs(A) ** 2)
    return float(np.sum(np.abs(proj) ** 2) / tot) if tot > 0 else 1.0


def group_bound(g, ctx, widen=1.0, background=True):
    """σ_f / f of a truth group's (mean) frequency, unstructured and structured residues.

    Returns {"sigma_u", "sigma_s", "sigma_r" (relative; the last the poly-reference model's,
    the largest of the members'), "purity", "n_lines", "n_poles", "window_hz"}.
    """
    truth, tf = ctx["truth"], ctx["tf"]
    mem = [k for k, m in enumerate(truth["modes"]) if m["n"] == g["n"] and m["branch"] == g["branch"]
           and any(abs(m["frequency_hz"] / x - 1) < 1e-9 for x in g["members"])]
    seen = ctx["snr"] >= 1
    mem = [k for k in mem if seen[k]] or mem  # the members a test records (a sin member at a channel's node is not)
    lo, hi, model = window(g["members"], g["zeta"], tf, ctx["tz"], seen, widen)
    model[mem] = True
    idx = np.flatnonzero(model)
    f, z, orders, pm = poles_of(idx, truth)
    A = np.stack([ctx["A"][:, :, ks].sum(axis=-1) for ks in pm], axis=-1)  # (C, P, K)
    lines = (ctx["freq"] >= lo) & (ctx["freq"] <= hi) & (ctx["freq"] > 0)
    df = ctx["freq"][1] - ctx["freq"][0]
    while lines.sum() < 2 * (len(f) + 1):  # twice the complex unknowns of an FRF (K residues, a constant)
        lo, hi = lo - df / 2, hi + df / 2
        lines = (ctx["freq"] >= lo) & (ctx["freq"] <= hi) & (ctx["freq"] > 0)
    w, s = 2 * np.pi * ctx["freq"][lines], ctx["s"][:, :, lines]
    mean = float(np.mean(tf[mem]))
    grad = np.zeros(2 * len(f))
    target = []
    for k in mem:
        j = next(j for j, ks in enumerate(pm) if k in ks)
        grad[2 * j] += tf[k] / (len(mem) * mean)
        target.append(j)
    C, P, K = A.shape
    Fu = fisher_unstructured(w, f, z, A.reshape(C * P, K), s.reshape(C * P, -1), background)
    Fs = fisher_structured(w, f, z, orders, ctx["theta"], A, s, background)
    pur = min(_purity(A[:, :, j], ctx["theta"], orders[j]) for j in set(target))
    return {"sigma_u": bound(Fu, grad), "sigma_s": bound(Fs, grad),
            "sigma_r": max(polyref_bound(k, ctx) for k in mem), "purity": pur,
            "n_lines": int(lines.sum()), "n_poles": int(K), "window_hz": [round(lo, 2), round(hi, 2)]}


def _nearest(rows, f):
    """Signed relative error of the table row nearest ``f`` (any label), or None."""
    if not rows:
        return None
    r = min(rows, key=lambda r: abs(r["frequency_hz"] - f))
    return r["frequency_hz"] / f - 1


def case_bounds(rec, keep, widen=1.0, background=True, misses_only=False):
    """Every expected group of a case of the matrix (record ``rec`` of validation.py's
    JSON lines, its kept run under ``keep``) with its bounds, status and the tool's error;
    and every ``biased`` spurious row with the bound of the truth group it estimates."""
    case = Case(**{k: v for k, v in rec["case"].items() if k in Case.__dataclass_fields__})
    cfg = config_for(case)
    sim = simulate(cfg)
    ctx = context(cfg, sim)
    groups = expected_groups(sim, cfg)
    rows = read_modes(Path(keep) / spurious.folder_of(rec["name"]) / "run" / "modes.csv")
    expected = [g for g in groups if g["expected"]]
    if len(expected) != len(rec["detail"]) or any(abs(g["frequency_hz"] - d["frequency_hz"]) > 1e-2
                                                  for g, d in zip(expected, rec["detail"])):
        raise ValueError(f"{rec['name']}: the truth groups do not match the record's detail")
    out = []
    for g, d in zip(expected, rec["detail"]):
        if misses_only and d["status"] == "found":
            continue
        b = group_bound(g, ctx, widen, background)
        err = _nearest(rows, g["frequency_hz"])
        out.append({"frequency_hz": g["frequency_hz"], "n": g["n"], "branch": g["branch"], "snr": g["snr"],
                    "status": d["status"], "error": err, **b})
    biased = []
    for sp in spurious.classify_spurious(rows, sim.truth["modes"]):
        if sp["class"] != "biased":
            continue
        g = next(g for g in groups if g["n"] == sp["truth_n"] and g["branch"] == sp["truth_branch"]
                 and any(abs(x / sp["truth_hz"] - 1) < 1e-9 for x in g["members"]))
        b = group_bound(g, ctx, widen, background)
        biased.append({"frequency_hz": sp["frequency_hz"], "truth_hz": sp["truth_hz"], "n": g["n"],
                       "branch": g["branch"], "expected": g["expected"], "snr": g["snr"],
                       "error": sp["frequency_hz"] / sp["truth_hz"] - 1, **b})
    return {"name": rec["name"], "groups": out, "biased": biased}


# ----------------------------------------------------------------------------- report
def _sig(x, s):
    return "–" if x is None or not np.isfinite(s) or s == 0 else f"{abs(x) / s:.1f}"


def summary(res) -> dict:
    """Counts of a case's bounds: expected modes beyond the ruler's reach (3 σ_f > 0.3 %)
    under each model, and the found modes' median |error| / σ_f (efficient: 0.67)."""
    gs = res["groups"]
    found = [g for g in gs if g["status"] == "found" and g["error"] is not None]

    def med(key):
        r = [abs(g["error"]) / g[key] for g in found if np.isfinite(g[key]) and g[key] > 0]
        return float(np.median(r)) if r else None
    return {"expected": len(gs), "beyond_u": sum(3 * g["sigma_u"] > TOLERANCE for g in gs),
            "beyond_s": sum(3 * g["sigma_s"] > TOLERANCE for g in gs),
            "beyond_r": sum(3 * g["sigma_r"] > TOLERANCE for g in gs),
            "impure": sum(g["purity"] < 0.99 for g in gs),
            "found_err_sigma_u": med("sigma_u"), "found_err_sigma_s": med("sigma_s")}


def print_case(res) -> None:
    s = summary(res)
    fmt = lambda x: "–" if x is None else f"{x:.2f}"  # noqa: E731
    print(f"{res['name']}: expected {s['expected']}, 3σ_f > 0.3 %: unstructured {s['beyond_u']}, "
          f"structured {s['beyond_s']}, poly-reference {s['beyond_r']}; impure shapes {s['impure']}; found |err|/σ median "
          f"{fmt(s['found_err_sigma_u'])} (u) {fmt(s['found_err_sigma_s'])} (s)")
    for g in res["groups"]:
        if g["status"] != "found":
            e = "–" if g["error"] is None else f"{100 * g['error']:+.3f} %"
            print(f"  {g['frequency_hz']:8.2f} Hz n={g['n']:<2d} {g['branch']:8s} {g['status']:28s} "
                  f"snr {g['snr']:7.1f}  σ_f/f {100 * g['sigma_u']:.4f} % (u) {100 * g['sigma_s']:.4f} % (s) "
                  f"{100 * g['sigma_r']:.4f} % (r)  "
                  f"purity {g['purity']:.3f}  nearest row {e} = {_sig(g['error'], g['sigma_u'])} σ_u, "
                  f"{_sig(g['error'], g['sigma_s'])} σ_s")
    for b in res["biased"]:
        print(f"  biased row {b['frequency_hz']:8.2f} Hz of truth {b['truth_hz']:.2f} n={b['n']} {b['branch']} "
              f"({'expected' if b['expected'] else 'not expected'}, snr {b['snr']:.1f})  σ_f/f "
              f"{100 * b['sigma_u']:.4f} % (u) {100 * b['sigma_s']:.4f} % (s) {100 * b['sigma_r']:.4f} % (r)  error {100 * b['error']:+.3f} % = "
              f"{_sig(b['error'], b['sigma_u'])} σ_u, {_sig(b['error'], b['sigma_s'])} σ_s")


def main(argv=None) -> int:
    ap = spurious.matrix_parser(__doc__)
    ap.add_argument("--widen", type=float, default=1.0, help="window: this many half-power half-widths")
    ap.add_argument("--no-background", action="store_true", help="no free constant per FRF")
    ap.add_argument("--out", help="write each case's bounds here (JSON lines)")
    ap.add_argument("--misses-only", action="store_true",
                    help="bound only the modes not found and the biased rows (the counts then cover those only)")
    a = ap.parse_args(argv)
    out = open(a.out, "w", encoding="utf-8") if a.out else None
    tot = {}
    for line in Path(a.records).read_text(encoding="utf-8").splitlines():
        rec = json.loads(line)
        if a.only and rec["name"] not in a.only:
            continue
        res = case_bounds(rec, a.keep, a.widen, not a.no_background, a.misses_only)
        print_case(res)
        gen = rec["case"]["generator"]
        for k, v in summary(res).items():
            if isinstance(v, int):
                tot.setdefault(gen, {}).setdefault(k, 0)
                tot[gen][k] += v
        if out:
            out.write(json.dumps(res | {"summary": summary(res)}, default=float) + "\n")
            out.flush()
    for gen, t in tot.items():
        print(f"total {gen}: " + ", ".join(f"{k} {v}" for k, v in t.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
