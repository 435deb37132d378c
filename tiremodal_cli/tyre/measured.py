"""Measured modes for a fit, read from modal-table rows (docs/identify.md's matching rules).
"""

from __future__ import annotations

import dataclasses

from dataclasses import dataclass

import numpy as np

from tiremodal_cli.conventions import BRANCHES

__all__ = ['MIN_MPC', 'MeasuredMode', 'modes_from_rows']


@dataclass(frozen=True)
class MeasuredMode:
    """One measured mode matched to the model: order, branch, frequency (Hz)."""

    n: int
    branch: str
    frequency_hz: float
    damping_ratio: float | None = None
    uncertainty_hz: float | None = None
    source: str = ""
    member: str | None = None  # "lower"/"upper" member of a split pair kept apart (diagnose)
    aliased: bool = False  # n above the spatial Nyquist order: read from the dispersion, not the points

    def to_dict(self) -> dict:
        """The mode as JSON-ready data (its fields)."""
        return dataclasses.asdict(self)


#: MPC under which a row is no normal mode (left out of a fit, and of the evidence of extra modes)
MIN_MPC = 0.5


def modes_from_rows(rows, *, min_confidence: float = 0.5, min_mpc: float = MIN_MPC,
                    source: str = "", split_pairs: str = "mean", free_rim: bool = False
                    ) -> tuple[list[MeasuredMode], list[dict]]:
    """Measured modes usable for a fit, from table rows (``lsce`` JSON/CSV or a Table A1 CSV).

    Matching rules (docs/identify.md): a row needs ``frequency_hz`` > 0, an integer ``n`` ≥ 0
    and ``branch`` in {same, opposite}; rows with ``n_confidence`` below ``min_confidence``
    are left out, and so are rows with ``mpc`` below ``min_mpc`` (not a normal mode) and rows
    flagged out of their branch's dispersion order (``in_order`` false, from lsce; not n = 0,
    the breathing mode, which a hoop stiffness the beam lacks may put far above the low
    orders: the fit's outlier screen judges it — and, with ``free_rim``, not n = 1 "same",
    which a free rim's own mode reads as, off the tread's dispersion); the two
    members of a split pair (one n and branch twice, within 5 %) enter as their mean
    frequency (``split_pairs="mean"``) or as two modes marked ``member`` "lower" and
    "upper" (``split_pairs="members"``, for ``diagnose``); of one n and branch twice
    farther apart, the more significant row stays — and for n = 1 "same" also the most
    significant of those below it (a free rim's mode reads as n = 1 "same").
    Returns the modes and the rows left out with their reasons (each with its ``row``
    number, ``frequency_hz``, and ``n``/``branch`` where the row has them).
    """
    kept, skipped = _parse_rows(rows, min_confidence, min_mpc, free_rim)
    modes = []
    for (n, b), vals in sorted(kept.items(), key=lambda kv: np.mean([v[0] for v in kv[1]])):
        if len(vals) > 1:
            # members of a split pair lie close together; a far "duplicate" is a misread
            # order (an alias, a spurious pole): keep the strongest, skip the rest
            vals.sort(key=lambda v: -v[3])
            far = [v for v in vals[1:] if abs(v[0] / vals[0][0] - 1) > 0.05]
            rim = _rim_candidate(n, b, vals[0], far)
            if rim is not None:  # a second n = 1 "same" below the first: the rim mode's place
                far.remove(rim)
                modes.extend(_modes_of(n, b, [rim], split_pairs, f"{source} (n = 1 same below another: a rim mode?)"))
            for v in far:
                skipped.append({"row": v[4], "frequency_hz": v[0], "n": n, "branch": b,
                                "reason": f"n={n} {b} already at {vals[0][0]:.2f} Hz (not a split pair: > 5 % apart)"})
            vals = [v for v in vals if v not in far]
        modes.extend(_modes_of(n, b, vals, split_pairs, source))
    return modes, skipped


def _rim_candidate(n, b, first, far):
    """Of the rows of n = 1 "same" far (> 5 %) from the strongest one, the strongest below it:
    a free rim's mode reads as n = 1 "same" and lies below the same-direction n = 1 mode, so
    n = 1 "same" may hold two modes (the fit matches each to the model's nearer one,
    :func:`tiremodal_cli.tyre.frequencies.nearer_rim_mode`). None for any other (n, branch)."""
    if (n, b) != (1, "same"):
        return None
    below = [v for v in far if v[0] < first[0]]
    return max(below, key=lambda v: v[3]) if below else None


