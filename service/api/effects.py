"""The effect catalogue: every contact effect the engine knows, and what the diagnosis knows of it.

Why an endpoint: users pick effects by registry name in jobs, campaigns and iterations, and the
diagnosis ranks them by the same name; the catalogue is where they learn what each name means,
its parameters with units and bounds, its plausible range and the fingerprint it leaves.
"""
from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from engine.candidates import candidates
from engine.effects import REGISTRY
from service.api.responses.common import typed
from service.api.responses.effects import Effects

router = APIRouter(tags=["effects"])


def _parameters(effect) -> list[dict[str, Any]]:
    schema = effect.params_model.model_json_schema()
    required = set(schema.get("required", []))
    out = []
    for name, prop in schema.get("properties", {}).items():
        out.append({"name": name, "required": name in required, "default": prop.get("default"),
                    "description": prop.get("description", ""),
                    **{k: prop[k] for k in ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum")
                       if k in prop}})
    return out


def _candidate(c) -> dict[str, Any]:
    return {"name": c.name, "title": c.title, "factor": c.factor, "unit": c.unit,
            "plausible_range": list(c.plausible_range), "step": c.step, "switch": c.is_switch,
            "off_value": c.off_value, "fingerprint": dict(c.fingerprint), "physics": c.physics,
            "revealed_by": [{"test": t, "quantity": q, "how": how} for t, q, how in c.revealed_by]}


@router.get("/effects", **typed(Effects),
            summary="Every contact effect and diagnosis candidate: physics, parameters, ranges, fingerprint")
def list_effects() -> dict[str, Any]:
    cands = candidates()
    effects = []
    for name, effect in REGISTRY.items():
        effects.append({"name": name, "stage": effect.stage, "description": (effect.doc or "").strip(),
                        "parameters": _parameters(effect),
                        "candidate": _candidate(cands[name]) if name in cands else None})
    shape = [_candidate(c) for n, c in cands.items() if n not in REGISTRY]
    return {"effects": effects, "other_candidates": shape}
