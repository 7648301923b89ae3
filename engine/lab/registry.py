"""The lab-test registry: every virtual-lab test declared once, as contact effects are (``engine/effects``).

A test's module in ``engine/lab/labtests/`` defines ``TEST = LabTest(...)``: name and title, the quantities
it reports (SI unit, physical bounds, the conditions they carry), the ``TestOptions`` it reads, what must run
first (the CCT and the DST start from the fill), its cost from its procedure's own stop rules, its procedure
and reducer, and the adapter that turns their outcome into bulk properties and curves. Everything that lists
tests or quantities reads them here: ``JobSpec.test`` and the campaign and measurement schemas, the bounds
of a measured value, the cost model (``engine.lab.cost``), the runner (``engine.lab.battery``), the CLI's
choices, ``GET /api/v1/tests`` and the page's selects. docs/lab.md, "Adding a lab test", walks through one.

The battery is the one composite: the tests declared ``battery=ALWAYS``, then those whose ``TestOptions``
switch (``include_aor``) is on, in registry order, each after what it needs.

Why the declarations load lazily: this module imports the bounds and the result record only, and a
declaration imports its procedure only when the test runs, so the spec, the API's schemas and the CLI
read the registry without loading the DEM engine.
"""
from __future__ import annotations

import importlib
import threading
from dataclasses import dataclass, field
from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated, Any

from pydantic import AfterValidator

from engine.lab.bounds import Bound, Typical
from engine.lab.result import BulkProperty

if TYPE_CHECKING:  # the context imports the spec, which imports this module
    from engine.lab.context import RunContext
    from engine.lab.spec import JobSpec, TestOptions

# Registry order is run order: a test comes after everything it needs.
_MODULES = (
    "engine.lab.labtests.fill",
    "engine.lab.labtests.cct",
    "engine.lab.labtests.dst",
    "engine.lab.labtests.aor",
    "engine.lab.labtests.anchor",
)
BATTERY = "battery"
ALWAYS = "always"  # LabTest.battery: in every battery
NEVER = "never"  # LabTest.battery: run alone only


@dataclass(frozen=True)
class Quantity:
    """One reported quantity: canonical name, SI unit, the interval a value must lie in, where granular
    materials usually lie (``typical``, None where the apparatus decides, e.g. a bulk mass), and the
    condition names it is reported under (besides the unconditioned value), e.g. normal_stress_pa."""

    name: str
    unit: str
    bound: Bound
    conditions: tuple[str, ...] = ()
    description: str = ""
    typical: Typical | None = None
    # the rig sections whose dimensions set the value (a bulk mass is the mass of that container's packing):
    # compared with a measurement only when the job's rig has the same sections (engine.lab.resolution)
    apparatus: tuple[str, ...] = ()
    # the value scales with the particles' size (a particle count): compared only when the job builds the
    # measured material's particles as they are
    per_particle: bool = False
    # the value is the rig's own number when the packing is struck off at a level (the packing height is then
    # the level, engine.lab.rigs.Fill.height_rule): nothing about the material, never a target there
    rig_value_when_struck_off: bool = False
    # the quantities of the same test and condition this one is computed from, and how (``relation``): the
    # laboratory reports it from the same weighing and reading (a porosity from the bulk density and the solid
    # density), so it is not a measurement of its own; a loop counts it once, through its sources, where they
    # are targets (calibration.comparable.once_each)
    derived_from: tuple[str, ...] = ()
    relation: str = ""
    # the TestOptions field listing the normal stresses this quantity is reported at: a measurement at a stress
    # makes the battery run it at exactly that stress (calibration.conditions.battery_options)
    stress_option: str | None = None


@dataclass(frozen=True)
class StageCost:
    """One test's share of a job's cost: ceilings from its procedure's stop rules, and the spec fields that
    lower them (``particles_field`` None: the field that put the test in the job, ``test`` or its switch)."""

    simulated_time_s: float
    time_field: str
    particles: int = 0  # spheres of the packing the test builds; 0 when it reuses another test's
    particles_field: str | None = None


