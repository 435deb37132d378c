"""The units of FRFs read from UFF dataset 58: which form they are in and the factor to SI.

What a file says, in order: the ordinate's axis labels (records 9/10 of dataset 58: ``g``
over ``N``, or ``m/s^2/N`` in one label), else the file's unit record (dataset 164: its
length and force factors, with the ordinate type's dimensions), else SI, stated as assumed.
"""

from __future__ import annotations

import re

from tiremodal_cli.conventions import ACCELERANCE, FORM_UNITS, MOBILITY, RECEPTANCE
from tiremodal_cli.errors import DataFormatError

__all__ = ["RESPONSE_UNITS", "FORCE_UNITS", "SPEC_OF_FORM", "frf_units"]

#: UFF dataset 58 ordinate specific data type of each form (12 acceleration, 11 velocity, 8 displacement)
SPEC_OF_FORM = {ACCELERANCE: 12, MOBILITY: 11, RECEPTANCE: 8}
_FORM_OF_SPEC = {v: k for k, v in SPEC_OF_FORM.items()}
_G = 9.80665  # standard gravity, m/s² (ISO 80000-3)
#: response units a UFF file may name (lower case, spaces removed) → (form, factor to SI)
RESPONSE_UNITS = {
    "g": ("accelerance", _G), "m/s^2": ("accelerance", 1.0), "mm/s^2": ("accelerance", 1e-3),
    "cm/s^2": ("accelerance", 1e-2), "in/s^2": ("accelerance", 0.0254), "ft/s^2": ("accelerance", 0.3048),
    "m/s": ("mobility", 1.0), "mm/s": ("mobility", 1e-3), "cm/s": ("mobility", 1e-2), "in/s": ("mobility", 0.0254),
    "m": ("receptance", 1.0), "mm": ("receptance", 1e-3), "µm": ("receptance", 1e-6), "um": ("receptance", 1e-6),
    "cm": ("receptance", 1e-2), "in": ("receptance", 0.0254),
}
#: force units a UFF file may name → factor to N
FORCE_UNITS = {"n": 1.0, "kn": 1e3, "lbf": 4.4482216152605}
#: length dimension of each form's response (time is always in seconds in UFF)
_FORM_LENGTH = {"accelerance": 1, "mobility": 1, "receptance": 1}


def _norm_unit(label) -> str:
    u = "".join(str(label or "").split()).replace("**", "^").replace("²", "^2").replace("µ", "u").lower()
    u = re.sub(r"/s2(?=$|/)", "/s^2", u)
    return "" if u in ("", "none", "unknown", "-") else u


def frf_units(frfs: list, units164: dict | None, where: str) -> tuple[str, float, dict]:
    """The FRFs' form and the factor that takes them to SI (form unit per N), and how it was found.

    Order: the ordinate's axis labels (records 9/10 of dataset 58: e.g. ``g`` over ``N``, or
    ``m/s^2/N`` in one label), else the file's unit record (dataset 164: its length and
    force factors, with the ordinate type's dimensions), else SI (stated as assumed).
    """
    spec = {int(s.get("ordinate_spec_data_type", 0) or 0) for s in frfs}
    if len(spec) != 1:
        raise DataFormatError(f"{where}: FRFs of different ordinate types {sorted(spec)}; one test has one form")
    spec = spec.pop()
    if spec and spec not in _FORM_OF_SPEC:
        raise DataFormatError(f"{where}: ordinate type {spec}; allowed: 12 (acceleration), 11 (velocity), "
                              "8 (displacement)")
    labels = {(_norm_unit(s.get("ordinate_axis_units_lab")), _norm_unit(s.get("orddenom_axis_units_lab")))
              for s in frfs}
    if len(labels) != 1:
        raise DataFormatError(f"{where}: FRFs in different units {sorted(labels)}; one test has one unit")
    num, den = labels.pop()
    for f in FORCE_UNITS:  # "g/N" or "m/s^2/N" in the ordinate label alone
        if not den and num.endswith("/" + f) and num[: -len(f) - 1] in RESPONSE_UNITS:
            num, den = num[: -len(f) - 1], f
    if num:
        if num not in RESPONSE_UNITS:
            raise DataFormatError(f"{where}: response unit {num!r} is not one tiremodal knows; known: "
                                  f"{', '.join(RESPONSE_UNITS)}")
        form, k = RESPONSE_UNITS[num]
        if spec and form != _FORM_OF_SPEC[spec]:
            raise DataFormatError(f"{where}: response unit {num!r} is a {form} unit but the ordinate type "
                                  f"{spec} says {_FORM_OF_SPEC[spec]}")
        if den and den not in FORCE_UNITS:
            raise DataFormatError(f"{where}: force unit {den!r} is not one tiremodal knows; known: N, kN, lbf")
        kf = FORCE_UNITS.get(den or "n")
        raw = [str(frfs[0].get(k) or "").strip() for k in ("ordinate_axis_units_lab", "orddenom_axis_units_lab")]
        how = f"the ordinate axis labels ({raw[0]!r} over {raw[1] or 'N, assumed'!r})"
        unit = f"{num}/{den or 'n'}".replace("/n", "/N").replace("/kn", "/kN")
        return form, k / kf, {"unit_in_file": unit, "to_si": k / kf, "from": how}
    if not spec:
        raise DataFormatError(f"{where}: the FRFs say neither their ordinate type (12, 11, 8) nor their unit; "
                              "allowed: an ordinate type or a unit label such as g, m/s^2, mm/s")
    form = _FORM_OF_SPEC[spec]
    if units164:
        try:
            lf, ff = float(units164.get("length")), float(units164.get("force"))
        except (TypeError, ValueError):
            raise DataFormatError(f"{where}: unit record (dataset 164) without length and force factors") from None
        if not (lf > 0 and ff > 0):
            raise DataFormatError(f"{where}: unit record (dataset 164) has factors {lf:g}, {ff:g}; allowed: > 0")
        k = ff / lf ** _FORM_LENGTH[form]  # file units → SI: divide by the factor (dataset 164's rule)
        desc = str(units164.get("units_description", "")).strip() or f"code {units164.get('units_code')}"
        return form, k, {"unit_in_file": desc, "to_si": k,
                         "from": f"the unit record (dataset 164: length factor {lf:g}, force factor {ff:g})"}
    return form, 1.0, {"unit_in_file": FORM_UNITS[form], "to_si": 1.0,
                       "from": "assumed SI: the file names no unit (no ordinate label, no dataset 164)"}
