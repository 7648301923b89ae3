"""The calibration loop in a notebook: a small driver over ``calibration.machine`` and any batch evaluator.

``CalibrationLoop(targets, evaluator, settings).run()`` asks the machine which batteries the current
phase waits for, has the evaluator run them (``calibration.evaluators``: the closed-form stand-in, the
DEM lab in this process, a queue, Dask), tells the machine their results and applies the transition,
until the loop is complete. The service's campaign runner drives the same machine on database rows,
so the same batteries give the same verdict, optimum, diagnosis and stop reason in both.

The state (``calibration.state.LoopState``) is plain data: ``loop.state.model_dump_json()`` saves a
loop, ``CalibrationLoop(..., state=LoopState.model_validate_json(text))`` resumes it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping, Sequence

from . import machine
from . import parameters as factor_paths
from .analysis import model_fails
from .automatic import kept_number
from .errors import SettingsError
from .evaluators import BatchEvaluator
from .history import history
from .keys import responses_of
from .records import Measured
from .settings import LoopSettings, validated
from .state import IterationState, LoopState, RunState
from .vocabulary import Phase


@dataclass
class LoopResult:
    """The iterations of a finished loop and why it stopped."""

    iterations: list[IterationState]
    stop_reason: str | None

    @property
    def first(self) -> IterationState:
        return self.iterations[0]

    @property
    def final(self) -> IterationState:
        """The model the loop ends with: the last iteration, unless the effect it added was rejected,
        then the iteration it was built on, or an alias fitted in place of an effect that passed was compared
        with it, then the one the comparison kept (``calibration.automatic.settle_alias``)."""
        last = self.iterations[-1]
        number = kept_number(last.number, last.report)
        return next(it for it in self.iterations if it.number == number)

    @property
    def decisions(self) -> list[dict]:
        """The automatic mode's judgements of each added effect, in order."""
        return [d for it in self.iterations if (d := ((it.report or {}).get("automatic") or {}).get("decision"))]

    def diagnosis(self, number: int = 1) -> dict | None:
        it = next((i for i in self.iterations if i.number == number), None)
        return (it.report or {}).get("diagnosis") if it is not None else None

    def model_fails(self, it: IterationState) -> bool:
        return model_fails(it.report or {})

    def history(self) -> dict[str, Any]:
        return history(self.iterations)


