"""How a validation case is scored: the ruler's rules, using only the generator's truth and
the test's set-up (also in docs/validation.md).

What a test *could* show:

* the front end's usable band: the mode's half-power band, up to f (1 + ζ), below
  fs / 2.56 (the usual analyser bandwidth under the anti-alias filter) and where the
  hammer's force spectrum is within 20 dB of its low-frequency level — a mode with one
  flank cut off by the band's top is fitted to that flank alone, its frequency biased
  (the estimator rejects such a pole: :func:`tiremodal_cli.modal.merge.off_edges`);
* visibility: the mode's peak accelerance at its best channel and point, |φ_o φ_i| / 2ζ,
  at least 3 × the H1 noise floor there (sensor noise of std ``noise`` × the channel's
  RMS, white, over the hits' averaged force spectrum);
* not in an unresolvable crowd: no other truth mode of the same branch whose order is an
  alias of this one with N points (n' ≡ ±n mod N) within one half-power bandwidth 2ζf
  (different orders are told apart by the circumferential decomposition, aliases are not).
  The paper's generator lists its orders up to ``n_max`` only; a tyre has them all, and no
  test can know where a generator stopped, so the orders it leaves out (up to n_max + 2N,
  by its own model, :func:`_unlisted_orders`) count in this test too — the same branch's
  orders converge on one frequency (167.8 Hz), so an order n ≤ N/2 near that asymptote
  whose alias above n_max lies within its bandwidth is a crowd like any other (they are
  not expected, found or counted anywhere else);
* a degenerate cos/sin pair (or a pair split by less than ζ f) is one mode.

A free rim's n = 1 modes: both generators call a mode "rim" when the rim holds the largest
share of its kinetic energy — a share a test cannot measure without the masses (the rim
mode and the tyre's n = 1 "same" mode of a free rim both move tread, sidewall and rim in
phase; the two generators label the second one differently). The tool has no "rim"
branch: a truth "rim" mode is found by a table mode of its order n = 1, not aliased, of
either branch (as cavity and tangential modes, which the tool has no label for, are
found by any label).

A mode a test could show is *found*, *mislabelled* or *missed* by ``run``'s modal table
(:func:`score_modes`). An order above N/2 is found by a row flagged aliased in its alias
class (the issue's "flagged as aliased"), whatever order and branch the row reads; how many
of those rows also read the truth's order (as their n or among their candidates) and its
branch is counted apart (``aliased_read`` of ``aliased_found``, since session 20: a row
flagged n = 100 for the truth's n = 32 counts as found, and is not read right). A diagnosis is right when it adopts what the case holds, or nothing
where the base model absorbs the case's physics within the noise (:func:`detectable`).
"""

from __future__ import annotations

import csv

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import maximum_bipartite_matching

from tiremodal_cli.diagnose.loop import base_fit
from tiremodal_cli.diagnose.options import DiagnoseOptions
from tiremodal_cli.diagnose.statistics import residual_analysis
from tiremodal_cli.tyre.measured import MeasuredMode
from tiremodal_cli.tyre.model import TyreParameters
from tiremodal_cli.tyre.robust import with_sigma
from tiremodal_cli.tyre.simulate import SimulationConfig, half_sine_spectrum
from tiremodal_cli.tyre.solve import solve_modes

__all__ = ["TOLERANCE", "EXPECTED_DIAGNOSIS", "DETECT_ALPHA", "expected_groups", "read_modes", "score_modes",
           "diagnosis_right", "detectable"]

#: Frequency tolerance of a match (relative).
TOLERANCE = 0.003

#: What a right diagnosis adopts for each variant: (required, allowed). ``required``: the
#: names (effects of the candidate library, or a parameter found off its nominal value) any
#: one of which must be adopted; ``allowed``: names that may be adopted besides, because the
#: variant holds that physics too. The three tangential variants of the ring are a belt
#: that moves tangentially *and* stretches (finite EA): its n = 0 mode is held by the hoop
#: stiffness (``extensible_belt``) and its n ≥ 1 modes feel the tangential coupling
#: (``tangential``); the variants differ in how much of each shows. The ring's sidewall
#: shear is the tangential sidewall stiffness k_t of the ``tangential`` effect. The ring's
#: cavity air also stiffens the breathing mode (its uniform pressure, ρc²b²/A per length):
#: on n = 0 that is the same stiffness as a belt's EA/R², which frequencies cannot tell apart.
EXPECTED_DIAGNOSIS = {
    "none": ((), ()),
    "tangential": (("tangential",), ("extensible_belt",)),
    "extensible": (("extensible_belt",), ("tangential",)),
    "sidewall_shear": (("tangential",), ("extensible_belt",)),
    "timoshenko": (("timoshenko",), ()),
    "sidewall_coupling": (("sidewall_membrane",), ()),
    "sidewall_membrane": (("sidewall_membrane",), ()),
    "rim": (("m_w", "rim_fixture"), ("m_w", "rim_fixture")),
    "cavity": (("air_cavity",), ("extensible_belt",)),
    "air_cavity": (("air_cavity",), ()),
    "mass": (("added_mass",), ()),
    "added_mass": (("added_mass",), ()),
    "viscoelastic": (("viscoelastic",), ()),
}