def _parse_rows(rows, min_confidence, min_mpc, free_rim=False):
    """The usable rows by (n, branch), each as (f, ζ, σ_f, significance, row number,
    aliased), and the rows left out with their reasons."""
    kept, skipped = {}, []
    for i, r in enumerate(rows):
        def get(k, r=r):
            v = r.get(k)
            return None if v is None or (isinstance(v, str) and v.strip() == "") else v
        try:
            f = float(get("frequency_hz"))
        except (TypeError, ValueError):
            skipped.append({"row": i + 1, "reason": "no frequency_hz"})
            continue
        n, b = get("n"), get("branch")
        if n is None or b is None:
            skipped.append({"row": i + 1, "frequency_hz": f, "reason": "no n or branch"})
            continue
        try:
            n = int(float(n))
        except ValueError:
            skipped.append({"row": i + 1, "frequency_hz": f, "reason": f"n={n!r} is not an integer"})
            continue
        b = str(b).strip().lower()
        problem = _row_problem(get, n, b, f, min_confidence, min_mpc, free_rim)
        if problem:
            skipped.append({"row": i + 1, "frequency_hz": f, "n": n, "branch": b, "reason": problem})
            continue
        z = get("damping_ratio")
        u = get("frequency_uncertainty_hz")
        sig = get("significance")
        al = str(get("n_aliased") or "").strip().lower() in ("true", "1")
        kept.setdefault((n, b), []).append((f, None if z is None else float(z), None if u is None else float(u),
                                            1.0 if sig is None else float(sig), i + 1, al))
    return kept, skipped


def _modes_of(n, b, vals, split_pairs, source) -> list[MeasuredMode]:
    """The measured mode(s) of one (n, branch): a split pair as two members or its mean."""
    if split_pairs == "members" and len(vals) == 2:
        return [MeasuredMode(n, b, v[0], v[1], v[2], source=f"{source} ({member} member of a split pair)",
                             member=member, aliased=v[5])
                for v, member in zip(sorted(vals, key=lambda v: v[0]), ("lower", "upper"))]
    f = float(np.mean([v[0] for v in vals]))
    zs = [v[1] for v in vals if v[1] is not None]
    us = [v[2] for v in vals if v[2] is not None]
    return [MeasuredMode(n, b, f, float(np.mean(zs)) if zs else None, float(np.mean(us)) if us else None,
                         source=source if len(vals) == 1 else f"{source} (mean of a split pair)",
                         aliased=any(v[5] for v in vals))]


#: a row explaining less of the physical response than lsce's own cut-off
#: (``ModalOptions.min_significance``) was kept by lsce for its share in its order group
#: alone: a mode, but its order is not trusted for a fit
WEAK_SIGNIFICANCE = 0.05


def _row_problem(get, n, b, f, min_confidence, min_mpc, free_rim=False) -> str | None:
    """Why a table row cannot enter the fit (None when it can)."""
    conf, order_ok, mpc = get("n_confidence"), get("in_order"), get("mpc")
    if b not in BRANCHES or n < 0 or not f > 0:
        return f"branch {b!r} / n {n} not fitted"
    crowd = get("crowd")
    if crowd is not None and str(crowd).strip().lower() in ("true", "1"):  # lsce: the order cannot be told
        return f"in a crowd: its order is one of {get('n_candidates') or 'several'}"
    sig = get("significance")
    if sig is not None and float(sig) < WEAK_SIGNIFICANCE:
        # lsce keeps a mode significant in its own order group only; its order is read from
        # a shape that explains little of the measured response
        return f"significance {float(sig):.3f} < {WEAK_SIGNIFICANCE}: its order is read from a weak shape"
    if conf is not None and float(conf) < min_confidence:
        return f"n_confidence {float(conf):.2f} < {min_confidence}"
    rim_mode = n == 1 and b == "same" and free_rim
    if order_ok is not None and str(order_ok).strip().lower() in ("false", "0") and n != 0 and not rim_mode:
        # n = 0 is not on its branch's dispersion: the breathing mode is held by the belt's
        # hoop stiffness (and the cavity air's uniform pressure), absent from the beam, and
        # may lie far above the low orders; the fit's outlier screen judges it, and a
        # candidate (the extensible belt) may bring it back. Nor is a free rim's own mode,
        # which reads as n = 1 "same" (tread and sidewall in phase)
        return f"n={n} {b} out of its branch's dispersion order"
    if mpc is not None and float(mpc) < min_mpc:
        return f"mpc {float(mpc):.2f} < {min_mpc}: not a normal mode"
    return None
