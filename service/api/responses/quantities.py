"""The catalogue of lab tests' quantities: units accepted on input and physical bounds."""
from __future__ import annotations

from pydantic import Field, RootModel

from service.api.responses.common import Out


class Bounds(Out):
    """The interval a measured value must lie in (SI); an infinite end is null."""

    low: float | None
    high: float | None
    low_inclusive: bool
    high_inclusive: bool
    why: str


class QuantityInfo(Out):
    si_unit: str
    accepted_units: list[str] = Field(description="units a measurement may be entered in")
    bounds: Bounds


class Quantities(RootModel[dict[str, dict[str, QuantityInfo]]]):
    """Per lab test, per quantity: its SI unit, the units accepted on input and its physical bounds."""
