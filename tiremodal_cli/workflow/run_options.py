"""What ``run`` is told (its options) and what it writes (the outputs, the manifest's name).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

from tiremodal_cli.conventions import FRF_FORMS
from tiremodal_cli.errors import ParameterError
from tiremodal_cli.io.files import dumps

__all__ = ['OUTPUTS', 'MODES_OUTPUTS', 'MANIFEST', 'RunOptions', 'json_text', 'required_outputs']


OUTPUTS = ("frf.h5", "modal.h5", "modes.csv", "identify.json", "diagnosis.json", "sensitivity.json")
#: what ``run`` writes for a table of measured modes (it starts at identify: no records, no frf.h5, no modal.h5)
MODES_OUTPUTS = ("modes.csv", "identify.json", "diagnosis.json", "sensitivity.json")


def required_outputs(man: dict) -> tuple[str, ...]:
    """The outputs a run folder's manifest must list: :data:`MODES_OUTPUTS` for a run that
    started at identify (a table of modes), else :data:`OUTPUTS`."""
    s = man.get("summary") if isinstance(man, dict) else None
    return MODES_OUTPUTS if isinstance(s, dict) and s.get("starts_at") == "identify" else OUTPUTS


MANIFEST = "run.json"


@dataclass(frozen=True)
class RunOptions:
    """Defaults of every stage (fractions of the sample rate fs where marked).

    frf_top : FRFs up to frf_top × fs (1/2.56 = 0.390625: an analyser's usable bandwidth under its
        anti-alias filter; the lsce band then ends where the coherence and force fail)
    band : lsce band (Hz); default: where the coherence and the force spectrum support the
        estimate (:func:`tiremodal_cli.modal.band.default_band`, its reason in the modal file)
    exp_end : exponential window's value at the record's end (its damping is corrected)
    predict_n : predictions (and sensitivities) reach at least this order, and always two
        beyond the highest measured one
    seed : seed of every evolutionary search
    pressure_from_file : the model's inflation pressure P0 is the one the measurement
        records (when it records one), not the nominal parameters' — a campaign over
        pressures is then fitted at each test's own pressure
    form : FRF form the modal stage works on: "accelerance" (what accelerometers give),
        "mobility" or "receptance" — the modes should not depend on it
    """
    frf_top: float = 1 / 2.56
    band: tuple[float, float] | None = None
    exp_end: float | None = 0.05
    seed: int = 0
    noise_floor_pct: float = 0.1
    max_effects: int = 2
    predict_n: int = 12
    pressure_from_file: bool = True
    form: str = "accelerance"

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_mapping(cls, d: dict, where: str = "options") -> "RunOptions":
        """RunOptions from a config table (``[run]`` of a campaign file); ``exp_end = false``
        means no exponential window. Unknown keys and bad values raise ParameterError."""
        names = [f.name for f in fields(cls)]
        unknown = sorted(set(d) - set(names))
        if unknown:
            raise ParameterError(f"{where}: unknown option {unknown[0]!r}; allowed: {', '.join(names)}")
        kw = dict(d)

        def bad(k, allowed):
            return ParameterError(f"{where}: {k} = {d[k]!r} is not allowed; allowed: {allowed}")

        def number(k, ok, allowed):
            v = kw[k]
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not ok(v):
                raise bad(k, allowed)
            return float(v)

        if kw.get("band") is not None:
            v = kw["band"]
            if (not isinstance(v, (list, tuple)) or len(v) != 2
                    or any(isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x) for x in v)
                    or not 0 <= v[0] < v[1]):
                raise bad("band", "[LO, HI] in Hz (band needs 0 ≤ LO < HI)")
            kw["band"] = (float(v[0]), float(v[1]))
        if "exp_end" in kw:
            if kw["exp_end"] is False or kw["exp_end"] is None:
                kw["exp_end"] = None
            else:
                kw["exp_end"] = number("exp_end", lambda x: 0 < x < 1, "a number in (0, 1), or false for no window")
        if "frf_top" in kw:
            kw["frf_top"] = number("frf_top", lambda x: 0 < x <= 0.5, "a fraction of the sample rate in (0, 0.5]")
        if "noise_floor_pct" in kw:
            kw["noise_floor_pct"] = number("noise_floor_pct", lambda x: 0 < x <= 100, "a percentage in (0, 100]")
        if "form" in kw and kw["form"] not in FRF_FORMS:
            raise bad("form", ", ".join(FRF_FORMS))
        if "pressure_from_file" in kw and not isinstance(kw["pressure_from_file"], bool):
            raise bad("pressure_from_file", "true or false")
        for k, lo, hi in (("seed", None, None), ("max_effects", 0, 5), ("predict_n", 1, 100)):
            if k in kw:
                v = kw[k]
                if (isinstance(v, bool) or not isinstance(v, int) or (lo is not None and not lo <= v <= hi)):
                    raise bad(k, "an integer" + (f" in {lo}…{hi}" if lo is not None else ""))
        return cls(**kw)


def json_text(obj) -> str:
    return dumps(obj)
