"""The modal stage: FRFs → poles (LSCE + stabilization) → shapes (LSFD) → a modal table.

General for any structure. For a tyre (points around the tread with angles), the FRFs are
first split into circumferential orders (:mod:`tiremodal_cli.modal.spatial`) and each order is
swept on its own; the poles of all orders then get their shapes from one LSFD over the
physical FRFs. Damping is corrected for the exponential window recorded in the FRF file.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np
from threadpoolctl import threadpool_limits

from tiremodal_cli.conventions import FORM_POWER
from tiremodal_cli.errors import DataFormatError, ParameterError
from tiremodal_cli.frf.windows import correct_poles
from tiremodal_cli.modal.band import (band_or_every_line, default_band, live_channels, no_stable_mode, noise_shape,
                                      order_for_lines)
from tiremodal_cli.modal.classify import classify
from tiremodal_cli.modal.gaps import cleaned_groups, weak_in_frfs
from tiremodal_cli.modal.groupfit import GroupData
from tiremodal_cli.modal.joint import add_missing_orders
from tiremodal_cli.modal.refine import refine_adopted
from tiremodal_cli.modal.point_order import (angle_order, frf_points_taken, result_points_taken, stored_order,
                                             table_points_taken)
from tiremodal_cli.modal.lsce import poles_to_modal, principal_responses
from tiremodal_cli.modal.lsfd import mpc
from tiremodal_cli.modal.mixed_rows import where_orders_mix
from tiremodal_cli.modal.leaks import leak_copies, under_residual
from tiremodal_cli.modal.merge import COPY_MAX_AMPLITUDE, merge_groups, off_edges
from tiremodal_cli.modal.misreads import without_misreads
from tiremodal_cli.modal.options import ModalOptions
from tiremodal_cli.modal.plscf import confirmed
from tiremodal_cli.modal.rescue import far_bands
from tiremodal_cli.modal.groupmodes import group_modes
from tiremodal_cli.modal.mirror import mirror_filled
from tiremodal_cli.modal.mixing import mixed_orders_note, order_mixing
from tiremodal_cli.modal.spatial import decompose, grid_points, is_circumferential, leakage
from tiremodal_cli.modal.stabilization import stabilize
from tiremodal_cli.modal.symmetry import antisymmetric_share
from tiremodal_cli.modal.table import table_from_result

log = logging.getLogger(__name__)
GROUP_MAX_ORDER = 40  # an order group holds a few modes, plus what models the band edges

__all__ = ["GROUP_MAX_ORDER", "ModalOptions", "ModalResult", "estimate_modes", "is_circumferential", "modal_table_from_frf", "confirmed"]


@dataclass(frozen=True)
class ModalResult:
    """Modes found in a set of FRFs.

    Attributes
    ----------
    freq_hz, damping_ratio : (n_modes,) ndarray     structural (window-corrected) values
    poles : (n_modes,) complex ndarray              as estimated from the FRFs, rad/s
    shapes : (n_modes, n_channels, n_points) complex ndarray   LSFD residues
    mpc, significance : (n_modes,) ndarray
    group : (n_modes,) ndarray of int               circumferential order group (−1: none)
    fit_error : (n_channels, n_points) ndarray      ‖H − Ĥ‖/‖H‖ over the band
    synthesis : (n_channels, n_points, n_band) complex ndarray
    band_freq_hz : (n_band,) ndarray
    diagrams : list of (group, Diagram)
    rejected : list of dict                         modes dropped after LSFD, with reasons
    frequency_std_hz : (n_modes,) ndarray, Hz       scatter of each mode's cluster of poles
                                                    over the model orders (its uncertainty)
    """

    freq_hz: np.ndarray
    damping_ratio: np.ndarray
    poles: np.ndarray
    shapes: np.ndarray
    mpc: np.ndarray
    significance: np.ndarray
    group: np.ndarray
    fit_error: np.ndarray
    synthesis: np.ndarray
    band_freq_hz: np.ndarray
    diagrams: list = field(default_factory=list)
    rejected: list = field(default_factory=list)
    meta: dict = field(default_factory=dict)
    frequency_std_hz: np.ndarray | None = None


def estimate_modes(freq_hz, H, **kwargs) -> "ModalResult":
    """Modal parameters of a set of FRFs (see :func:`_estimate_modes` for the parameters).

    The sweep is thousands of small solves and eigenproblems; OpenBLAS's threads cost more
    than they give at that size (measured: 2 × slower on 2 cores), so BLAS runs on one
    thread here (threadpoolctl), whatever the caller's setting.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return _estimate_modes(freq_hz, H, **kwargs)


