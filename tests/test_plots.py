"""Figures a reader can read: MAC values only where legible, integer orders, labelled and
uncut axes, one stabilization panel per order group, names and units from one table."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tiremodal_cli import names, plots
from tiremodal_cli.tyre.effects import EFFECTS
from tiremodal_cli.tyre.model import TyreParameters


def test_mac_prints_values_only_where_readable():
    rng = np.random.default_rng(0)
    for k, texts in ((6, 36), (plots.MAC_VALUES_MAX, plots.MAC_VALUES_MAX ** 2), (34, 0)):
        M = rng.uniform(size=(k, k))
        ax = plots.plot_mac(M)
        assert len(ax.texts) == texts


def test_order_axes_tick_at_integers():
    rows = [{"n": n, "branch": b, "model_hz": 50 + 10 * n + (100 if b == "opposite" else 0), "std_hz": 1.0}
            for n in range(0, 6) for b in ("same", "opposite")]
    ax = plots.plot_dispersion(rows)
    ax.figure.canvas.draw()
    lo, hi = ax.get_xlim()
    ticks = [t for t in ax.get_xticks() if lo <= t <= hi]
    assert ticks and all(float(t).is_integer() for t in ticks)


@pytest.mark.parametrize("history", [[(g, 0.12 * 0.9 ** g + 0.09) for g in range(1, 70)],
                                     [(g, 0.5 * 0.8 ** g + 1e-4) for g in range(1, 70)]])
def test_convergence_has_a_y_label_and_tick_labels_inside_the_figure(history):
    ax = plots.plot_convergence(history)
    fig = ax.figure
    fig.canvas.draw()
    assert ax.get_ylabel()
    r = fig.canvas.get_renderer()
    fb = fig.bbox
    (xlo, xhi), (ylo, yhi) = ax.get_xlim(), ax.get_ylim()
    shown = [t for t in ax.get_yticklabels(which="both") if t.get_text() and ylo <= t.get_position()[1] <= yhi]
    shown_x = [t for t in ax.get_xticklabels() if t.get_text() and xlo <= t.get_position()[0] <= xhi]
    assert len(shown) >= 2  # at least two numbers on the error axis
    for t in shown + shown_x + [ax.yaxis.label, ax.xaxis.label]:
        b = t.get_window_extent(r)
        assert b.x0 >= fb.x0 - 1 and b.x1 <= fb.x1 + 1 and b.y0 >= fb.y0 - 1 and b.y1 <= fb.y1 + 1, t.get_text()


def test_stabilization_has_one_panel_per_order_group():
    groups = [0, 1, 2, 3, 4]
    diag = np.array([(g, o, 50.0 + 20 * g + 0.1 * o, 0.02, 4) for g in groups for o in range(2, 12)], float)

    class T:
        diagram = diag
        frequency_hz = np.array([50.0 + 20 * g for g in groups])
        group = np.array(groups)

    fig = plots.stabilization_grid(T)
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == len(groups)
    assert [ax.get_title() for ax in visible] == [f"spatial order {g}" for g in groups]
    for ax, g in zip(visible, groups):  # each panel holds its own group's poles and mode
        xs = np.concatenate([ln.get_xdata() for ln in ax.lines if ln.get_linestyle() == "None"])
        assert np.all(np.abs(xs - (50 + 20 * g)) < 2)


def test_names_table_covers_the_model_and_the_effects():
    """ONE table: every model parameter has a name and the unit TyreParameters uses; every
    effect parameter a unit; labels carry the unit."""
    for f in dataclasses.fields(TyreParameters):
        assert f.name in names.PARAMETERS and names.unit(f.name) == TyreParameters.UNITS[f.name]
        assert names.name(f.name) != f.name
    for e in EFFECTS.values():
        assert names.effect_title(e.name) != e.name
        for p in e.parameters:
            assert names.unit(f"{e.name}.{p.name}") == p.unit
    assert names.long_label("rhoA") == "tread mass per length rhoA [kg/m]"
    assert names.label("sidewall_membrane.T_s") == "T_s [N]"


def test_campaign_repeats_do_not_overplot_and_effects_are_shown():
    recs = [{"status": "done", "test": f"t{i}", "inflation_pressure": p,
             "identified": {"k_r1": {"value": 6e6 + i, "std_error": 1e4}},
             "augmented_parameters": {"k_r1": {"value": 6e6, "std_error": 1e4},
                                      "sidewall_membrane.T_s": {"value": 2e4 + i, "std_error": 30.0}}}
            for i, p in enumerate([7e5, 7e5, 7e5, 9e5, 9e5])]
    fig = plots.plot_campaign_parameters(recs)
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert len(axes) == 2 and "T_s [N]" in axes[1].get_title() and "[N/m²]" in axes[0].get_title()
    x = axes[0].lines[0].get_xdata()
    assert len(set(np.round(x, 9))) == 5  # five tests, five places
    assert np.all(np.abs(x[:3] - 700) <= 200 / 8 + 1e-9) and np.all(np.abs(x[3:] - 900) <= 200 / 8 + 1e-9)
    assert list(axes[0].get_xticks()) == [700.0, 900.0]