#: Level of the test that decides whether an effect is detectable at all (the diagnosis's).
DETECT_ALPHA = 0.01

def _alias(n: int, n_points: int) -> int:
    r = n % n_points
    return min(r, n_points - r)


def _h_noise_floor(cfg: SimulationConfig, sim, freq_hz: float, channel: int) -> float:
    """Std of the H1 estimate's error at ``freq_hz`` on ``channel`` (m/s²/N): white sensor
    noise of std noise × the channel's RMS over the test, on the DFT of the record, over the
    nominal hammer pulse's spectrum, averaged over the hits."""
    if cfg.noise == 0:
        return 0.0
    resp = np.asarray(sim.measurement.response[:, :, channel, :], dtype=float)
    rms = np.sqrt(np.mean(resp**2))
    f_spec = abs(half_sine_spectrum([freq_hz], cfg.pulse_width_s, cfg.amplitude_n)[0]) * cfg.sample_rate
    return float(cfg.noise * rms * np.sqrt(cfg.n_samples) / (f_spec * np.sqrt(cfg.n_hits)))


def expected_groups(sim, cfg: SimulationConfig) -> list[dict]:
    """The truth modes grouped (a degenerate pair is one mode), each with what a test could
    show of it: ``valid`` (in the usable band), ``visible``, ``crowd``, ``aliased``
    (n > N/2), ``foreign`` (a branch outside the tool's labels) and ``expected``
    (valid, visible and not in a crowd)."""
    truth = sim.truth
    n_pts = len(truth["point_angle_rad"])
    fs = cfg.sample_rate
    f_pulse = np.linspace(0, 0.5 * fs, 2049)
    spec = abs(half_sine_spectrum(f_pulse, cfg.pulse_width_s))
    below = np.flatnonzero(spec < 0.1 * spec[0])
    f_force = f_pulse[below[0]] if below.size else 0.5 * fs
    f_valid = min(fs / 2.56, f_force)
    names = [c.name for c in cfg.channels]
    tread = next(c.name for c in cfg.channels if c.location == "tread")
    modes = sorted(truth["modes"], key=lambda m: (m["branch"], m["n"], m["frequency_hz"]))
    groups = []
    for m in modes:
        g = groups[-1] if groups else None
        if (g is not None and g["branch"] == m["branch"] and g["n"] == m["n"]
                and m["frequency_hz"] - g["members"][-1] <= m["damping_ratio"] * m["frequency_hz"]):
            g["members"].append(m["frequency_hz"])
            g["shapes"].append(m["shape_at_points"])
            continue
        groups.append({"n": m["n"], "branch": m["branch"], "zeta": m["damping_ratio"],
                       "members": [m["frequency_hz"]], "shapes": [m["shape_at_points"]]})
    out = []
    for g in groups:
        f = float(np.mean(g["members"]))
        best = 0.0
        for sh in g["shapes"]:
            phi_in = np.asarray(sh[tread])
            for ic, c in enumerate(names):
                peak = np.max(np.abs(sh[c][0] * phi_in)) / (2 * g["zeta"])
                floor = _h_noise_floor(cfg, sim, f, ic)
                best = max(best, peak / floor if floor > 0 else (np.inf if peak > 0 else 0.0))
        out.append({"frequency_hz": f, "members": list(g["members"]), "n": g["n"], "branch": g["branch"],
                    "zeta": g["zeta"],
                    "snr": float(best), "valid": bool(f * (1 + g["zeta"]) <= f_valid), "visible": bool(best >= 3.0),
                    "aliased": bool(g["n"] > n_pts / 2), "alias_class": _alias(g["n"], n_pts),
                    "foreign": g["branch"] not in ("same", "opposite", "rim")})
    others = out + _unlisted_orders(cfg, n_pts)
    for g in out:
        bw = 2 * g["zeta"] * g["frequency_hz"]
        g["crowd"] = any(h is not g and h["branch"] == g["branch"] and _alias(h["n"], n_pts) == _alias(g["n"], n_pts)
                         and abs(h["frequency_hz"] - g["frequency_hz"]) < bw for h in others)
        g["expected"] = g["valid"] and g["visible"] and not g["crowd"]
    return out


