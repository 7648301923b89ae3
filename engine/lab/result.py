"""Result record of a virtual laboratory test or battery.

The record is the contract between the virtual lab, the service (which stores
it as JSON) and the calibration loop (which matches measurements to simulated
values one to one by ``(test, quantity, condition)``). Everything is SI.
"""
from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

# Canonical quantity names per test. Measurements and simulated values meet on
# these names, so they are listed once here and nowhere else.
QUANTITIES: dict[str, dict[str, str]] = {
    "fill": {
        "bulk_density_kg_m3": "kg/m3",
        "porosity": "1",
        "voids_ratio": "1",
        "packing_height_m": "m",
        "bulk_mass_kg": "kg",
        "particle_count": "1",
    },
    "cct": {
        "confined_modulus_pa": "Pa",
        "bulk_stiffness_n_per_m": "N/m",
    },
    "dst": {
        "residual_shear_stress_pa": "Pa",
        "dilatancy_angle_deg": "deg",
        "friction_angle_deg": "deg",
        "cohesion_pa": "Pa",
        "mohr_coulomb_r2": "1",
    },
    "aor": {"angle_of_repose_deg": "deg"},
    "anchor": {"peak_pull_force_n": "N"},
}


def known_test(test: str) -> str:
    """The test name if QUANTITIES has it; else a ValueError listing the names (API 422 messages)."""
    if test not in QUANTITIES:
        raise ValueError(f"unknown test {test!r}; one of {sorted(QUANTITIES)}")
    return test


def known_quantity(test: str | None, quantity: str) -> str:
    """The quantity if ``test`` reports it (``test`` None: its own error was raised already)."""
    if test is not None and quantity not in QUANTITIES[test]:
        raise ValueError(f"quantity {quantity!r} is not reported by {test!r}; one of {sorted(QUANTITIES[test])}")
    return quantity


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
    fidelity: str
    engine_version: str
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
