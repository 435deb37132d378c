"""The conventions every stage shares, defined once: FRF forms and their units, branches.

FRF forms
---------
An FRF is one of three forms (the field's vocabulary, as in sdypy-EMA's ``frf_form``):

* **accelerance** — acceleration per force, m/s²/N; the form of the records (accelerometers)
  and the modal stage's internal form;
* **mobility** — velocity per force, m/s/N: accelerance divided by iω;
* **receptance** — displacement per force, m/N: accelerance divided by −ω².

:data:`FORM_POWER` is the power q of iω that takes receptance to the form
(H_form = (iω)^q H_receptance), the exponent of the LSFD basis
(:mod:`tiremodal_cli.modal.lsfd`). :data:`FORM_UNITS` are the units as files write them
(ASCII, the FRF file's ``units`` attribute and UFF labels); :data:`FORM_UNITS_DISPLAY` as
figures and pages show them.

Branches
--------
A tyre's mode of circumferential order n ≥ 1 lies on one of two branches of the model
(:mod:`tiremodal_cli.tyre.model`), read from the relative phase of the sidewall and tread
(:mod:`tiremodal_cli.modal.classify`): :data:`SAME` (in phase, ω₁) or :data:`OPPOSITE`
(out of phase, ω₂); :data:`BRANCHES` lists them in that order (the model's column order).
"""

from __future__ import annotations

__all__ = ["ACCELERANCE", "MOBILITY", "RECEPTANCE", "FRF_FORMS", "FORM_POWER", "FORM_UNITS",
           "FORM_UNITS_DISPLAY", "SAME", "OPPOSITE", "BRANCHES"]

ACCELERANCE, MOBILITY, RECEPTANCE = "accelerance", "mobility", "receptance"
#: the FRF forms, the records' own (accelerance) first
FRF_FORMS = (ACCELERANCE, MOBILITY, RECEPTANCE)
#: power q of iω in H_form = (iω)^q H_receptance
FORM_POWER = {RECEPTANCE: 0, MOBILITY: 1, ACCELERANCE: 2}
#: SI unit of each form, as files write it (ASCII)
FORM_UNITS = {ACCELERANCE: "m/s^2/N", MOBILITY: "m/s/N", RECEPTANCE: "m/N"}
#: SI unit of each form, as figures show it
FORM_UNITS_DISPLAY = {ACCELERANCE: "m/s²/N", MOBILITY: "m/s/N", RECEPTANCE: "m/N"}

SAME, OPPOSITE = "same", "opposite"
#: the model's two branches of a circumferential order n ≥ 1 (its column order)
BRANCHES = (SAME, OPPOSITE)
