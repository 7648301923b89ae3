"""Pydantic schemas of the materials API (kept apart from the ORM rows)."""
from __future__ import annotations

import math
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator

from engine.lab.result import QUANTITIES, known_quantity, known_test
from service.errors import Invalid
from service.materials.units import UnitError, condition_si_unit, to_si


class MeasurementIn(BaseModel):
    """A measurement as a user sends it: any accepted unit, converted to SI on validation."""

    model_config = ConfigDict(extra="forbid")

    test: str = Field(..., description=f"one of {sorted(QUANTITIES)}")
    quantity: str = Field(..., description="canonical quantity name of the test (engine.lab.result.QUANTITIES)")
    unit: str | None = Field(None, description="unit of `values`; default the quantity's SI unit")
    values: list[float] = Field(..., min_length=1, description="replicate values (at least one)")
    condition: dict[str, float] = Field(default_factory=dict, description="test condition, e.g. normal_stress_pa")
    condition_units: dict[str, str] = Field(
        default_factory=dict, description="unit per condition entry when not SI, e.g. {'normal_stress_pa': 'kPa'}"
    )
    reported_replicates: int | None = Field(None, ge=1, description="replicates behind a published average")
    standard_uncertainty: float | None = Field(None, gt=0, description="stated standard uncertainty, in `unit`")
    source: str = ""

    @field_validator("test")
    @classmethod
    def _known_test(cls, test: str) -> str:
        return known_test(test)

    @field_validator("values")
    @classmethod
    def _finite(cls, values: list[float]) -> list[float]:
        if not all(math.isfinite(v) for v in values):
            raise ValueError("values must be finite numbers")
        return values

    @field_validator("quantity")
    @classmethod
    def _check_quantity(cls, quantity: str, info: ValidationInfo) -> str:
        return known_quantity(info.data.get("test"), quantity)

    def to_si(self) -> dict[str, Any]:
        """SI fields for the ORM row; UnitError names the offending field in its args."""
        si_unit = QUANTITIES[self.test][self.quantity]
        unit = self.unit or si_unit
        try:
            values = [to_si(v, unit, si_unit) for v in self.values]
            uncertainty = None if self.standard_uncertainty is None else to_si(self.standard_uncertainty, unit, si_unit)
        except UnitError as exc:
            raise FieldError("unit", str(exc)) from exc
        condition: dict[str, float] = {}
        for name, value in self.condition.items():
            try:
                si = condition_si_unit(name)
                condition[name] = to_si(value, self.condition_units.get(name, si), si)
            except UnitError as exc:
                raise FieldError("condition", str(exc)) from exc
            if not math.isfinite(condition[name]):
                raise FieldError("condition", f"condition {name!r} must be finite")
        for name in self.condition_units:
            if name not in self.condition:
                raise FieldError("condition_units", f"{name!r} is not in condition")
        return {
            "test": self.test, "quantity": self.quantity, "unit": si_unit, "values": values,
            "condition": condition, "reported_replicates": self.reported_replicates,
            "stated_uncertainty": uncertainty, "input_unit": unit, "source": self.source,
        }


class FieldError(Invalid):
    """Bad input found after pydantic validation (units); rendered as a 422 naming ``field``."""

    def __init__(self, field: str, message: str):
        super().__init__(message, field)


class MaterialIn(BaseModel):
    model_config = ConfigDict(extra="forbid")

    name: str = Field(..., min_length=1, max_length=200)
    description: str = ""
    source: str = ""
    direct_estimates: dict[str, Any] = Field(default_factory=dict)
    measurements: list[MeasurementIn] = Field(default_factory=list)


class MeasurementOut(BaseModel):
    id: int
    material_id: int
    test: str
    quantity: str
    condition: dict[str, float]
    unit: str
    values: list[float]
    n: int
    reported_replicates: int | None
    mean: float
    standard_uncertainty: float | None
    input_unit: str
    source: str
    created_at: str | None


class MaterialOut(BaseModel):
    id: int
    name: str
    description: str
    source: str
    bundled: bool
    direct_estimates: dict[str, Any]
    measurements: list[MeasurementOut]
    created_at: str
