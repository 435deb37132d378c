"""Misread orders: a weak pole whose order reading its branch contradicts is a leak or a
blend of its order group, not a mode (docs/lsce.md, "Misread orders").

A tyre's modes lie on branches whose frequency rises with the circumferential order n; the
classification flags a mode whose order falls below its branch's as the frequency rises
(``in_order`` false: of two modes out of order, the less significant). Read at its own
spatial order (not an alias of a grid too coarse for it), such a mode claims an order its
branch already places elsewhere. It is then either a mode of another family at that order
(a tangential or breathing mode, a rim's or a cavity's) — a physical mode, which holds its
frequency's response in the physical FRFs — or an artefact of the order decomposition: where
the symmetry is broken (an added mass) or a grid aliases a crowd of orders onto the group,
the group's rows hold other orders' modes, and one pole of the group stands for several of
them, biased between them (a blend), or for a stronger mode's share seen through the
group (a leak). The order group's own evidence (its share of the group's response, the
group's peak) cannot tell the two apart: both are real in the group's rows. The physical
response can: a blend or a leak explains little of it.

**The rule**: a mode out of its branch's dispersion order, at its spatial order, explaining
less than :data:`MISREAD_MAX_SIGNIFICANCE` of the physical response in its half-power band,
and no narrower than every mode whose half-power band overlaps its own, is dropped as a
misread; the rest are classified again (one at a time, the weakest first, until none is
left). A blend of modes decays no slower than the slowest of them, so a pole narrower than
all its neighbours is no blend of them: the paper's air-cavity mode (ζ = 0.5 %, 7.6 % of
the response on the flank of the n = 6 at ζ = 2.9 %, read n = 1 out of order) is kept.
Identify never used such rows (``in_order`` false); the table no longer reports them as
modes (they are in ``rejected``, with their reason).

The level is measured, not derived (session 14, on the kept run of the validation matrix
at 7e88d43, 55 cases): of the 106 modes out of order at their spatial order, the 42 that
match a truth mode's frequency, order and branch (the opposite n = 0 and 1 of the
tangential, extensible, cavity, rim and shear variants, lifted above the branch's low
orders; the 40-point ring's same n = 10, 11) explain 0.29–0.87 of the physical response;
13 of the 14 within 0.3 % of no truth mode (the added mass's blends, 170–183 Hz, one in
the ring's sidewall coupling + mass, one in a 48-point combination) 0.010–0.093 (the 14th,
0.45, is a biased n = 2 in order's place, not a misread); the 8 mislabelled 0.005–0.055;
the 42 others within 0.3 % of a truth mode of another order (mostly the crowd under the
sidewall resonance seen in a low group) 0.037–0.49, 38 of them below 0.15. 0.15 lies in
the gap, 1.6 × above the largest blend and 1.9 × below the weakest true mode. A true
off-branch mode under 15 % of the response in its half-power band would be lost: the
matrix holds one (the ring's sidewall-shear n = 1 same at 98.32 Hz, 10 %, beside the
branch's n = 4 0.015 Hz away), read as an alias until session 38. Since then a mode of
another family (``Classification.other_family``: the branch above it contradicts every
alias of its spatial order) is spared on a test whose FRFs show a structure symmetric
about its sensors, where an order group's rows hold no other order's leak and the alias
class no crowd there.

**Crowd blends** (session 30; :func:`crowd_blends`). The merge keeps a weaker pole of another
order group apart from a stronger one when it moves the channels otherwise
(:func:`~tiremodal_cli.modal.merge._other_channel_shape`: one mode's FRFs are rank one over
channel and point, so every copy of it moves the channels as it does). That argument needs
each pole to be one mode. Where orders of a pole's alias class crowd within its half-power
bandwidth (the classification's crowd: the paper's same-direction orders under the sidewall
resonance, mixed by an added mass), one pole of a group stands for several modes, biased
between them, and its channel shape is their blend's: a shape of its own, no evidence of a
mode. A pole kept apart by its channel shape alone (the other rules would have merged it:
:attr:`~tiremodal_cli.modal.merge.MergedMode.by_channels`) and found in a crowd is dropped
once the misreads are (:func:`_without_blends`), and the other modes keep the readings the
blend was part of: its pole lies among the orders it stands for, and the crowd test reads
the branch's dispersion through it (classified again without the blends, the paper's added
mass at seeds + 2000 read its clear n = 9 at 153.07 Hz as a crowd of n = 9 and 25: the
dispersion interpolated across the gap the blends left). Measured: docs/lsce.md, "Crowd
blends (session 30)".
"""

from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["MISREAD_MAX_SIGNIFICANCE", "misread", "crowd_blends", "false_splits", "without_misreads", "without_modes", "dropped_and_classified"]

