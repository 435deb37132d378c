"""One order group's modes: its poles at every model order (LSCE, poly-reference LSCE or
pLSCF), its stabilization diagram, the group's fit (:mod:`~tiremodal_cli.modal.groupfit`),
and the poles the rescue (:mod:`~tiremodal_cli.modal.rescue`) and the fit beside its poles
(:mod:`~tiremodal_cli.modal.beside`) add."""

from __future__ import annotations

import dataclasses

import numpy as np

from tiremodal_cli.modal.beside import with_beside
from tiremodal_cli.modal.groupfit import GroupData, fit_clusters, row_visibility
from tiremodal_cli.modal.guard import guarded_diagram
from tiremodal_cli.modal.lsce import bridge, sweep, sweep_poly
from tiremodal_cli.modal.merge import GroupMode, swap_cost
from tiremodal_cli.modal.plscf import sweep_plscf
from tiremodal_cli.modal.refine import dropped_poles
from tiremodal_cli.modal.rescue import parts_kept, split_at_top, unexplained_bands, with_rescued, without_blends

__all__ = ["group_modes", "group_poles"]


def group_poles(data: GroupData, b, spatial: bool, group_max: int) -> list:
    """One group's poles at every model order, by the method of ``data.opt``."""
    opt, rows, n_h = data.opt, data.rows, data.n_h
    poly = spatial and opt.poly and n_h == 2  # the cos and sin components as two references
    if opt.method == "plscf":
        Y3 = rows.reshape(n_h, data.n_c, -1).transpose(1, 0, 2) if poly else rows[:, None, :]
        poles = sweep_plscf(data.freq, Y3, range(1, (opt.poly_order if poly else group_max) + 1))
        if not poly:  # one reference: no participation to compare, shapes from the band
            poles = [dataclasses.replace(op, participation=None) for op in poles]
        return poles
    if poly:  # split pairs resolve
        guard = b.irf.shape[-1] - b.freq_hz.size
        irf = np.fft.ifft(bridge(rows.reshape(n_h, data.n_c, -1).transpose(1, 0, 2), guard), axis=-1)
        return sweep_poly(irf, range(1, opt.poly_order + 1), b.dt, b.f_lo, b.width_hz, workers=opt.workers)
    return sweep(b, range(2, group_max + 1), skip=opt.skip)


def group_modes(data: GroupData, spatial: bool, group_max: int, rescue=(), beside: bool = False, diagram=None,
                split: bool = False):
    """One order group: its stabilization diagram, its modes (GroupMode), the poles dropped
    after LSFD, its synthesis in the physical FRFs, (with ``opt.refine``; else None) what
    :func:`_refine_adopted` needs: (data, kept poles, their participation, the fit's
    synthesis in the group's rows, the poles the fit dropped and their participation —
    :func:`~tiremodal_cli.modal.refine.dropped_poles`), and the bands where its fit leaves a
    peak no kept pole stands for (:func:`~tiremodal_cli.modal.rescue.unexplained_bands`).
    ``rescue`` (bands, Hz): the sweep redone at twice the order adds its clusters there.
    ``beside``: poles the group's residual asks for beside its kept ones added
    (:mod:`~tiremodal_cli.modal.beside`); ``diagram``: the group's diagram of an earlier call
    (not swept again). ``split``: a blend the sweep's top resolves swept again
    (:func:`~tiremodal_cli.modal.rescue.split_at_top`; not on a grid with points missing, where
    every group holds every mode's leaks, as for ``rescue``)."""
    d = diagram or guarded_diagram(data, lambda b: group_poles(data, b, spatial, group_max))
    s0, parts, (fit, s, rej, refit) = fit_clusters(data, d.selected())
    line, poles_to = data.freq[1] - data.freq[0], lambda dd, b, top: group_poles(dd, b, spatial, top)
    split = split_at_top(d, data.freq) if split and diagram is None else []
    d1 = split and with_rescued(data, d, split, poles_to, group_max)
    d1 = d1 and without_blends(d1, split, line, len(d.clusters))
    f1 = d1 and fit_clusters(data, d1[0].selected())
    if f1 and parts_kept(d1[1], f1[2][1], line):  # a blend of two modes the sweep to twice the order resolves
        d, (s0, parts, (fit, s, rej, refit)) = d1[0], f1
    d2 = rescue and with_rescued(data, d, rescue, poles_to, group_max)
    if d2:  # peaks no pole stood for (``rescue``): the sweep at twice the order found poles there
        d, (s0, parts, (fit, s, rej, refit)) = d2, fit_clusters(data, d2.selected())
    d3 = beside and fit is not None and with_beside(data, d, s0, parts, s, fit.synthesis)
    if d3:  # a weak mode beside a strong one (modal.beside)
        d, (s0, parts, (fit, s, rej, refit)) = d3, fit_clusters(data, d3.selected())
    bands = unexplained_bands(data.freq, data.rows, 0 if fit is None else fit.synthesis, s)
    if fit is None:
        return d, [], rej, None, None, bands
    scatter = {c.representative.s: c.frequency_std_hz for c in d.selected()}
    fitted = {c.representative.s: c.std_hz is not None for c in d.selected()}
    noise = float(np.sqrt(np.mean(np.sum(np.abs(data.rows - fit.synthesis) ** 2, axis=0))))
    seen = row_visibility(fit.residues, s, data.rows - fit.synthesis)
    modes = [GroupMode(s[k], data.group, data.back @ fit.residues[:, k], float(fit.significance[k]),
                       scatter[complex(s[k])], swap_cost(data.rows, fit.synthesis, s, k, refit),
                       float(fit.own[k]), noise, float(np.linalg.norm(fit.residues[:, k]) * abs(s[k]) ** 2 / abs(s[k].real)),
                       float(seen[k]), fitted=fitted[complex(s[k])])
             for k in range(s.size)]
    if not data.opt.refine:
        return d, modes, rej, data.back @ fit.synthesis, None, bands
    P = np.array(parts) if all(pt is not None for pt in parts) else None
    L = None if P is None else np.array([P[list(s0).index(p)] for p in s])
    return (d, modes, rej, data.back @ fit.synthesis, (data, s, L, fit.synthesis) + dropped_poles(s0, P, s, data.freq),
            bands)
