"""The modal stage's result: the modal table, with shapes, geometry and the stabilization.

:class:`ModalTable` is what ``lsce`` hands to ``identify`` and what the modal file holds
(:mod:`tiremodal_cli.io.modalfile` reads and writes it); :func:`to_rows` gives its rows
(the ``--json`` list, the CSV's columns :data:`COLUMNS`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ModalTable", "table_from_result", "frequency_uncertainty", "to_rows", "channel_live", "COLUMNS",
           "STATUS_CODES"]

#: the stabilization diagram's status of a pole, as a code (the diagram's fifth column)
STATUS_CODES = {"new": 0, "f": 1, "fd": 2, "fv": 3, "stable": 4}
#: the columns of a modal table's rows (``to_rows``) and of its CSV, in order
COLUMNS = ("mode", "frequency_hz", "damping_ratio", "n", "branch", "n_confidence", "branch_confidence",
           "mpc", "significance", "n_spatial", "n_aliased", "pair", "splitting_hz", "in_order", "group",
           "frequency_uncertainty_hz", "crowd", "n_candidates", "confirmed")


@dataclass(frozen=True)
class ModalTable:
    """A modal table with shapes and geometry (what the modal file holds)."""

    frequency_hz: np.ndarray
    damping_ratio: np.ndarray
    pole: np.ndarray
    mpc: np.ndarray
    significance: np.ndarray
    group: np.ndarray
    n: np.ndarray
    n_spatial: np.ndarray
    n_confidence: np.ndarray
    branch: tuple
    branch_confidence: np.ndarray
    pair: np.ndarray
    splitting_hz: np.ndarray
    in_order: np.ndarray
    shapes: np.ndarray
    point_angle: np.ndarray
    point_index: np.ndarray
    channel_name: tuple
    channel_location: tuple
    channel_angle: np.ndarray
    fit_error: np.ndarray
    diagram: np.ndarray
    form: str = "accelerance"
    meta: dict | None = None
    clusters: list | None = None
    rejected: list | None = None
    synthesis: np.ndarray | None = None
    synthesis_freq_hz: np.ndarray | None = None
    #: each mode's frequency uncertainty (Hz) carried from the stabilization (and stored in the
    #: modal file since session 12); None when read from an older file (:func:`frequency_uncertainty`
    #: rebuilds it there, and can swap a split pair's two values)
    frequency_std_hz: np.ndarray | None = None

    @property
    def n_modes(self) -> int:
        return self.frequency_hz.size


def table_from_result(res, classes, *, point_angle, point_index, channel_name, channel_location,
                      channel_angle, form) -> ModalTable:
    """A ModalTable from a ModalResult and its classifications (None: not a tyre)."""
    k = res.freq_hz.size
    cls = classes or [None] * k
    diag, clusters = [], []
    for g, d in res.diagrams:
        diag += [(g, p.order, p.freq_hz, p.damping_ratio, STATUS_CODES[p.status]) for p in d.poles]
        clusters += [{"group": int(g), **c.to_dict()} for c in d.clusters]
    return ModalTable(
        frequency_hz=res.freq_hz, damping_ratio=res.damping_ratio, pole=res.poles, mpc=res.mpc,
        significance=res.significance, group=res.group,
        n=np.array([c.n if c else -1 for c in cls]), n_spatial=np.array([c.n_spatial if c else -1 for c in cls]),
        n_confidence=np.array([c.n_confidence if c else np.nan for c in cls]),
        branch=tuple((c.branch or "") if c else "" for c in cls),
        branch_confidence=np.array([c.branch_confidence if c else np.nan for c in cls]),
        pair=np.array([c.pair if c and c.pair is not None else -1 for c in cls]),
        splitting_hz=np.array([c.splitting_hz if c and c.splitting_hz is not None else np.nan for c in cls]),
        in_order=np.array([c.in_order if c else True for c in cls]),
        shapes=res.shapes, point_angle=np.asarray(point_angle, float), point_index=np.asarray(point_index),
        channel_name=tuple(channel_name), channel_location=tuple(channel_location),
        channel_angle=np.asarray(channel_angle, float), fit_error=res.fit_error,
        diagram=np.array(diag, dtype=float).reshape(-1, 5), form=form, meta=res.meta, clusters=clusters,
        rejected=res.rejected, synthesis=res.synthesis, synthesis_freq_hz=res.band_freq_hz,
        frequency_std_hz=res.frequency_std_hz)


def frequency_uncertainty(t: ModalTable) -> np.ndarray:
    """Each mode's frequency scatter (Hz) rebuilt from the table's clusters, for a table read
    from a file (the modal stage carries it: ``t.frequency_std_hz``): the standard deviation
    of its cluster's poles over the model orders of the stabilization diagram (the adopted
    cluster of its group nearest in frequency, within 1 %). NaN where none matches (an old file)."""
    out = np.full(t.n_modes, np.nan)
    adopted = [c for c in (t.clusters or []) if c.get("adopted") and "frequency_std_hz" in c]
    for i in range(t.n_modes):
        near = [c for c in adopted if c.get("group") == int(t.group[i])
                and abs(c["frequency_hz"] - t.frequency_hz[i]) <= 0.01 * t.frequency_hz[i]]
        if near:
            out[i] = min(near, key=lambda c: abs(c["frequency_hz"] - t.frequency_hz[i]))["frequency_std_hz"]
    return out


def to_rows(t: ModalTable) -> list[dict]:
    """One dict per mode (the ``--json`` list; n, branch, pair absent when not a tyre).

    Parameters
    ----------
    t : ModalTable

    Returns
    -------
    list of dict
        Keys of :data:`COLUMNS` (``frequency_hz`` in Hz, ``damping_ratio`` a fraction …),
        what ``identify``, ``diagnose`` and :func:`tiremodal_cli.tyre.measured.modes_from_rows` read.
    """
    rows = []
    # carried from the stabilization (and the modal file); rebuilt from the clusters only for a
    # file written before session 12 — where nearest-frequency matching can swap a split pair's
    # values (4 of 55 validation cases), so a re-diagnosis of such a file may differ from run's
    unc = frequency_uncertainty(t) if t.frequency_std_hz is None else np.asarray(t.frequency_std_hz, float)
    crowds = (t.meta or {}).get("crowds") or []
    n_top = t.point_angle.size // 2
    for i in range(t.n_modes):
        cands = next((c["n_candidates"] for c in crowds if abs(c["frequency_hz"] - t.frequency_hz[i])
                      <= 1e-9 * t.frequency_hz[i]), [])
        row = {"mode": i + 1, "frequency_hz": float(t.frequency_hz[i]), "damping_ratio": float(t.damping_ratio[i]),
               "mpc": float(t.mpc[i]), "significance": float(t.significance[i]), "group": int(t.group[i]),
               "frequency_uncertainty_hz": None if not np.isfinite(unc[i]) else float(unc[i])}
        conf = (t.meta or {}).get("confirmed")
        if conf is not None and len(conf) == t.n_modes:
            row["confirmed"] = bool(conf[i])
        if t.n[i] >= 0:
            row.update(n=int(t.n[i]), branch=t.branch[i] or None, n_confidence=float(t.n_confidence[i]),
                       branch_confidence=float(t.branch_confidence[i]), n_spatial=int(t.n_spatial[i]),
                       n_aliased=bool(t.n[i] != t.n_spatial[i] or any(c > n_top for c in cands)),
                       crowd=bool(cands), n_candidates=" ".join(str(c) for c in cands) or None,
                       pair=None if t.pair[i] < 0 else int(t.pair[i]) + 1,
                       splitting_hz=None if not np.isfinite(t.splitting_hz[i]) else float(t.splitting_hz[i]),
                       in_order=bool(t.in_order[i]))
        rows.append(row)
    return rows


def channel_live(t: ModalTable) -> np.ndarray:
    """(n_channels,) bool: False for a dead channel (its fit error and shapes NaN in memory)."""
    fe = np.asarray(t.fit_error, dtype=float)
    if fe.ndim != 2 or fe.shape[0] != len(t.channel_name):
        return np.ones(len(t.channel_name), dtype=bool)
    return ~np.all(np.isnan(fe), axis=1)