@dataclass
class Run:
    """What one test leaves behind: its procedure's outcome (for the tests that start from it), its bulk
    properties and its curves."""

    outcome: Any
    properties: list[BulkProperty] = field(default_factory=list)
    curves: dict[str, dict[str, list[float]]] = field(default_factory=dict)


@dataclass
class Bench:
    """The tests of one job share the context and each other's runs (the CCT and DST reuse the fill)."""

    ctx: RunContext
    ran: dict[str, Run] = field(default_factory=dict)


@dataclass(frozen=True)
class LabTest:
    """One virtual-lab test, declared once.

    ``cost(ctx, planned)`` gives the test's ``StageCost`` for the job's context, ``planned`` the names of every
    test the job runs; ``run(bench, lo, hi)`` runs it with progress in [lo, hi) and returns its ``Run``;
    ``check(ctx)``, if given, refuses (``SpecFieldError``) what the options make impossible for this test.
    ``procedure`` and ``reducer`` are "module:function" references, served and checked, that ``run`` calls.
    """

    name: str
    title: str
    quantities: tuple[Quantity, ...]
    options: tuple[str, ...]
    procedure: str
    reducer: str
    cost: Callable[[RunContext, frozenset[str]], StageCost]
    run: Callable[[Bench, float, float], Run]
    needs: tuple[str, ...] = ()
    battery: str = NEVER  # ALWAYS, NEVER, or the TestOptions switch that adds it to a battery
    progress_weight: float = 1.0  # share of the progress bar, roughly the test's cost at screening fidelity
    check: Callable[[RunContext], None] | None = None
    description: str = ""
    # the rig sections (engine.lab.rigs) the test runs in: a job whose rig lacks one is refused naming ``rig``
    apparatus: tuple[str, ...] = ("shear_box",)

    def quantity(self, name: str) -> Quantity:
        for q in self.quantities:
            if q.name == name:
                return q
        raise ValueError(f"quantity {name!r} is not reported by {self.name!r}; one of "
                         f"{sorted(q.name for q in self.quantities)}")

    def property(self, quantity: str, value: float, **condition: float) -> BulkProperty:
        """A bulk property of this test, its unit from the declaration; an undeclared quantity or condition
        is a programming error caught on the first run, not a key no measurement can ever meet."""
        q = self.quantity(quantity)
        extra = set(condition) - set(q.conditions)
        if extra:
            raise ValueError(f"{self.name}/{quantity}: condition {sorted(extra)} not declared {q.conditions}")
        return BulkProperty(test=self.name, quantity=quantity, value=float(value), unit=q.unit,
                            condition={k: float(v) for k, v in condition.items()})


_lock = threading.Lock()
_REGISTRY: dict[str, LabTest] = {}


def _validate(test: LabTest, known: dict[str, LabTest]) -> None:
    """Refuse a declaration that would break a derivation: each rule is what some list relied on."""
    from engine.lab.spec import TestOptions

    if test.name in known or test.name == BATTERY:
        raise ValueError(f"lab test {test.name!r}: the name is taken")
    for need in test.needs:
        if need not in known:
            raise ValueError(f"lab test {test.name}: needs {need!r}, which must be registered before it")
    unknown = set(test.options) - set(TestOptions.model_fields)
    if unknown:
        raise ValueError(f"lab test {test.name}: options {sorted(unknown)} are not TestOptions fields")
    if test.battery not in (ALWAYS, NEVER) and TestOptions.model_fields.get(test.battery) is None:
        raise ValueError(f"lab test {test.name}: battery switch {test.battery!r} is not a TestOptions field")
    names = [q.name for q in test.quantities]
    if not names or len(set(names)) != len(names):
        raise ValueError(f"lab test {test.name}: quantities must be named once each")
    for q in test.quantities:
        # a quantity measured at a stress must name the option that makes the battery report it there
        if ("normal_stress_pa" in q.conditions) != (q.stress_option is not None) \
                or (q.stress_option is not None and q.stress_option not in test.options):
            raise ValueError(f"lab test {test.name}: {q.name} is reported at a normal stress only through one of "
                             f"the test's options (stress_option), got {q.stress_option!r}")
    if not test.progress_weight > 0:
        raise ValueError(f"lab test {test.name}: progress_weight must be positive")