def _unlisted_orders(cfg: SimulationConfig, n_pts: int) -> list[dict]:
    """The orders n_max < n ≤ n_max + 2N the paper's generator leaves out of its truth (and
    its FRFs), by its own model: ``frequency_hz``, ``n``, ``branch`` for the crowd test
    only (module docstring). Two alias cycles above n_max hold each alias class's nearest
    unlisted orders of both signs (±n mod N); the ring lists every order below its band's
    top (its mesh resolves them): none."""
    if cfg.model != "paper":
        return []
    modes = solve_modes(cfg.params, n_max=cfg.n_max + 2 * n_pts, effects=cfg.effects)
    keep = (modes.n > cfg.n_max) & (modes.freq_hz < 0.5 * cfg.sample_rate)
    return [{"frequency_hz": float(f), "n": int(n), "branch": b} for f, n, b in zip(modes.freq_hz[keep], modes.n[keep], np.asarray(modes.branch)[keep])]


def read_modes(path) -> list[dict]:
    """The modal table (``modes.csv``) as the rows :func:`score_modes` reads."""
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    out = []
    for r in rows:
        n = r.get("n", "")
        out.append({"frequency_hz": float(r["frequency_hz"]), "damping_ratio": float(r["damping_ratio"]),
                    "n": int(n) if n not in ("", None) else None, "branch": r.get("branch") or None,
                    "aliased": str(r.get("n_aliased", "")).lower() == "true",
                    "n_spatial": int(r["n_spatial"]) if r.get("n_spatial") not in ("", None) else None,
                    "n_candidates": [int(c) for c in (r.get("n_candidates") or "").split()]})
    return out


def score_modes(groups: list[dict], rows: list[dict], truth_modes: list[dict]) -> dict:
    """Found / mislabelled / missed / spurious (module docstring) and the errors of the
    found modes' frequencies and damping ratios (relative)."""
    found = mis = missed = aliased_found = aliased_read = 0
    f_err, z_err, detail, bw_err = [], [], [], []
    for g in (g for g in groups if g["expected"]):
        # within 0.3 % of the pair's mean or of one of its members (a split pair — an added
        # mass's cos/sin members, 0.5–0.6 % apart at ζ = 2 % — is one truth mode; a row at
        # one member is that mode, not a miss)
        at = [g["frequency_hz"], *g.get("members", [])]
        cand = [r for r in rows if any(abs(r["frequency_hz"] / f - 1) <= TOLERANCE for f in at)]
        if g["foreign"]:
            ok = [r for r in cand]
        elif g["branch"] == "rim":  # the rim mode of a free rim: its order, any branch (module docstring)
            ok = [r for r in cand if r["n"] == g["n"] and not r["aliased"]]
        elif g["aliased"]:  # flagged, and seen in the order group its order aliases onto
            ok = [r for r in cand if r["aliased"] and (r.get("n_spatial") is None or "alias_class" not in g
                                                       or r["n_spatial"] == g["alias_class"])]
        else:
            ok = [r for r in cand if r["n"] == g["n"] and r["branch"] == g["branch"] and not r["aliased"]]
        if ok:
            found += 1
            r, f_ref = min(((r, f) for r in ok for f in at), key=lambda rf: abs(rf[0]["frequency_hz"] - rf[1]))
            f_err.append(abs(r["frequency_hz"] / f_ref - 1))
            z_err.append(abs(r["damping_ratio"] / g["zeta"] - 1))
            bw_err.append(abs(r["frequency_hz"] - f_ref) / (2 * g["zeta"] * f_ref))
            status = "found"
            if g["aliased"] and not g["foreign"]:  # its order read: the truth's n is the row's or a candidate
                aliased_found += 1
                aliased_read += any(r["branch"] == g["branch"] and g["n"] in [r["n"], *r.get("n_candidates", [])]
                                    for r in ok)
        elif cand:
            mis += 1
            r = cand[0]
            status = f"mislabelled as n={r['n']} {r['branch']}"
        else:
            missed += 1
            status = "missed"
        detail.append({"frequency_hz": round(g["frequency_hz"], 3), "n": g["n"], "branch": g["branch"],
                       "status": status})
    tf = np.array([m["frequency_hz"] for m in truth_modes]) if truth_modes else np.zeros(0)
    spurious = [r for r in rows if not np.any(np.abs(tf / r["frequency_hz"] - 1) <= TOLERANCE)]
    return {"expected": found + mis + missed, "found": found, "mislabelled": mis, "missed": missed,
            "spurious": len(spurious), "adopted": len(rows), "surplus": _surplus(groups, rows),
            "freq_err_bw": [float(x) for x in bw_err],
            "spurious_hz": [round(r["frequency_hz"], 2) for r in spurious],
            "freq_err_median_pct": 100 * float(np.median(f_err)) if f_err else None,
            "damping_err_median_pct": 100 * float(np.median(z_err)) if z_err else None,
            "n_aliased_groups": sum(1 for g in groups if g["expected"] and g["aliased"]),
            "aliased_found": aliased_found, "aliased_read": aliased_read,
            "n_crowd_groups": sum(1 for g in groups if g["valid"] and g["crowd"]),
            "detail": detail}