@dataclass(frozen=True)
class _Band:
    """The FRFs of the analysis band in the stage's internal form (accelerance).

    live : (n_channels,) bool ; lines : (n_freq,) bool, the band's lines ; freq : (K,) Hz
    to_acc : (K,) complex, the factor from the given form ; Hb : (n_live, n_points, K)
    noise : (K,) the FRFs' noise variance per line in accelerance, relative (median 1;
    :func:`~tiremodal_cli.modal.band.noise_shape`), or None (white)
    window : (τ s, line spacing Hz) of the FRFs' exponential window, or None
    (:func:`~tiremodal_cli.modal.band.window_noise_gain`)
    """

    live: np.ndarray
    lines: np.ndarray
    freq: np.ndarray
    to_acc: np.ndarray
    Hb: np.ndarray
    noise: np.ndarray | None = None
    window: tuple | None = None

    @property
    def flat(self) -> np.ndarray:
        return self.Hb.reshape(-1, self.freq.size)


def _estimate_modes(freq_hz, H, *, point_angle=None, channel_location=(), form="accelerance",
                    exp_tau_s=None, opt: ModalOptions = ModalOptions(), progress=None,
                    channel_angle=None, noise_var=None) -> ModalResult:
    """Modal parameters of a set of FRFs.

    Parameters
    ----------
    freq_hz : (n_freq,) array, Hz
    H : (n_channels, n_points, n_freq) complex array
    point_angle : (n_points,) array, rad, optional
    channel_location : sequence of str, optional ; channel_angle : (n_channels,) rad, optional
    form : FRF form of H
    exp_tau_s : float, optional — exponential window to correct the damping for
    noise_var : (n_freq,) array, optional — the FRFs' noise variance per line in accelerance,
        relative (:func:`~tiremodal_cli.modal.band.noise_shape`); None: white
    opt : ModalOptions
    progress : callable(done, total), optional

    Returns
    -------
    ModalResult
    """
    opt.check()
    freq_hz = np.asarray(freq_hz, dtype=float)
    H = np.asarray(H)
    band = _band_frfs(freq_hz, H, live_channels(freq_hz, H), form, opt, noise_var, exp_tau_s)
    spatial = opt.spatial == "on" or (opt.spatial == "auto" and point_angle is not None
                                      and is_circumferential(point_angle, channel_location))
    groups, group_max, opt = _order_groups(band, point_angle, spatial, opt)
    gaps = spatial and grid_points(point_angle) > len(point_angle)  # points missing: every order leaks
    share = (antisymmetric_share(band.freq, band.Hb, point_angle, np.asarray(channel_angle)[band.live], exp_tau_s)
             if spatial and channel_angle is not None and point_angle is not None else None)
    ortho = share is not None and share < COPY_MAX_AMPLITUDE  # (with gaps: the ones no mirror image filled)
    live_angles = () if channel_angle is None else np.asarray(channel_angle, dtype=float)[band.live]
    diagrams, modes, rejected, synth, kept, mixing = _modes_of_groups(band, groups, point_angle, spatial, gaps,
                                                                      group_max, opt, progress, ortho, live_angles)
    if gaps:  # once more, each group read with the found modes' leaks taken out (modal.gaps)
        groups = cleaned_groups(band.freq, band.Hb, point_angle, [m.pole for m in modes],
                                [set(m.order_energy) for m in modes])
        diagrams, modes, rejected, synth, kept, mixing = _modes_of_groups(band, groups, point_angle, spatial, gaps,
                                                                          group_max, opt, progress, ortho, live_angles)
    if gaps:  # the branches' unfound orders, refined jointly with the modes found (modal.joint)
        locs = [tuple(channel_location)[i] for i in np.flatnonzero(band.live)] if len(channel_location) else []
        modes, synth, proposed = add_missing_orders(band.freq, band.Hb, point_angle, locs, modes, synth, window=band.window)
        modes, weak = weak_in_frfs(modes, opt.min_significance, band.freq, point_angle, band.flat - synth, window=band.window)
        rejected += proposed + weak
    if opt.refine:  # the poles near the band's edges (docs/lsce.md, "Pole refinement"); the physical
        # check where a group's rows are not its orders' whole data (docs/lsce.md, "Session 33")
        modes, unlocated = refine_adopted(modes, {g: k for g, k in kept.items() if k is not None},
                                          None if ortho and not gaps else synth,
                                          complete=ortho and not gaps and not (mixing and mixing["mixed"]))
        rejected += unlocated
    modes, edge = off_edges(modes, band.freq[0], band.freq[-1], exp_tau_s)
    if not modes:
        raise no_stable_mode(band.freq, group_max)
    meta = {"band_hz": [float(band.freq[0]), float(band.freq[-1])], "spatial": bool(spatial),
            "max_order": int(group_max), "exp_tau_s": exp_tau_s, "antisymmetric_share": share,
            "order_mixing": mixing}
    return _result(band, H.shape, modes, synth, exp_tau_s, diagrams=diagrams, rejected=rejected + edge, meta=meta)