def tests() -> dict[str, LabTest]:
    """Every lab test by name, in run order (declarations are imported on the first call)."""
    if not _REGISTRY:
        with _lock:
            if not _REGISTRY:
                loaded: dict[str, LabTest] = {}
                for module in _MODULES:
                    test = importlib.import_module(module).TEST
                    _validate(test, loaded)
                    loaded[test.name] = test
                _REGISTRY.update(loaded)
    return _REGISTRY


def get(name: str) -> LabTest:
    table = tests()
    try:
        return table[name]
    except KeyError:
        raise ValueError(f"unknown test {name!r}; one of {sorted(table)}") from None


def job_test_names() -> list[str]:
    """What ``JobSpec.test`` accepts: the battery, then every test alone."""
    return [BATTERY, *tests()]


def battery_members(options: TestOptions) -> list[LabTest]:
    return [t for t in tests().values()
            if t.battery == ALWAYS or (t.battery != NEVER and bool(getattr(options, t.battery)))]


def requested(spec: JobSpec) -> list[LabTest]:
    """The tests whose properties the job reports."""
    return reported_by(spec.test, spec.options)


def reported_by(test: str, options: TestOptions) -> list[LabTest]:
    """The tests whose properties a job of ``test`` (the battery or one test) with ``options`` reports: what
    a campaign can match its targets against, known before anything runs."""
    return battery_members(options) if test == BATTERY else [get(test)]


def plan(spec: JobSpec) -> list[tuple[LabTest, bool]]:
    """The tests the job runs, in registry order, each with whether its properties are reported: what the
    requested tests need (the fill before a lone CCT) runs first, its properties left out."""
    wanted = {t.name for t in requested(spec)}
    table = tests()
    running: set[str] = set()
    pending = list(wanted)
    while pending:
        name = pending.pop()
        if name not in running:
            running.add(name)
            pending.extend(table[name].needs)
    return [(t, t.name in wanted) for t in table.values() if t.name in running]


def joined_by(spec: JobSpec, test: LabTest) -> str:
    """The spec field that put ``test`` in this job: its battery switch, else ``test``."""
    if spec.test == BATTERY and test.battery not in (ALWAYS, NEVER):
        return f"options.{test.battery}"
    return "test"


def known_test(name: str) -> str:
    """A test that reports quantities (a measurement's, a target's); ValueError listing the names."""
    get(name)
    return name


def known_quantity(test: str | None, quantity: str) -> str:
    """The quantity if ``test`` reports it (``test`` None: its own error was raised already)."""
    if test is not None:
        get(test).quantity(quantity)
    return quantity


def quantity(test: str, name: str) -> Quantity:
    return get(test).quantity(name)


def units() -> dict[str, dict[str, str]]:
    """test -> quantity -> SI unit, every reported quantity."""
    return {name: {q.name: q.unit for q in t.quantities} for name, t in tests().items()}


def _job_test(name: str) -> str:
    if name != BATTERY and name not in tests():
        raise ValueError(f"unknown test {name!r}; one of {job_test_names()}")
    return name


class _JobTestEnum:
    """Documents the registry's names as the field's enum in the JSON schema (and so the OpenAPI)."""

    def __get_pydantic_json_schema__(self, core_schema, handler):
        schema = handler(core_schema)
        schema["enum"] = job_test_names()
        return schema


# A pydantic field type for what a job runs: the battery or a registered test, refused with a 422 naming the
# field otherwise.
JobTestName = Annotated[str, AfterValidator(_job_test), _JobTestEnum()]
