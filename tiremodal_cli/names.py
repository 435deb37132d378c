"""Physical names and units of everything a page or a plot names: ONE table.

Reports, campaign plots and tables take a parameter's words and unit from here, never
from the code name alone. The tyre model's parameters are listed in :data:`PARAMETERS`
(``TyreParameters.UNITS`` is drawn from it); an effect's title and its parameters' units
and meanings come from the effect's own declaration (:mod:`tiremodal_cli.tyre.effects`), read
here so that every caller has one place to ask.
"""

from __future__ import annotations

__all__ = ["PARAMETERS", "QUANTITIES", "unit", "name", "label", "long_label", "effect_title"]

#: code name → (physical name, SI unit)
PARAMETERS: dict[str, tuple[str, str]] = {
    "R": ("tread radius", "m"),
    "b": ("tread width", "m"),
    "P0": ("inflation pressure", "Pa"),
    "rhoA": ("tread mass per length", "kg/m"),
    "m_s": ("sidewall mass per length", "kg/m"),
    "EI": ("tread bending stiffness", "N·m²"),
    "k_r1": ("tread–sidewall radial stiffness per length", "N/m²"),
    "k_r2": ("sidewall–rim radial stiffness per length", "N/m²"),
    "m_w": ("rim (and fixture) mass", "kg"),
}

#: other quantities that figures and tables name: key → (name, unit)
QUANTITIES: dict[str, tuple[str, str]] = {
    "frequency_hz": ("frequency", "Hz"),
    "damping_ratio": ("damping ratio", "–"),
    "damping_pct": ("damping ratio", "%"),
    "n": ("circumferential order n", "–"),
    "rms_error_pct": ("RMS frequency error", "%"),
    "inflation_pressure": ("inflation pressure", "Pa"),
}


def _effect_param(key: str):
    from tiremodal_cli.tyre.effects import EFFECTS

    eff, _, p = key.partition(".")
    if eff in EFFECTS:
        for q in EFFECTS[eff].parameters:
            if q.name == p:
                return EFFECTS[eff], q
    return None, None


def unit(key: str) -> str:
    """The SI unit of a parameter (``"k_r1"``, an effect's ``"sidewall_membrane.T_s"`` or a
    quantity); "" when unknown."""
    if key in PARAMETERS:
        return PARAMETERS[key][1]
    if key in QUANTITIES:
        return QUANTITIES[key][1]
    _, q = _effect_param(key)
    return q.unit if q is not None else ""


def name(key: str) -> str:
    """The physical name of a parameter (its meaning in words); the key itself when unknown."""
    if key in PARAMETERS:
        return PARAMETERS[key][0]
    if key in QUANTITIES:
        return QUANTITIES[key][0]
    eff, q = _effect_param(key)
    if q is not None:
        return q.doc.split(":")[0].strip()
    return key


def label(key: str) -> str:
    """Symbol and unit for an axis or a column: ``"k_r1 [N/m²]"``, ``"T_s [N]"``."""
    u = unit(key)
    sym = key.split(".")[-1]
    return f"{sym} [{u}]" if u and u != "–" else sym


def long_label(key: str) -> str:
    """Name, symbol and unit: ``"tread mass per length rhoA [kg/m]"``."""
    n = name(key)
    lab = label(key)
    return lab if n == key else f"{n} {lab}"


def effect_title(effect: str) -> str:
    """An effect's title in words (``sidewall_membrane`` → "sidewall circumferential (membrane)
    stiffness ∝ n²"); a parameter found off (``"EI"``) → its name; else the code name."""
    from tiremodal_cli.tyre.effects import EFFECTS

    if effect in EFFECTS:
        return EFFECTS[effect].title
    if effect in PARAMETERS:
        return f"{PARAMETERS[effect][0]} ({effect}) off its nominal value"
    return effect