def _surplus(groups: list[dict], rows: list[dict]) -> int:
    """Table modes beyond one per truth mode: rows within 0.3 % of some truth mode (so not
    spurious) that a one-to-one matching of rows to truth groups (a degenerate pair is one)
    leaves over — one mode reported twice (a pole seen in two order groups and not merged)."""
    if not rows or not groups:
        return 0
    fr = np.array([r["frequency_hz"] for r in rows])
    fg = np.array([g["frequency_hz"] for g in groups])
    near = np.abs(fr[:, None] / fg[None, :] - 1) <= TOLERANCE
    matched = maximum_bipartite_matching(csr_matrix(near.astype(np.int8)), perm_type="column")
    return int(np.sum(near.any(axis=1) & (matched < 0)))


def diagnosis_right(physics: str, adopted: list[str], detectable: bool | dict = True) -> bool:
    """Right when every part of ``physics`` has one of its required names adopted and
    nothing else is adopted but their allowed names; an effect the base model absorbs within
    the noise (:func:`detectable`) needs nothing: it is not required, and its names stay
    allowed. ``detectable``: one verdict for the whole case, or one per part
    ({part: bool}, a part missing from it counted detectable)."""
    parts = [p for p in physics.split("+") if p != "none"]
    if not parts:
        return not adopted
    det = {p: (detectable.get(p, True) if isinstance(detectable, dict) else bool(detectable)) for p in parts}
    spec = {p: EXPECTED_DIAGNOSIS.get(p, ((p,), ())) for p in parts}
    ok = set().union(*(set(r) | set(a) for r, a in spec.values()))
    if any(a not in ok for a in adopted):
        return False
    return all(any(a in spec[p][0] for a in adopted) for p in parts if det[p])


def detectable(case, groups, params: TyreParameters) -> dict:
    """Can the paper's model tell this case's physics from noise, given the modes a test shows?

    The base model (k_r1, k_r2, EI free, rim as in ``run``) is fitted robustly to the
    case's expected same/opposite truth modes as a test can show them, each with the
    diagnosis's 0.1 % frequency uncertainty: the physics is *detectable* when that fit's
    residual exceeds the noise (χ² p < 0.01 or a mode set aside). An effect the base model
    absorbs within the noise is not missing physics for it, and a right diagnosis adopts
    nothing. A pair split by less than ζ f is one mode (:func:`expected_groups`: its two
    peaks merge into one under the damping), at the mean of its members — on the grid of
    points the cos and sin members carry the same modal energy, so one pole fitted to the
    pair's summed response sits between them, at their mean; a pair split by more (two
    groups of one n and branch) enters as its lower and upper member, as ``diagnose``
    takes a resolved split pair. Returns {"detectable", "rms_pct", "p_value", "set_aside"}."""
    if case.physics == "none":
        return {"detectable": False, "rms_pct": 0.0, "p_value": 1.0, "set_aside": 0}
    kept = [g for g in groups if g["expected"] and g["branch"] in ("same", "opposite") and not g["aliased"]]
    by_order = {}
    for g in kept:
        by_order.setdefault((g["n"], g["branch"]), []).append(float(np.mean(g["members"])))
    modes = []
    for (n, branch), fs in by_order.items():
        fs = sorted(fs)
        if len(fs) >= 2:  # a resolved split pair: its outer members
            modes += [MeasuredMode(n, branch, fs[0], member="lower"), MeasuredMode(n, branch, fs[-1], member="upper")]
        else:
            modes.append(MeasuredMode(n, branch, fs[0]))
    opt = DiagnoseOptions(alpha=DETECT_ALPHA)
    rf = base_fit(with_sigma(modes, opt.noise_floor_pct), params, opt)
    res = residual_analysis(rf, opt)
    return {"detectable": bool(res["exceeds_noise"]), "rms_pct": rf.fit.rms_error_pct, "p_value": res["p_value"],
            "set_aside": len(rf.set_aside)}
