"""Pydantic schemas of the materials API (kept apart from the ORM rows)."""
from __future__ import annotations

import math
from typing import Annotated, Any

from pydantic import BaseModel, Field, ValidationInfo, field_validator

from service.api.responses.common import Page

from engine.lab.bounds import CONDITION_BOUNDS, check_finite_tree
from engine.lab.spec import STRICT_INPUT
from engine.lab.whole_number import bounded_whole_number
from engine.lab.registry import known_quantity, known_test, quantity
from service.errors import Invalid
from engine.lab.units import UnitError, condition_si_unit, to_si
from engine.particles.description import Particles

# Replicates of one measurement: a laboratory series, not a data dump (each value is stored and returned
# with every listing of the material).
MAX_REPLICATES = 1000
MAX_TEXT = 10_000


ReplicateCount = bounded_whole_number(1, MAX_REPLICATES)

class MeasurementIn(BaseModel):
    """A measurement as a user sends it: any accepted unit, converted to SI on validation."""

    model_config = STRICT_INPUT

    test: str = Field(..., max_length=32, description="a test that reports quantities (GET /api/v1/tests)")
    quantity: str = Field(..., max_length=64,
                          description="canonical quantity name of the test, with its SI unit and physical bounds "
                                      "(GET /api/v1/tests; engine.lab.registry)")
    unit: str | None = Field(None, max_length=16, description="unit of `values`; default the quantity's SI unit")
    values: list[float] = Field(..., min_length=1, max_length=MAX_REPLICATES,
                                description="replicate values (at least one), each within the quantity's bounds")
    condition: dict[str, float] = Field(default_factory=dict, max_length=8,
                                        description="test condition, e.g. normal_stress_pa")
    condition_units: dict[str, Annotated[str, Field(max_length=16)]] = Field(
        default_factory=dict, max_length=8,
        description="unit per condition entry when not SI, e.g. {'normal_stress_pa': 'kPa'}",
    )
    reported_replicates: ReplicateCount | None = Field(
        None, description="replicates behind a published average")
    standard_uncertainty: float | None = Field(None, gt=0, description="stated standard uncertainty, in `unit`")
    source: str = Field("", max_length=MAX_TEXT)

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
        declared = quantity(self.test, self.quantity)
        si_unit = declared.unit
        unit = self.unit or si_unit
        try:
            values = [to_si(v, unit, si_unit) for v in self.values]
            uncertainty = None if self.standard_uncertainty is None else to_si(self.standard_uncertainty, unit, si_unit)
        except UnitError as exc:
            raise FieldError("unit", str(exc)) from exc
        # Bounds apply in SI, after conversion: 1e300 GPa overflows to infinity here, not in a listing.
        bound = declared.bound
        for index, value in enumerate(values):
            try:
                bound.check(value, f"{self.test} {self.quantity} [{si_unit}]")
            except ValueError as exc:
                raise FieldError(f"values.{index}", str(exc)) from None
        if uncertainty is not None and not math.isfinite(uncertainty):
            raise FieldError("standard_uncertainty", "standard_uncertainty must be finite in SI units")
        condition: dict[str, float] = {}
        for name, value in self.condition.items():
            try:
                si = condition_si_unit(name)
                condition[name] = to_si(value, self.condition_units.get(name, si), si)
            except UnitError as exc:
                raise FieldError(f"condition.{name}", str(exc)) from exc
            try:
                CONDITION_BOUNDS[si].check(condition[name], f"condition {name} [{si}]")
            except ValueError as exc:
                raise FieldError(f"condition.{name}", str(exc)) from None
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
    model_config = STRICT_INPUT

    name: str = Field(..., min_length=1, max_length=200)
    description: str = Field("", max_length=MAX_TEXT)
    source: str = Field("", max_length=MAX_TEXT)
    direct_estimates: dict[str, Any] = Field(
        default_factory=dict, max_length=100,
        description="parameters measured directly (JSON; numbers finite), e.g. "
                    "{'particle_density_kg_m3': {'value': 2586.5, 'source': '...'}}",
    )
    rig: str | None = Field(None, min_length=1, max_length=200,
                            description="name of the rig (GET /api/v1/rigs) every measurement of the material was made "
                                        "in; unset: not stated")
    particles: Particles | None = Field(None, description="what the material is made of: size distribution, solid "
                                                          "density, shapes (engine.particles.description)")
    measurements: list[MeasurementIn] = Field(default_factory=list, max_length=1000)

    @field_validator("direct_estimates")
    @classmethod
    def _finite_estimates(cls, estimates: dict[str, Any]) -> dict[str, Any]:
        """Free-form JSON, but without NaN or infinities: stored, they would come back as null."""
        check_finite_tree(estimates)
        return estimates


class MeasurementOut(BaseModel):
    """Numbers are null only in rows stored before validation existed (non-finite values)."""

    id: int
    material_id: int
    test: str
    quantity: str
    condition: dict[str, float | None]
    unit: str
    values: list[float | None]
    n: int
    reported_replicates: int | None
    mean: float | None
    standard_uncertainty: float | None
    input_unit: str
    source: str
    created_at: str | None
    warnings: list[str] = Field(default_factory=list,
                                description="the value or a condition outside what granular materials measure, "
                                            "with the unit slip it probably is (engine.lab.plausibility); "
                                            "stored all the same, and repeated in the reports that use it")


class MaterialOut(BaseModel):
    id: int
    name: str
    description: str
    source: str
    bundled: bool
    owner: str | None = Field(None, description="the user (bearer token name) who made it; null when made without a token")
    direct_estimates: dict[str, Any]
    rig_id: int | None = Field(None, description="the rig the measurements were made in")
    rig: str | None = Field(None, description="that rig's name")
    particles: dict[str, Any] | None = Field(None, description="the particles (engine.particles.description)")
    warnings: list[str] = Field(default_factory=list,
                                description="the rig too small for the particles (direct-shear standards' sizes)")
    measurements: list[MeasurementOut]
    created_at: str


class MaterialCopy(BaseModel):
    model_config = STRICT_INPUT

    name: str = Field(..., min_length=1, max_length=200, description="name of the editable copy")


class MaterialList(Page):
    """A page of materials, by id (the bundled one first)."""

    items: list[MaterialOut]


class MeasurementList(Page):
    """A page of a material's measurements, by id."""

    items: list[MeasurementOut]
