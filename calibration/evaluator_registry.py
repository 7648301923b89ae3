"""The evaluator registry: every backend that can run a lab job, declared once.

Why: the backends' names used to be written in nine places (the queue, the job and campaign schemas,
the CLI, the page, the workers) beside three ways of calling them. Here each backend is declared
once: its name (what jobs and campaigns store), a title and a description for people, the lab tests
it covers, and the function that runs one job. Everything else is derived from the declaration:

* one job: ``run_job(name, spec, progress, should_cancel) -> LabResult`` is what the service's
  workers (local and Dask) call;
* a batch: ``backend.batch(fidelity=..., test=..., options=...)`` is a ``calibration.evaluators``
  batch evaluator (a list of (parameters, seed) in, one list of bulk-value records per run out)
  that runs the same function in this process, for notebooks and the library loop;
* names: ``names()`` for CLI choices, ``EvaluatorName`` for pydantic fields (a 422 naming the field
  for an unknown name, and the names as an enum in the OpenAPI schema), GET /api/v1/evaluators
  for the page.

A backend's run function is named by its import path ("module:function") and imported on first
use: listing the names (the CLI, the API) must not import the stand-in's effect kernels or the
DEM procedures.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated, Any, Callable, Mapping

from pydantic import AfterValidator

from engine.lab.registry import job_test_names

if TYPE_CHECKING:
    from engine.lab.result import LabResult
    from engine.lab.spec import JobSpec

    from .evaluators import LabEvaluator

ProgressFn = Callable[[float, str], None]
CancelFn = Callable[[], bool]

# The jobs and campaigns tables store the name in a String(16) column.
NAME_MAX = 16
LAB_TESTS: tuple[str, ...] = tuple(job_test_names())  # the lab's tests (engine.lab.registry), battery included


class UnknownEvaluator(ValueError):
    """A name no backend is registered under; the message lists the names that are."""


class UncoveredTest(ValueError):
    """A lab test the backend does not run; the message lists the tests it does."""


@dataclass(frozen=True)
class Backend:
    """One evaluator: what it is called, what it covers and how it runs one job.

    ``runner`` is "module:function" for ``function(spec, progress=None, should_cancel=None) ->
    LabResult``, the contract of ``engine.lab.run_job``: ``progress(fraction, phase)`` is called now
    and then, ``should_cancel()`` is polled and ``engine.lab.Cancelled`` raised when it answers True.
    """

    name: str
    title: str
    description: str
    tests: tuple[str, ...]
    runner: str

    def run(self, spec: JobSpec, progress: ProgressFn | None = None,
            should_cancel: CancelFn | None = None) -> LabResult:
        """Run one job; a test the backend does not cover is refused before anything runs."""
        self.check_test(spec.test)
        module, function = self.runner.split(":")
        return getattr(importlib.import_module(module), function)(
            spec, progress=progress, should_cancel=should_cancel)

    def check_test(self, test: str) -> None:
        if test not in self.tests:
            raise UncoveredTest(f"evaluator {self.name!r} does not run test {test!r}; it runs {list(self.tests)}")

    def batch(self, *, fidelity: str = "screening", test: str = "battery",
              options: Mapping[str, Any] | None = None, lab: Mapping[str, Any] | None = None) -> LabEvaluator:
        """This backend as a batch evaluator in this process (``options``: TestOptions fields; ``lab``:
        ``LoopSettings.lab``, a resolution with its rig and particles)."""
        from .evaluators import LabEvaluator

        return LabEvaluator(fidelity=fidelity, test=test, options=dict(options or {}), backend=self, lab=dict(lab or {}))


REGISTRY: dict[str, Backend] = {}


def register(backend: Backend) -> Backend:
    """Declare a backend; a second backend under the same name, or a name or test that cannot be
    stored or run, is a programming error caught at import."""
    if backend.name in REGISTRY:
        raise ValueError(f"evaluator {backend.name!r} is already registered")
    if not backend.name or len(backend.name) > NAME_MAX:
        raise ValueError(f"evaluator name {backend.name!r} must have 1 to {NAME_MAX} characters (the stored column)")
    unknown = sorted(set(backend.tests) - set(LAB_TESTS))
    if unknown or not backend.tests:
        raise ValueError(f"evaluator {backend.name!r} declares tests {unknown or '[]'}; "
                         f"lab tests are {list(LAB_TESTS)}")
    if ":" not in backend.runner:
        raise ValueError(f"evaluator {backend.name!r}: runner {backend.runner!r} is not 'module:function'")
    REGISTRY[backend.name] = backend
    return backend


def names() -> list[str]:
    """The registered names, in declaration order."""
    return list(REGISTRY)


def get(name: str) -> Backend:
    try:
        return REGISTRY[name]
    except KeyError:
        raise UnknownEvaluator(f"unknown evaluator {name!r}; choose one of {names()}") from None


def check_name(name: str) -> str:
    """``name`` if a backend is registered under it, else ``UnknownEvaluator`` (a pydantic validator)."""
    get(name)
    return name


def run_job(name: str, spec: JobSpec, progress: ProgressFn | None = None,
            should_cancel: CancelFn | None = None) -> LabResult:
    """Run one job on the named backend: what the service's workers call."""
    return get(name).run(spec, progress, should_cancel)


class _NamesAsEnum:
    """Publishes the registered names as the field's ``enum`` in the JSON schema (OpenAPI), read
    when the schema is built, so clients and fuzzers see the choices a Literal used to show."""

    def __get_pydantic_json_schema__(self, core_schema, handler):
        schema = handler(core_schema)
        schema["enum"] = names()
        return schema


EvaluatorName = Annotated[str, AfterValidator(check_name), _NamesAsEnum()]


DEM = register(Backend(
    name="dem", title="simulation", runner="engine.lab:run_job", tests=LAB_TESTS,
    description="The virtual laboratory on the numba DEM engine: every test simulated from the micro "
                "parameters (minutes to hours a battery).",
))
ANALYTIC = register(Backend(
    name="analytic", title="closed-form stand-in", runner="calibration.standin_job:run_analytic", tests=LAB_TESTS,
    description="A closed-form battery with the thesis's trends, every candidate effect and the simulator's "
                "scatter (milliseconds a battery): for tests, demonstrations and campaigns that must finish "
                "in seconds.",
))

# The evaluator a job or campaign runs on when none is named, one for both (JobSubmit, CampaignCreate, the
# ORM columns, the queue). The simulation, because a default should give the answer the service exists for:
# a campaign that silently calibrates against the stand-in returns parameters fitted to closed-form trends,
# which look like a calibration and mean nothing for the material. The stand-in's speed is one word away
# (evaluator "analytic"), and the DEM's cost is checked before anything is queued (service.limits).
DEFAULT = DEM
