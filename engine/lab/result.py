"""Result record of a virtual laboratory test or battery.

The record is the contract between the virtual lab, the service (which stores
it as JSON) and the calibration loop (which matches measurements to simulated
values one to one by ``(test, quantity, condition)``). Everything is SI. The quantity names and units
each test reports are declared with the test (``engine.lab.registry``).
"""
from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field


class BulkProperty(BaseModel):
    """One simulated bulk property, keyed like a measurement."""

    test: str
    quantity: str
    value: float
    unit: str
    condition: dict[str, float] = Field(
        default_factory=dict,
        description="Test condition, SI, e.g. {'normal_stress_pa': 24000.0}",
    )

    def key(self) -> tuple[str, str, tuple[tuple[str, float], ...]]:
        return (self.test, self.quantity, tuple(sorted(self.condition.items())))


class Provenance(BaseModel):
    parameters: dict[str, Any]
    seed: int
    fidelity: str  # the preset's name, or the resolution ("as_measured", "coarse"): engine.lab.resolution.label
    engine_version: str
    rig: str | None = None  # the rig the job ran in (None: results stored before rigs were data)
    scale_factor: float = 1.0  # particle sizes over the material's (a coarse resolution's factor)
    steps: int = 0
    simulated_time_s: float = 0.0
    wall_time_s: float = 0.0
    max_inertial_number: float | None = None
    warnings: list[str] = Field(default_factory=list)


class LabResult(BaseModel):
    """Scalars, the curves behind them, and how they were obtained."""

    test: str
    properties: list[BulkProperty]
    curves: dict[str, dict[str, list[float]]] = Field(
        default_factory=dict,
        description="Named curves, each a dict of equal-length columns (SI).",
    )
    provenance: Provenance

    def value(self, test: str, quantity: str, **condition: float) -> float:
        for prop in self.properties:
            if prop.test == test and prop.quantity == quantity and all(
                abs(prop.condition.get(k, float("nan")) - v) <= 1e-9 * max(1.0, abs(v))
                for k, v in condition.items()
            ):
                return prop.value
        raise KeyError(f"no property {test}/{quantity} with condition {condition}")


class Cancelled(Exception):
    """Raised by a running test when its ``should_cancel`` callback answers True."""