def _modes_of_groups(band: _Band, groups, point_angle, spatial: bool, gaps: bool, group_max: int,
                     opt: ModalOptions, progress, orthogonal: bool = False, channel_angle=()):
    """Every order group swept and fitted, and their modes merged into one per physical pole
    (``orthogonal``: a complete grid of a structure symmetric about its sensors, merge_groups);
    a group whose fit left a peak that no group's pole reaches, on a complete grid, fitted
    again with the sweep at twice its order there (:mod:`~tiremodal_cli.modal.rescue`).

    Returns (diagrams, modes (MergedMode), rejected, the physical synthesis (n_frf, K), each
    group's kept fit ({group: kept or None}, for the pole refinement), the order-mixing test
    (:func:`~tiremodal_cli.modal.mixing.order_mixing`; None: not run))."""
    diagrams, found, rejected, kept, out = [], [], [], {}, {}
    synth = np.zeros(band.flat.shape, dtype=complex)
    for i, (g, (rows, back)) in enumerate(sorted(groups.items())):
        data = GroupData(band.freq, rows, back, band.flat, "accelerance", opt, g, rows.shape[0] // band.Hb.shape[0],
                         band.Hb.shape[0], band.noise, band.window)
        out[g] = (data, group_modes(data, spatial, group_max, split=not gaps))
        if progress:
            progress(i + 1, len(groups))
    every = [(m.pole, h) for h, (_, r) in out.items() for m in r[1]]
    for g, (data, r) in out.items():  # peaks no pole of any group stands for (modal.rescue)
        far = far_bands(r[5], [p for p, _ in every], band.freq[1] - band.freq[0], [h for _, h in every],
                        2 if orthogonal else 1, own=g) if not gaps else []
        out[g] = (data, group_modes(data, spatial, group_max, far, split=True)) if far else out[g]
    mixing = (order_mixing(band.freq, {g: d.rows for g, (d, _) in out.items()},
                           [(m.group, m.pole, m.significance) for _, r in out.values() for m in r[1]], channel_angle)
              if orthogonal and not gaps else None)
    if opt.beside and mixing is not None and not mixing["mixed"]:  # each group's rows a complete model
        out = {g: (data, group_modes(data, spatial, group_max, beside=True, diagram=r[0]))
               for g, (data, r) in out.items()}
    for g, (_, (d, modes, rej, group_synth, kept[g], _)) in sorted(out.items()):
        diagrams.append((g, d))
        found += modes
        rejected += rej
        if group_synth is not None:
            synth += group_synth
    if not found:
        raise no_stable_mode(band.freq, group_max)
    if gaps:
        found, copies = leak_copies(found, leakage(point_angle))
        rejected += copies
    orthogonal = orthogonal and not (mixing and mixing["mixed"])  # a lumped mass on the sensors' plane (modal.mixing)
    mixed = not orthogonal and not gaps  # a complete grid whose groups are no complete model of their orders
    modes = merge_groups(found, line_hz=band.freq[1] - band.freq[0], min_significance=opt.min_significance,
                         orthogonal=orthogonal, leak=leakage(point_angle) if gaps else None,
                         n_channels=band.Hb.shape[0], mixed=mixed)
    if not gaps:  # (with gaps: leak_copies only)
        modes, unseen = under_residual(modes, band.freq[1] - band.freq[0], band.Hb.shape[0], opt.min_significance,
                                       orthogonal=orthogonal)
        rejected += unseen
    return diagrams, modes, rejected, synth, kept, mixing


