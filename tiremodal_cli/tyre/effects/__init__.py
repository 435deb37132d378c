"""Candidate physical effects beyond the seed model of ``docs/model.md``.

Each effect is one small module in this package that defines a module-level ``EFFECT``
(an :class:`Effect`): its name, its parameters with units and bounds, and how it changes
the model. Adding an effect is adding one module; nothing else changes. The registry is
built by scanning this package, so a new module is found without being listed anywhere.

An effect acts through one or more of three hooks:

``modify_block(n, block, values, p, freq_hz)``
    Change the per-length block of circumferential order ``n`` (mass, stiffness,
    degrees of freedom). ``freq_hz`` is given for frequency-dependent effects. The hook
    must also take a stack: ``n`` a (k,) int array, ``block.M``/``block.K`` (k, d, d)
    arrays and ``freq_hz`` None or a (k,) array (index with ``K[..., i, j]``), and then
    the fields of ``p`` and the ``values`` may be (k,) arrays too (one parameter set per
    stacked block: a whole optimiser population evaluated at once, see
    :class:`tiremodal_cli.tyre.model.ParamStack`). Blocks of n = 1 come alone or in a stack
    of their own, so an effect that adds a degree of freedom there (the air cavity)
    leaves stacks of other orders as they are.
``couple(M, K, dofs, values)``
    Add terms that couple different orders or harmonics (a lumped mass), acting on the
    assembled generalised matrices (kg, N/m).
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

from tiremodal_cli.errors import ParameterError

__all__ = ["Block", "Effect", "Param", "EFFECTS", "get_effect", "resolve_effects"]


@dataclass(frozen=True)
class Param:
    """One parameter of an effect: default, physical bounds, unit and meaning."""

    name: str
    default: float
    lower: float
    upper: float
    unit: str
    doc: str
    #: the upper bound is a physical limit (a fraction that cannot exceed 1), not a search
    #: limit: a fit may rest on it
    upper_is_physical: bool = False


@dataclass(frozen=True)
class Block:
    """Per-length matrices of one circumferential order.

    Attributes
    ----------
    M : (k, k) ndarray, kg/m
    K : (k, k) ndarray, N/m²
    dofs : tuple of str
        ``"U"`` tread radial, ``"S"`` sidewall radial, ``"W"`` rim translation (n = 1),
        ``"A"`` cavity acoustic coordinate (n = 1, when that effect is on).
    """

    M: "object"
    K: "object"
    dofs: tuple[str, ...]


@dataclass(frozen=True)
class Effect:
    """A candidate effect: equations (in its module), parameters and hooks."""

    name: str
    title: str
    parameters: tuple[Param, ...]
    signature: str
    modify_block: Callable | None = None
    couple: Callable | None = None
    frequency_dependent: bool = False
    kind: str = "structural"  # "structural", "acoustic" or "coupling"
    reference: str = ""
    extra: dict = field(default_factory=dict)
    #: the parameters ``diagnose`` fits (default: all); the others stay at
    #: ``diagnose_fixed`` (default: their defaults) because the data cannot see them
    diagnose_free: tuple[str, ...] | None = None
    diagnose_fixed: dict = field(default_factory=dict)

    def fitted_parameters(self) -> tuple[Param, ...]:
        """The parameters a diagnosis fits."""
        names = self.diagnose_free or tuple(p.name for p in self.parameters)
        return tuple(p for p in self.parameters if p.name in names)

    def defaults(self) -> dict[str, float]:
        return {p.name: p.default for p in self.parameters}

    def resolve(self, values: Mapping[str, float] | None) -> dict[str, float]:
        """Defaults overlaid with ``values``; unknown names and values out of bounds raise."""
        out = self.defaults()
        known = {p.name: p for p in self.parameters}
        for k, v in (values or {}).items():
            if k not in known:
                raise ParameterError(f"effect {self.name!r} has no parameter {k!r}; "
                                     f"allowed: {', '.join(known)}")
            p = known[k]
            v = float(v)
            if not p.lower <= v <= p.upper:
                raise ParameterError(f"effect {self.name!r}: {k}={v:g} {p.unit} is outside "
                                     f"[{p.lower:g}, {p.upper:g}]")
            out[k] = v
        return out


def _discover() -> dict[str, Effect]:
    found = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        if info.name.startswith("_"):
            continue
        mod = importlib.import_module(f"{__name__}.{info.name}")
        eff = getattr(mod, "EFFECT", None)
        if isinstance(eff, Effect):
            found[eff.name] = eff
    return found


EFFECTS: dict[str, Effect] = _discover()


def get_effect(name: str) -> Effect:
    try:
        return EFFECTS[name]
    except KeyError:
        raise ParameterError(f"unknown effect {name!r}; allowed: {', '.join(EFFECTS)}") from None


def resolve_effects(effects: Mapping[str, Mapping[str, float] | None] | None
                    ) -> tuple[tuple[Effect, dict[str, float]], ...]:
    """Turn ``{name: {param: value}}`` into ``((Effect, values), ...)`` in a fixed order."""
    if not effects:
        return ()
    return tuple((get_effect(k), get_effect(k).resolve(v)) for k, v in sorted(effects.items()))