#: a mode out of its branch's order at its spatial order must explain at least this share
#: of the physical response in its half-power band (measured on the matrix: see above)
MISREAD_MAX_SIGNIFICANCE = 0.15


def misread(classes, freq_hz, damping_ratio, significance, symmetric: bool = False) -> np.ndarray:
    """(n_modes,) bool: the modes out of their branch's dispersion order, read at their
    spatial order (not aliased), explaining less than :data:`MISREAD_MAX_SIGNIFICANCE` of
    the physical response (``significance``, (n_modes,)), and no narrower than every other
    mode whose half-power band overlaps theirs (``freq_hz``, Hz, ``damping_ratio``: a
    blend decays no slower than the slowest of the modes it stands for; a lightly damped
    mode on a broad one's flank — the paper's air cavity, ζ = 0.5 % beside the n = 6 at
    2.9 % — is a mode of its own). On a test whose FRFs show a structure symmetric about
    its sensors (``symmetric``: its orders unmixed, so an order group's rows hold no other
    order's leak) a mode of another family (``other_family``: the branch above it
    contradicts every alias of its spatial order, so it is no blend of aliased orders
    either) is a mode whatever its share: the ring's sidewall-shear n = 1 same at
    98.32 Hz, 0.004 half-power bandwidths from the branch's n = 4 and 10 % of the physical
    response there (docs/lsce.md, "Session 38")."""
    f, z, sig = (np.asarray(a, dtype=float) for a in (freq_hz, damping_ratio, significance))
    hw = z * f
    out = np.zeros(f.size, dtype=bool)
    for i, c in enumerate(classes):
        if c is None or c.in_order or c.aliased or c.branch is None or not sig[i] < MISREAD_MAX_SIGNIFICANCE:
            continue
        if symmetric and c.other_family:
            continue
        near = (np.abs(f - f[i]) <= hw + hw[i]) & (np.arange(f.size) != i)
        out[i] = bool(np.any(near)) and z[i] >= z[near].min()
    return out


def without_misreads(res, classify_modes, symmetric: bool = False):
    """The ModalResult ``res`` without its misread modes, and the remaining modes'
    classifications.

    Parameters
    ----------
    res : :class:`~tiremodal_cli.modal.modes.ModalResult`
    classify_modes : callable   ModalResult → list of Classification (one per mode)
    symmetric : bool   the test's FRFs show a structure symmetric about its sensors, its
        orders unmixed: a split pair's weaker, broader member is then dropped too
        (:func:`false_splits`)

    Returns
    -------
    (ModalResult, list of Classification): the misreads dropped one at a time (the least
    significant first; the others classified again after each drop), then the crowd's
    blends (:func:`_without_blends`), each added to ``res.rejected`` with its reason.
    """
    classes = classify_modes(res)
    while True:
        bad = np.flatnonzero(misread(classes, res.freq_hz, res.damping_ratio, res.significance, symmetric))
        if bad.size == 0:  # (a mode is out of order only beside a more significant one in order)
            res, classes = _without_blends(res, classes)
            return _without_false_splits(res, classes, classify_modes) if symmetric else (res, classes)
        i = int(bad[np.argmin(res.significance[bad])])
        c = classes[i]
        why = {"frequency_hz": float(res.freq_hz[i]), "damping_ratio": float(res.damping_ratio[i]),
               "group": int(res.group[i]),
               "reason": f"a misread order: read n = {c.n} {c.branch} at its spatial order, out of its branch's "
                         f"dispersion order, and explaining {100 * res.significance[i]:.1f} % of the physical "
                         f"response in its half-power band (< {100 * MISREAD_MAX_SIGNIFICANCE:.0f} %): a leak or "
                         f"a blend of its order group's rows, not a mode"}
        res = without_modes(res, np.delete(np.arange(res.freq_hz.size), i), why)
        classes = classify_modes(res)


def false_splits(classes, significance, damping_ratio) -> np.ndarray:
    """(n_modes,) bool: of each split pair (two modes of one order and branch, in order,
    within 5 %), the member explaining less of the physical response (``significance``)
    when it is also the broader (``damping_ratio``).

    For a test whose FRFs show a structure symmetric about its sensors (session 34): an
    axisymmetric tyre's cos and sin modes of one order share one frequency, so two poles
    of one order a few per cent apart are no pair split by a broken symmetry. The weaker
    stands for what its group's fit leaves beside the mode — the other orders of its alias
    class crowding above it (the held-out 20-point paper tests: n = 8 at 147.1 Hz and a row
    at 150.1 Hz, ζ 6.2 % against 3.8 %, 3 % of the response, in the group that holds
    n = 12 at 161.1 Hz and the crowd at 167 Hz) — and a blend decays no slower than the
    slowest of the modes it stands for (the misread rule's argument). Measured: docs/lsce.md,
    "Session 34"."""
    out = np.zeros(len(classes), dtype=bool)
    members = {}
    for i, c in enumerate(classes):
        if c is not None and c.pair is not None:
            members.setdefault(c.pair, []).append(i)
    for pair in members.values():
        if len(pair) == 2:
            weak, strong = sorted(pair, key=lambda k: significance[k])
            out[weak] = damping_ratio[weak] > damping_ratio[strong]
    return out