def _band_frfs(freq_hz, H, live, form: str, opt: ModalOptions, noise_var=None, exp_tau_s=None) -> _Band:
    """The live FRFs on the band's lines, in accelerance, and their noise variance per line
    (``noise_var``, median 1 over the band: the records are accelerations (FORMAT.md), so
    their sensor noise is the same in accelerance whatever form the FRFs are given in).

    One internal form: the estimate then weighs the lines alike whatever form the FRFs come
    in (receptance's 1/ω² would let the low lines dominate and turn the high band's noise
    into stable poles); the residues mean the same in every form (the LSFD basis carries
    (iω)^q), and the synthesis goes back to the given form.
    """
    band = band_or_every_line(freq_hz, opt.band_hz)
    sel = principal_responses(freq_hz, H[live].reshape(-1, freq_hz.size), band, rtol=opt.rtol_svd)
    lines = (freq_hz >= sel.freq_hz[0] - 1e-9) & (freq_hz <= sel.freq_hz[-1] + 1e-9)
    k_lines = freq_hz[lines]
    if form not in FORM_POWER:
        raise ParameterError(f"form={form!r}; allowed: {', '.join(FORM_POWER)}")
    if FORM_POWER[form] != 2 and k_lines[0] <= 0:
        raise ParameterError(f"the band of {form} FRFs must start above 0 Hz (got {k_lines[0]:g} Hz)")
    to_acc = (2j * np.pi * k_lines) ** (2 - FORM_POWER[form])
    noise = None if noise_var is None else np.asarray(noise_var, dtype=float)[lines]
    noise = None if noise is None else noise / np.median(noise)
    window = (float(exp_tau_s), float(freq_hz[1] - freq_hz[0])) if exp_tau_s and freq_hz.size > 1 else None
    return _Band(live, lines, k_lines, to_acc, H[live][:, :, lines] * to_acc, noise, window)


