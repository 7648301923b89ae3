"""The lab-test catalogue: every test the virtual lab runs, read from ``engine.lab.registry``.

Why an endpoint: jobs and campaigns name a test, measurements a test and a quantity; the page, the CLI and
scripts learn here which names exist, what each test reports (SI unit, physical bounds, typical range,
conditions), which options it reads, what it needs first and how the battery is composed, instead of each
keeping its own list.
"""
from __future__ import annotations

from fastapi import APIRouter
from pydantic import BaseModel, Field

from engine.lab.bounds import Bound
from engine.lab.registry import ALWAYS, BATTERY, NEVER, LabTest, Quantity, job_test_names, tests
from service.api.jsonsafe import json_safe
from engine.lab.units import accepted_units

router = APIRouter(tags=["tests"])


class BoundsOut(BaseModel):
    """The interval a value must lie in (SI); an infinite end is null."""

    low: float | None
    high: float | None
    low_inclusive: bool
    high_inclusive: bool
    why: str


class TypicalOut(BaseModel):
    """Where granular materials usually measure (SI, closed): outside, a value is stored with a warning."""

    low: float
    high: float
    what: str = Field(description="the population the range describes")
    source: str = Field(description="short reference; docs/lab.md, 'Plausible ranges', has the full one")


class QuantityOut(BaseModel):
    name: str
    si_unit: str
    accepted_units: list[str] = Field(description="units a measurement may be sent in (converted to SI)")
    bounds: BoundsOut
    typical: TypicalOut | None = Field(description="the typical range; null where the apparatus sets the value")
    conditions: list[str] = Field(description="condition names the value is reported under, besides none")
    description: str


class LabTestOut(BaseModel):
    name: str
    title: str
    description: str
    quantities: list[QuantityOut]
    options: list[str] = Field(description="TestOptions fields the test reads")
    needs: list[str] = Field(description="tests run first because this one starts from their outcome")
    battery: str = Field(description="'always', 'never', or the TestOptions switch that adds it to a battery")
    procedure: str
    reducer: str


class BatteryOut(BaseModel):
    name: str
    always: list[str] = Field(description="tests every battery runs, in run order")
    optional: dict[str, str] = Field(description="test -> the TestOptions switch that adds it")


class TestCatalogue(BaseModel):
    job_tests: list[str] = Field(description="what a job's or campaign's `test` accepts")
    tests: list[LabTestOut]
    battery: BatteryOut


def bounds_out(bound: Bound) -> BoundsOut:
    return BoundsOut(low=json_safe(bound.low), high=json_safe(bound.high), low_inclusive=not bound.low_open,
                     high_inclusive=not bound.high_open, why=bound.why)


def quantity_out(q: Quantity) -> QuantityOut:
    typical = None if q.typical is None else TypicalOut(low=q.typical.low, high=q.typical.high, what=q.typical.what,
                                                        source=q.typical.source)
    return QuantityOut(name=q.name, si_unit=q.unit, accepted_units=accepted_units(q.unit), bounds=bounds_out(q.bound),
                       typical=typical, conditions=list(q.conditions), description=q.description)


def _test_out(t: LabTest) -> LabTestOut:
    return LabTestOut(name=t.name, title=t.title, description=t.description,
                      quantities=[quantity_out(q) for q in t.quantities], options=list(t.options),
                      needs=list(t.needs), battery=t.battery, procedure=t.procedure, reducer=t.reducer)


@router.get("/tests", response_model=TestCatalogue,
            summary="Every lab test: quantities with SI units and bounds, options, prerequisites, the battery")
def list_tests() -> TestCatalogue:
    table = tests()
    return TestCatalogue(
        job_tests=job_test_names(),
        tests=[_test_out(t) for t in table.values()],
        battery=BatteryOut(name=BATTERY, always=[n for n, t in table.items() if t.battery == ALWAYS],
                           optional={n: t.battery for n, t in table.items() if t.battery not in (ALWAYS, NEVER)}),
    )