class CalibrationLoop:
    """``settings``: ``LoopSettings`` or its JSON dict; ``targets``: the measurements.

    ``measured_rig`` and ``measured_particles`` (``engine.lab.rigs.Rig``, ``engine.particles.description.Particles``,
    or their JSON): the apparatus the measurements were made in and the material's particles. Given, the targets
    the runs cannot be compared with (a bulk mass measured in another rig, a per-particle quantity at a coarse
    resolution) are left out with the reason (``left_out_targets``, in every report too), as a campaign does."""

    def __init__(self, targets: Sequence[Measured], evaluator: BatchEvaluator,
                 settings: LoopSettings | Mapping[str, Any], *, state: LoopState | None = None,
                 evaluator_name: str | None = None, measured_rig=None, measured_particles=None):
        from .comparable import in_world, split

        measured = [t if isinstance(t, Measured) else Measured.from_record(t) for t in targets]
        self.evaluator = evaluator
        self.evaluator_name = evaluator_name
        rig, particles = _world(measured_rig, measured_particles)
        loop_settings = in_world(settings if isinstance(settings, LoopSettings) else LoopSettings.model_validate(dict(settings)),
                                 rig, particles)
        self.state = state or LoopState(settings=loop_settings.model_dump(mode="json"))
        self.targets, self.left_out_targets = split(measured, rig, particles,
                                                    LoopSettings.model_validate(self.state.settings))
        if not self.targets and self.left_out_targets:
            raise ValueError("no target can be compared with what the runs simulate: " + "; ".join(
                f"{t['test']}/{t['quantity']}: {t['reason']}" for t in self.left_out_targets))

    @classmethod
    def on_backend(cls, targets: Sequence[Measured], backend: str, settings: LoopSettings | Mapping[str, Any],
                   **kwargs) -> "CalibrationLoop":
        """The loop on a registered backend (``calibration.evaluator_registry``: "dem", "analytic") in this
        process, its batteries run as a campaign's jobs would be: the settings' test and fidelity, and the
        options that make them compute every target's condition (``conditions.battery_options``)."""
        from .comparable import in_world
        from .conditions import battery_options
        from .evaluator_registry import get

        loop_settings = settings if isinstance(settings, LoopSettings) else LoopSettings.model_validate(settings)
        measured = [t if isinstance(t, Measured) else Measured.from_record(t) for t in targets]
        loop_settings = in_world(loop_settings, *_world(kwargs.get("measured_rig"), kwargs.get("measured_particles")))
        evaluator = get(backend).batch(fidelity=loop_settings.fidelity, test=loop_settings.test,
                                       options=battery_options([t.key for t in measured], loop_settings.options),
                                       lab=loop_settings.lab())
        return cls(measured, evaluator, loop_settings, evaluator_name=backend, **kwargs)

    # -- driving ---------------------------------------------------------------------------
    def run(self) -> LoopResult:
        while self.advance():
            pass
        return self.result()

    def result(self) -> LoopResult:
        last = self.state.iterations[-1] if self.state.iterations else None
        stop = (((last.report or {}).get("automatic") or {}).get("stop_reason")) if last else None
        return LoopResult(list(self.state.iterations), stop)

    def advance(self) -> bool:
        """One step: evaluate what the phase waits for, or take the phase's transition; False once
        the loop is complete."""
        st = self.state
        if st.complete:
            return False
        it = st.iterations[-1] if st.iterations else None
        if it is None or it.phase == Phase.DONE:
            self._new_iteration()
            return True
        pending = [r for r in machine.awaited(it) if r.responses is None]
        if pending:
            self.tell(self.ask(pending), pending)
            return True
        transition = machine.step(self._context(), it)
        if transition is None:
            return False
        self._apply(it, transition)
        return True

    def extend(self, more_iterations: int = 1) -> "CalibrationLoop":
        """Take a completed automatic loop up again with ``more_iterations`` beyond its last iteration
        (``machine.extended``: its next step decided again under the raised limit); ``run()`` then goes on.
        SettingsError when there is nothing more iterations would do."""
        if not self.state.complete or not self.state.iterations:
            raise SettingsError("the loop has not stopped: run it first", "more_iterations", conflict=True)
        it = self.state.iterations[-1]
        transition = machine.extended(self._context(), it, more_iterations)
        self._apply(it, transition)
        self.state.complete = False
        return self

    def ask(self, runs: Sequence[RunState]) -> list[list[dict]]:
        """Evaluate ``runs`` (in the design's randomised run order) with the batch evaluator."""
        settings = LoopSettings.model_validate(self.state.settings)
        ordered = sorted(runs, key=lambda r: (r.run_order, r.id))
        results = self.evaluator([(factor_paths.apply(settings.fixed_parameters, r.natural), r.seed)
                                  for r in ordered])
        by_id = {r.id: res for r, res in zip(ordered, results)}
        return [by_id[r.id] for r in runs]

    @staticmethod
    def tell(results: Sequence[Sequence[dict]], runs: Sequence[RunState]) -> None:
        """Store each run's response records (``responses_of`` shape, as the service stores them)."""
        for run, recs in zip(runs, results):
            run.responses = responses_of({"properties": list(recs)})

    # -- applying the machine's decisions -----------------------------------------------------
    def _context(self) -> machine.Context:
        settings = LoopSettings.model_validate(self.state.settings)
        return machine.Context(settings, self.state.settings, self.targets, self.state.iterations, validated,
                               self.left_out_targets)

    def _new_iteration(self) -> None:
        settings = LoopSettings.model_validate(self.state.settings)
        number = len(self.state.iterations) + 1
        self.state.iterations.append(IterationState(
            number=number, parameters=machine.iteration_parameters(settings, self.evaluator_name)))

    def _apply(self, it: IterationState, t: machine.Transition) -> None:
        for name, value in t.values.items():
            setattr(it, name, value)
        for new in t.runs:
            it.runs.append(RunState(id=self.state.next_run_id, kind=new.kind, std_order=new.std_order,
                                    run_order=new.run_order, is_centre=new.is_centre, natural=new.natural,
                                    coded=new.coded, seed=new.seed, responses=new.responses, job_id=new.job_id,
                                    reused_from=new.reused_from))
            self.state.next_run_id += 1
        it.phase = t.to
        if t.next_settings is not None:
            self.state.settings = {**self.state.settings, **t.next_settings}
        if t.complete:
            self.state.complete = True


def _world(rig, particles):
    """The measurements' rig and particles as the engine's models (JSON accepted), None where not given."""
    from engine.lab.rigs import Rig
    from engine.particles.description import Particles

    return (None if rig is None else rig if isinstance(rig, Rig) else Rig.model_validate(rig),
            None if particles is None else particles if isinstance(particles, Particles)
            else Particles.model_validate(particles))