def _without_false_splits(res, classes, classify_modes):
    """``res`` without :func:`false_splits`' members, the others classified again."""
    bad = np.flatnonzero(false_splits(classes, res.significance, res.damping_ratio))
    return dropped_and_classified(res, classes, bad, lambda c: (
        f"no split-pair member: read n = {c.n} {c.branch} beside a stronger, narrower mode of that "
        f"order {c.splitting_hz:.2f} Hz away, on a test whose FRFs show a structure symmetric about "
        "its sensors (its cos and sin modes share one frequency): a blend of what its order "
        "group's fit leaves beside the mode"), classify_modes)


def dropped_and_classified(res, classes, bad, reason, classify_modes):
    """``res`` without the modes ``bad`` (indices into it), each added to ``res.rejected`` with
    ``reason(classification)``, and the others classified again (``classify_modes``); ``res``
    and ``classes`` as they are when ``bad`` is empty."""
    if len(bad) == 0:
        return res, classes
    for i in sorted(bad, reverse=True):
        why = {"frequency_hz": float(res.freq_hz[i]), "damping_ratio": float(res.damping_ratio[i]),
               "group": int(res.group[i]), "reason": reason(classes[i])}
        res = without_modes(res, np.delete(np.arange(res.freq_hz.size), i), why)
    return res, classify_modes(res)


def _without_blends(res, classes):
    """``res`` and ``classes`` without the crowd's blends (:func:`crowd_blends`), the others'
    readings kept: a blend's pole lies among the orders it stands for, and the crowd test
    reads the branch's dispersion through it (module docstring, "Crowd blends")."""
    blends = np.flatnonzero(crowd_blends(classes, res.meta.get("by_channels")))
    if blends.size == 0:
        return res, classes
    keep = np.setdiff1d(np.arange(len(classes)), blends)
    new = {int(k): j for j, k in enumerate(keep)}  # a split pair's id is its first member's index
    for i in blends[::-1]:
        c = classes[i]
        why = {"frequency_hz": float(res.freq_hz[i]), "damping_ratio": float(res.damping_ratio[i]),
               "group": int(res.group[i]),
               "reason": "a crowd's blend: kept apart from a stronger pole of another order group by its shape over "
                         "the channels alone, while orders of its alias class crowd within its bandwidth (n = "
                         f"{' '.join(str(k) for k in c.n_candidates)}): one pole standing for several modes moves "
                         "the channels as none of them does, so that shape is no evidence of a mode"}
        res = without_modes(res, np.delete(np.arange(res.freq_hz.size), i), why)
    out = [classes[k] if classes[k].pair is None or classes[k].pair in new and any(
        classes[q].pair == classes[k].pair for q in keep if q != k) else
        dataclasses.replace(classes[k], pair=None, splitting_hz=None) for k in keep]
    return res, [c if c.pair is None else dataclasses.replace(c, pair=new[c.pair]) for c in out]


def crowd_blends(classes, by_channels) -> np.ndarray:
    """(n_modes,) bool: the modes that the merge kept apart by their channel shape alone
    (``by_channels``, one bool per mode; None: none) and that the classification finds in a
    crowd — several orders of their alias class within one half-power bandwidth (module
    docstring, "Crowd blends")."""
    flag = np.zeros(len(classes), dtype=bool) if by_channels is None else np.asarray(by_channels, dtype=bool)
    return flag & np.array([c is not None and bool(c.crowd) for c in classes], dtype=bool)


def without_modes(res, keep, rejected: dict):
    """``res`` with only the modes ``keep`` (the synthesis stays the order groups' fit)."""
    meta = dict(res.meta)
    for key in ("order_energy", "significance_in_group", "by_channels"):
        if key in meta and meta[key] is not None:
            meta[key] = [meta[key][k] for k in keep]
    std = None if res.frequency_std_hz is None else res.frequency_std_hz[keep]
    return dataclasses.replace(res, freq_hz=res.freq_hz[keep], damping_ratio=res.damping_ratio[keep],
                               poles=res.poles[keep], shapes=res.shapes[keep], mpc=res.mpc[keep],
                               significance=res.significance[keep], group=res.group[keep],
                               rejected=list(res.rejected) + [rejected], meta=meta, frequency_std_hz=std)
