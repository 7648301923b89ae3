"""Design factors as dotted paths into the micro parameters, checked against the engine's registry.

A factor is either a scalar ``MicroParameters`` field (``friction_pp``, ``clump_aspect_ratio``) or an
effect parameter ``effects.<effect>.<parameter>`` (``effects.rolling_epsd2.rolling_friction``), so an
effect's strength can be a design factor like any other. ``apply`` writes values into a plain
parameter dict; ``check_factor`` refuses a name the engine does not know, naming what it knows.
"""
from __future__ import annotations

import copy
from typing import Any, Mapping

from engine.effects import REGISTRY
from engine.lab.spec import MicroParameters

SCALAR_FIELDS = tuple(n for n in MicroParameters.model_fields if n != "effects")


def check_factor(name: str) -> str:
    """``name`` if it is a scalar micro parameter or a registered effect's parameter, else ValueError."""
    if name in SCALAR_FIELDS:
        return name
    parts = name.split(".")
    if len(parts) == 3 and parts[0] == "effects":
        effect = REGISTRY.get(parts[1])
        if effect is None:
            raise ValueError(f"unknown effect {parts[1]!r} in factor {name!r}; known effects: {sorted(REGISTRY)}")
        if parts[2] not in effect.params_model.model_fields:
            raise ValueError(f"effect {parts[1]!r} has no parameter {parts[2]!r}; its parameters: "
                             f"{sorted(effect.params_model.model_fields)}")
        return name
    raise ValueError(f"factor {name!r} is neither a micro parameter ({', '.join(SCALAR_FIELDS)}) nor "
                     "'effects.<effect>.<parameter>'")


def upper_limit(name: str) -> float:
    """The largest value the engine accepts for a factor (its pydantic ``le``/``lt``), or inf."""
    import math

    from annotated_types import Le, Lt

    parts = check_factor(name).split(".")
    model = MicroParameters if len(parts) == 1 else REGISTRY[parts[1]].params_model
    info = model.model_fields[parts[-1]]
    limit = math.inf
    for m in info.metadata:
        if isinstance(m, Le):
            limit = min(limit, float(m.le))
        elif isinstance(m, Lt):
            limit = min(limit, float(m.lt))
    return limit


def typical_range(name: str) -> tuple[float, float] | None:
    """(low, high) where a scalar micro parameter's values usually lie (its field's ``Typical``,
    ``engine.lab.bounds``: friction coefficients 0.1-1.0, thesis Table 4.4; contact stiffnesses 1e4-1e10
    N/m; grain densities 800-8,000 kg/m3), or None for an effect's parameter or a field without one."""
    from engine.lab.bounds import Typical

    if check_factor(name) not in SCALAR_FIELDS:
        return None
    typical = next((m for m in MicroParameters.model_fields[name].metadata if isinstance(m, Typical)), None)
    return None if typical is None else (float(typical.low), float(typical.high))


def apply(base: Mapping[str, Any], values: Mapping[str, float]) -> dict[str, Any]:
    """A copy of the parameter dict ``base`` with each dotted factor set to its value."""
    out = copy.deepcopy(dict(base))
    for name, value in values.items():
        parts = check_factor(name).split(".")
        if len(parts) == 1:
            out[name] = float(value)
        else:
            effects = out.setdefault("effects", {})
            effects.setdefault(parts[1], {})[parts[2]] = float(value)
    return out


def read(parameters: Mapping[str, Any], name: str, default: float | None = None) -> float | None:
    """The value of a dotted factor in a parameter dict (``default`` where it is not set)."""
    parts = check_factor(name).split(".")
    if len(parts) == 1:
        value = parameters.get(name)
        return default if value is None else float(value)
    value = (parameters.get("effects") or {}).get(parts[1], {}).get(parts[2])
    return default if value is None else float(value)


def without_effect(parameters: Mapping[str, Any], effect: str) -> dict[str, Any]:
    out = copy.deepcopy(dict(parameters))
    (out.get("effects") or {}).pop(effect, None)
    return out
