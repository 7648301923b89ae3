"""The effect catalogue: every contact effect and what the diagnosis knows of it."""
from __future__ import annotations

from typing import Any

from pydantic import Field

from service.api.responses.common import Out


class EffectParameter(Out):
    name: str
    required: bool
    default: Any = None
    description: str
    minimum: int | float | None = None  # as the parameter's JSON schema states it
    maximum: int | float | None = None  # as the parameter's JSON schema states it
    exclusiveMinimum: int | float | None = None  # as the parameter's JSON schema states it
    exclusiveMaximum: int | float | None = None  # as the parameter's JSON schema states it


class RevealingMeasurement(Out):
    test: str
    quantity: str
    how: str = Field(description="at which conditions, for people")


class Candidate(Out):
    """What the diagnosis knows of an effect (engine.candidates)."""

    name: str
    title: str
    factor: str = Field(description="the micro-parameter path of its strength")
    unit: str
    plausible_range: list[float] = Field(description="[low, high], in the unit")
    step: float = Field(description="the secant step of its diagnosis battery, in the unit")
    switch: bool = Field(description="on or off, matched at a strength rather than stepped")
    off_value: float | None
    fingerprint: dict[str, str] = Field(description="per measured feature: the sign of the change it makes")
    physics: str
    revealed_by: list[RevealingMeasurement] = Field(
        default_factory=list, description="the measurements that would show it where the measured ones cannot")


class Effect(Out):
    name: str
    stage: str = Field(description="where in the contact law it acts")
    description: str
    parameters: list[EffectParameter]
    candidate: Candidate | None


class Effects(Out):
    """GET /effects."""

    effects: list[Effect]
    other_candidates: list[Candidate] = Field(description="diagnosis candidates that are not contact effects")
