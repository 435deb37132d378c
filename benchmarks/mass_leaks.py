"""What the added mass leaks into each order group, from the generator's own model.

A point mass m_a at θ_a adds ``m_a ψ ψᵀ`` to the generalised mass matrix (ψ the tread's
cos nθ_a / sin nθ_a, ``tyre/effects/added_mass.py``). Split it into its diagonal (each
order's own member lowered: the split pairs, no coupling) and the rest (the coupling
between orders: the leaks). For a ``paper`` case of the validation matrix this script

1. computes, noiseless, each order group's response (spatial DFT over the case's points,
   tread and sidewall channels) with the full mass, with its diagonal only and without
   it, and reports per group ``‖H_full − H_diag‖ / ‖H_full‖`` (the leaks' share) and
   ``‖H_diag − H_none‖ / ‖H_full‖`` (the self-terms' share) over a band;
2. lists the first-order perturbation coefficients of the strongest modes,
   ``c_rs = ω_r² m_a φ_r(θ_a) φ_s(θ_a) / (ω_s² − ω_r²)`` (unit modal masses), which
   must be small (≪ 1) for a first-order leak prediction to hold;
3. with ``--oracle R ...``, simulates the case again with every coupled mode's shape
   outside its dominant order times r (0: a perfect leak subtraction, the modes' coupled
   frequencies kept; 1: the case itself), runs it and scores it as the matrix does
   (``--jobs 1`` conditions: one BLAS thread): how exact must a leak prediction be for the
   blends to go?
4. with ``--subtract M_A THETA_DEG``, simulates the case and subtracts from its FRFs the
   leaks the generator's model predicts with that mass (the difference between its
   coupled modes' FRFs and theirs on their own orders), before noise: approach (a) with
   everything but the mass exact.
5. with ``--fit-shapes RUN``, estimates (m_a, θ_a) from a kept run's measured order-group
   FRFs in the band (the diagnosed model with the mass, the paper's damping law: the most
   favourable case for the estimate).

Usage::

    python benchmarks/mass_leaks.py paper:physics=added_mass --band 140 200
    python benchmarks/mass_leaks.py paper:physics=added_mass --oracle 0 0.25 1 --keep /tmp/ml
    python benchmarks/mass_leaks.py paper:physics=added_mass --subtract 0.4 0 --subtract 0.5 2
    python benchmarks/mass_leaks.py paper:physics=added_mass --band 178 198 \\
        --fit-shapes /tmp/m2/paper_physics-added_mass/run
"""

from __future__ import annotations

import argparse
import json
import sys
from contextlib import contextmanager
from pathlib import Path

import h5py
import numpy as np
from scipy.optimize import minimize
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tiremodal_cli.tyre.effects import get_effect  # noqa: E402
from tiremodal_cli.tyre.model import TyreParameters, paper_damping  # noqa: E402
from tiremodal_cli.tyre.solve import frf, observation, solve_modes  # noqa: E402
from tiremodal_cli.tyre import simulate as SIM  # noqa: E402
from tiremodal_cli.workflow import validation as V  # noqa: E402

EFFECT = get_effect("added_mass")
_COUPLE = EFFECT.couple


def _scaled(s: float):
    """The added mass's ``couple`` hook with its off-diagonal (inter-order) part times s."""
    def couple(M, K, dofs, v, p):
        M0 = np.asarray(M, dtype=float)
        M1, K1 = _COUPLE(M0, K, dofs, v, p)
        d = M1 - M0
        dd = np.diag(np.diag(d))
        return M0 + dd + s * (d - dd), K1
    return couple


@contextmanager
def coupling_scale(s: float):
    """Within the block, the added mass couples the orders with s times its real weight."""
    object.__setattr__(EFFECT, "couple", _scaled(s))
    try:
        yield
    finally:
        object.__setattr__(EFFECT, "couple", _COUPLE)