def _order_groups(band: _Band, point_angle, spatial: bool, opt: ModalOptions):
    """The rows to sweep, by circumferential order group ({group: (rows, back)}; one group
    −1 without the spatial split), the highest model order of a group's sweep, and the
    options for the groups.

    With points missing from the grid every group holds every mode of the band (leaked,
    :func:`~tiremodal_cli.modal.spatial.leakage`), as the unsplit FRFs do: a group's sweep
    then gets the unsplit sweep's order (``max_order``; two references: half of it),
    else the leaks it cannot model bias its own modes (seen: 0.5 % on 19 of 24 points).
    """
    n_live, n_p, K = band.Hb.shape
    if spatial:
        groups = decompose(band.Hb, point_angle)
        group_max = min(opt.max_order, GROUP_MAX_ORDER)
        if grid_points(point_angle) > n_p:
            group_max = opt.max_order
            opt = replace(opt, poly_order=max(opt.poly_order, opt.max_order // 2))
    else:
        groups = {-1: (band.Hb.reshape(-1, K), np.eye(n_live * n_p))}
        group_max = opt.max_order
    top = order_for_lines(group_max, K, opt.order_within_band)  # (short records lower it, for run)
    poly = min(opt.poly_order, max(1, top // 2)) if top < group_max else opt.poly_order
    poly = order_for_lines(poly, K, opt.order_within_band, n_ref=2) if spatial else poly
    return groups, top, replace(opt, poly_order=poly)


def _classified(res: ModalResult, r) -> tuple:
    """The modes of a tyre test (points round a tread) classified by order and branch, their
    misreads dropped (:func:`~tiremodal_cli.modal.misreads.without_misreads`) and their crowds in
    ``meta["crowds"]``: (result, classifications, or None when there is no tread to read)."""
    live = [i for i, n in enumerate(r.channel_name) if n not in r.dead_channels]
    locs = [r.channel_location[i] for i in live]
    if not res.meta["spatial"] or "tread" not in locs:
        return res, None
    share = res.meta.get("antisymmetric_share")  # None: not measured (no sensor angles)
    # the orders mix: a lumped mass on the sensors' plane (modal.mixing), or off it (no symmetry)
    mixed = bool((res.meta.get("order_mixing") or {}).get("mixed")) or bool(share and share >= COPY_MAX_AMPLITUDE)
    res.meta["orders_mix"] = mixed_orders_note(share, res.meta.get("order_mixing"))
    def classify_modes(m):
        return classify(m.freq_hz, m.shapes[:, live], r.point_angle, locs, m.significance, m.damping_ratio,
                        m.meta.get("significance_in_group"), m.group, mixed=mixed)

    res, classes = without_misreads(res, classify_modes, symmetric=share is not None and not mixed)
    if mixed:  # split pairs and one order's blends against the other orders' copies (modal.mixed_rows)
        res, classes = where_orders_mix(res, classes, classify_modes, r, live)
    res.meta["crowds"] = [{"frequency_hz": float(res.freq_hz[i]), "n_spatial": c.n_spatial,
                           "n_candidates": list(c.n_candidates),
                           "reason": "orders aliasing onto one spatial order lie within one half-power "
                                     "bandwidth by the branch's dispersion: the order cannot be told"}
                          for i, c in enumerate(classes) if c.crowd]
    return res, classes


def _result(band: _Band, shape, modes, synth, exp_tau_s, *, diagrams, rejected, meta) -> ModalResult:
    """The merged modes as a ModalResult: shapes, fit errors and synthesis back in the given
    form with NaN on the dead channels, frequencies and damping corrected for the window."""
    n_c, n_p = shape[:2]
    n_live, live = band.Hb.shape[0], band.live
    s = np.array([m.pole for m in modes])
    shapes = np.full((s.size, n_c, n_p), np.nan + 0j)
    shapes[:, live] = np.array([m.residues for m in modes]).reshape(s.size, n_live, n_p)
    err = np.full((n_c, n_p), np.nan)
    Hflat, synth = band.flat / band.to_acc, synth / band.to_acc  # back to the given form
    err[live] = (np.linalg.norm(Hflat - synth, axis=1) /
                 np.maximum(np.linalg.norm(Hflat, axis=1), np.finfo(float).tiny)).reshape(n_live, n_p)
    syn = np.full((n_c, n_p, band.freq.size), np.nan + 0j)
    syn[live] = synth.reshape(n_live, n_p, -1)
    f_true, z_true = poles_to_modal(correct_poles(s, exp_tau_s))
    meta = {**meta, "order_energy": [m.order_energy for m in modes],
            "significance_in_group": [m.significance_in_group for m in modes],
            "by_channels": [m.by_channels for m in modes]}
    return ModalResult(freq_hz=f_true, damping_ratio=z_true, poles=s, shapes=shapes,
                       mpc=np.array([mpc(m.residues) for m in modes]),
                       significance=np.array([m.significance for m in modes]),
                       group=np.array([m.group for m in modes]), fit_error=err, synthesis=syn,
                       band_freq_hz=band.freq, diagrams=diagrams, rejected=rejected, meta=meta,
                       frequency_std_hz=np.array([m.frequency_std_hz for m in modes]))


def modal_table_from_frf(r, opt: ModalOptions = ModalOptions(), *, progress=None):
    """The whole modal stage on an FRFResult: modes, and the tyre classification when the
    points go round a tread.

    Without ``opt.band_hz`` the band is :func:`default_band` of the FRFs' coherence and, when
    the FRFs carry it, the mean over the points of their force autospectrum
    (``r.force_autospectrum``: ``lsce`` on an FRF file chooses the band ``run`` chose); its
    reason in ``meta["band_reason"]``.

    Returns
    -------
    table : ModalTable ; result : ModalResult
    """
    order = angle_order(r.point_angle)
    if order is not None:  # every estimate in the order of the angles (point_order): the same however stored
        return stored_order(modal_table_from_frf(frf_points_taken(r, order), opt, progress=progress), order)
    if opt.band_hz is None:
        g = None if r.force_autospectrum is None else np.mean(r.force_autospectrum, axis=0)
        band, why = default_band(r.freq_hz, r.coherence, r.n_averages, g)
        opt = replace(opt, band_hz=band)
    else:
        why = "given"
    if opt.method == "both":
        table, res = modal_table_from_frf(r, replace(opt, method="lsce"), progress=progress)
        other, res2 = modal_table_from_frf(r, replace(opt, method="plscf"), progress=progress)
        table.meta["band_reason"] = why
        table.meta["method"] = "both"
        table.meta["confirmed"] = confirmed(res, res2).tolist()
        return table, res

    r, measured, mirrored = (mirror_filled(r, opt.band_hz) if is_circumferential(r.point_angle, r.channel_location)
                             else (r, None, None))
    res = estimate_modes(r.freq_hz, r.H, point_angle=r.point_angle, channel_location=r.channel_location,
                         form=r.form, exp_tau_s=r.exp_tau_s, opt=opt, progress=progress, channel_angle=r.channel_angle,
                         noise_var=noise_shape(r.force_autospectrum, r.n_averages))
    res.meta["band_reason"] = why
    res.meta["method"] = opt.method
    res, classes = _classified(res, r)
    table = table_from_result(res, classes, point_angle=r.point_angle, point_index=r.point_index,
                              channel_name=r.channel_name, channel_location=r.channel_location,
                              channel_angle=r.channel_angle, form=r.form)
    if mirrored is not None:  # the points filled from their mirror images out again (modal.mirror)
        table.meta["mirrored_points"] = mirrored
        if measured is not None:
            table, res = table_points_taken(table, measured), result_points_taken(res, measured)
    return table, res