def group_response(cfg, effects, freq_hz, s: float = 1.0) -> np.ndarray:
    """Noiseless order-group FRFs of a paper-model case.

    Returns
    -------
    G : (n_channel, N // 2 + 1, n_freq) complex ndarray
        accelerance, m/(s²·N), spatial DFT over the N points (the hammer's), divided by N.
    """
    with coupling_scale(s):
        m = solve_modes(cfg.params, n_max=cfg.n_max, effects=effects)
    z = np.array([paper_damping(int(n), b) for n, b in zip(m.n, m.branch)])
    ang = 2 * np.pi * np.arange(cfg.n_points) / cfg.n_points
    locs = [c.location for c in cfg.channels]
    c_ang = np.array([c.angle_rad for c in cfg.channels])
    H = frf(m, freq_hz, z, locs, c_ang, ang)
    return (np.fft.fft(H, axis=1) / cfg.n_points)[:, : cfg.n_points // 2 + 1]


def leak_shares(case, band=(140.0, 200.0), step_hz: float = 0.5) -> list[dict]:
    """Per order group and channel: the leaks' and the self-terms' share of the response."""
    cfg = V.config_for(case)
    f = np.arange(band[0], band[1] + step_hz / 2, step_hz)
    eff = dict(cfg.effects)
    none = {k: v for k, v in eff.items() if k != "added_mass"}
    Gf, Gd, G0 = group_response(cfg, eff, f), group_response(cfg, eff, f, 0.0), group_response(cfg, none, f)
    out = []
    for g in range(Gf.shape[1]):
        for ch, c in enumerate(cfg.channels):
            a = np.linalg.norm(Gf[ch, g])
            if a == 0:
                continue
            out.append({"group": g, "channel": c.name, "leak": float(np.linalg.norm(Gf[ch, g] - Gd[ch, g]) / a),
                        "self": float(np.linalg.norm(Gd[ch, g] - G0[ch, g]) / a)})
    return out


def first_order(case, band=(140.0, 200.0), top: int = 3) -> list[dict]:
    """First-order coupling coefficients of the mass between the uncoupled model's modes in ``band``."""
    cfg = V.config_for(case)
    eff = dict(cfg.effects)
    v = EFFECT.resolve(eff["added_mass"])
    m = solve_modes(cfg.params, n_max=cfg.n_max, effects={k: x for k, x in eff.items() if k != "added_mass"})
    phi = observation(m.dofs, "tread", v["theta_a"]) @ m.shapes.T  # (n_modes,), m/√kg
    w2 = (2 * np.pi * m.freq_hz) ** 2
    out = []
    for r in np.flatnonzero((m.freq_hz >= band[0]) & (m.freq_hz <= band[1]) & (np.abs(phi) > 0)):
        with np.errstate(divide="ignore", invalid="ignore"):
            c = w2[r] * v["m_a"] * phi[r] * phi / (w2 - w2[r])
        c[(np.abs(phi) == 0) | (np.arange(len(c)) == r)] = 0.0
        big = np.argsort(-np.abs(c))[:top]
        out.append({"frequency_hz": float(m.freq_hz[r]), "n": int(m.n[r]), "branch": m.branch[r],
                    "coupled": [(int(m.n[s]), m.branch[s], round(float(m.freq_hz[s]), 2), round(float(c[s]), 3))
                                for s in big]})
    return out


def leak_free(model, r: float):
    """The coupled modes with the part of each shape outside its dominant order times r.

    r = 0: every mode on its own order only (a perfect leak subtraction), at its coupled
    frequency; r = 1: the model as it is.
    """
    dof_n = np.array([d[1] for d in model.dofs])
    own = dof_n[None, :] == np.asarray(model.n)[:, None]  # (n_modes, n_dof)
    shapes = np.where(own, model.shapes, r * model.shapes)
    return type(model)(model.freq_hz, model.n, model.harmonic, model.branch, shapes, model.dofs)


def oracle(case, r: float, keep: Path) -> dict:
    """Simulate ``case`` with every mode's leaks into other orders times r, run and score it."""
    real = SIM.solve_modes

    def solve(*a, **kw):
        return leak_free(real(*a, **kw), r)

    SIM.solve_modes = solve
    try:
        with threadpool_limits(1):
            rec = V.run_case(case, keep / f"r{r:g}_{case.name.replace(':', '_').replace('=', '-')}")
    finally:
        SIM.solve_modes = real
    keys = ("name", "expected", "found", "mislabelled", "missed", "spurious", "adopted", "spurious_hz",
            "adopted_effects", "diagnosis_right")
    return {"r": r} | {k: rec.get(k) for k in keys}


def subtracted(case, m_a: float, theta_a: float, keep: Path) -> dict:
    """Simulate ``case``, subtract from its FRFs the leaks predicted with a point mass
    (m_a kg, θ_a rad) in the generator's own model and damping (approach (a) at its most
    favourable: only the mass can be wrong), run and score it."""
    real = SIM._paper_source

    def source(cfg, freq, angles):
        modes, zeta, H, listed = real(cfg, freq, angles)
        eff = dict(cfg.effects) | {"added_mass": {"m_a": m_a, "theta_a": theta_a}}
        pred = SIM.solve_modes(cfg.params, n_max=cfg.n_max, effects=eff)
        z = np.array([paper_damping(int(n), b) for n, b in zip(pred.n, pred.branch)])
        locs = [c.location for c in cfg.channels]
        c_ang = np.array([c.angle_rad for c in cfg.channels])
        leak = frf(pred, freq, z, locs, c_ang, angles) - frf(leak_free(pred, 0.0), freq, z, locs, c_ang, angles)
        return modes, zeta, H - leak, listed

    SIM._paper_source = source
    tag = f"m{m_a:g}_t{np.degrees(theta_a):g}_{case.name.replace(':', '_').replace('=', '-')}"
    try:
        with threadpool_limits(1):
            rec = V.run_case(case, keep / tag)
    finally:
        SIM._paper_source = real
    keys = ("name", "expected", "found", "mislabelled", "missed", "spurious", "adopted", "spurious_hz",
            "adopted_effects", "diagnosis_right")
    return {"m_a": m_a, "theta_a_deg": float(np.degrees(theta_a))} | {k: rec.get(k) for k in keys}


def _measured_groups(run: Path, band):
    """The run's measured order-group FRFs (tread, sidewall) in ``band``: (G (2, N//2+1, n_f), f, angles, τ)."""
    with h5py.File(run / "frf.h5", "r") as f:
        fr = f["freq_hz"][:]
        sel = (fr >= band[0]) & (fr <= band[1])
        ang, tau = f["point_angle"][:], float(f.attrs["exp_tau_s"])
        H = f["frf"][:2][:, :, sel]
    n = len(ang)
    return (np.fft.fft(H, axis=1) / n)[:, : n // 2 + 1], fr[sel], ang, tau


def fit_mass_from_shapes(run: Path, band=(178.0, 198.0), *, step_kg: float = 0.1, step_deg: float = 10.0) -> dict:
    """(m_a, θ_a) that make the diagnosed model's order-group FRFs, with the mass, match the
    measured ones in ``band`` (one free complex scale per channel; the paper's damping law
    plus the exponential window's 1/(ωτ)): a grid, then Nelder–Mead. The mass read from
    the shapes, not from the frequencies."""
    Gm, fr, ang, tau = _measured_groups(run, band)
    diag = json.loads((run / "diagnosis.json").read_text(encoding="utf-8"))
    p = TyreParameters.from_mapping({k: v for k, v in diag["augmented"]["all_parameters"].items() if v is not None})
    eff = dict(diag["augmented"]["effects"])
    n = len(ang)

    def cost(x):
        m = solve_modes(p, n_max=60, effects=eff | {"added_mass": {"m_a": x[0], "theta_a": x[1]}})
        z = np.array([paper_damping(int(k), b) for k, b in zip(m.n, m.branch)])
        z = z + 1.0 / (2 * np.pi * np.maximum(m.freq_hz, 1.0) * tau)
        g = (np.fft.fft(frf(m, fr, z, ["tread", "sidewall"], np.zeros(2), ang), axis=1) / n)[:, : n // 2 + 1]
        c = 0.0
        for ch in range(2):
            a = np.vdot(g[ch], Gm[ch]) / np.vdot(g[ch], g[ch])
            c += np.linalg.norm(Gm[ch] - a * g[ch]) ** 2 / np.linalg.norm(Gm[ch]) ** 2
        return c / 2

    grid = [(cost((m_a, th)), m_a, th) for m_a in np.arange(0.0, 1.5 + 1e-9, step_kg)
            for th in np.radians(np.arange(-180.0, 180.0, step_deg))]
    c0, m0, t0 = min(grid)
    res = minimize(cost, [m0, t0], method="Nelder-Mead", bounds=[(0.0, 20.0), (None, None)],
                   options={"xatol": 1e-4, "fatol": 1e-9})
    return {"run": str(run), "m_a_kg": float(res.x[0]), "theta_a_deg": float(np.degrees(res.x[1])),
            "cost": float(res.fun), "cost_without_mass": float(cost((0.0, 0.0)))}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("case", help="a paper case of the matrix with an added mass, e.g. paper:physics=added_mass")
    ap.add_argument("--band", nargs=2, type=float, default=(140.0, 200.0), metavar=("LO", "HI"))
    ap.add_argument("--oracle", nargs="*", type=float, default=[], metavar="S")
    ap.add_argument("--subtract", nargs=2, type=float, action="append", default=[], metavar=("M_A", "THETA_DEG"),
                    help="subtract the leaks predicted with this mass (kg) at this angle (deg); repeatable")
    ap.add_argument("--fit-shapes", type=Path, metavar="RUN",
                    help="a kept run folder of the case: estimate (m_a, θ_a) from its order-group FRFs")
    ap.add_argument("--keep", type=Path, default=Path("/tmp/mass_leaks"))
    args = ap.parse_args(argv)
    case = next(c for c in V.matrix() if c.name == args.case)
    if case.generator != "paper" or "added_mass" not in case.physics:
        ap.error("a paper case with physics added_mass")
    for row in leak_shares(case, tuple(args.band)):
        print(json.dumps(row))
    for row in first_order(case, tuple(args.band)):
        print(json.dumps(row))
    for r in args.oracle:
        print(json.dumps(oracle(case, r, args.keep)), flush=True)
    if args.fit_shapes:
        print(json.dumps(fit_mass_from_shapes(args.fit_shapes, tuple(args.band))), flush=True)
    for m_a, deg in args.subtract:
        print(json.dumps(subtracted(case, m_a, np.radians(deg), args.keep)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
