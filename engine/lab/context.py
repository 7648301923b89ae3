"""What every procedure of one job shares: its spec and preset, callbacks, counters, warnings."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

from engine.lab.errors import SpecFieldError
from engine.lab.presets import Fidelity
from engine.lab.resolution import is_preset, particles_field, setup_for, setup_notes
from engine.lab.result import Cancelled
from engine.lab.spec import JobSpec


class QuasiStaticError(ValueError):
    """The test ran faster than the quasi-static limit and the spec asked to refuse such runs."""


@dataclass
class StageTally:
    """Steps, body-steps, simulated and wall seconds spent in one named phase of a job."""
    steps: int = 0
    particle_steps: int = 0
    simulated_time_s: float = 0.0
    wall_time_s: float = 0.0


@dataclass
class RunContext:
    spec: JobSpec
    preset: Fidelity
    progress: Callable[[float, str], None] | None = None
    should_cancel: Callable[[], bool] | None = None
    steps: int = 0
    particle_steps: int = 0
    sphere_steps: int = 0
    simulated_time_s: float = 0.0
    max_inertial_number: float | None = None
    warnings: list[str] = field(default_factory=list)
    started: float = field(default_factory=time.perf_counter)
    # per phase (the name each procedure reports its progress under, in order of first report): what ran
    # since the previous report. Every stage loop reports after each chunk it advances, so this is the
    # per-stage breakdown with no timer in the kernels (bench/lab.py --battery prints it)
    stages: dict[str, StageTally] = field(default_factory=dict)
    _tally_mark: tuple[float, int, int, float] | None = None
    # progress of the whole job is split among phases: [lo, hi) of the current phase
    _span: tuple[float, float] = (0.0, 1.0)
    _last_progress: float = -1.0

    @classmethod
    def from_spec(cls, spec: JobSpec, progress=None, should_cancel=None) -> "RunContext":
        return cls(spec, setup_for(spec), progress, should_cancel)

    # ----------------------------------------------------------------- options with preset defaults
    @property
    def speed_factor(self) -> float:
        o = self.spec.options.speed_factor
        return float(o) if o is not None else self.preset.default_speed_factor

    @property
    def lid_speed_m_s(self) -> float:
        return self.preset.lab_lid_speed_m_s * self.speed_factor

    @property
    def shear_speed_m_s(self) -> float:
        return self.preset.lab_shear_speed_m_s * self.speed_factor

    @property
    def stop_after_reduced(self) -> bool:
        o = self.spec.options.stop_after_reduced
        return bool(o) if o is not None else self.preset.stop_after_reduced

    def dst_speed_scale(self, normal_stress_pa: float) -> float:
        """What the DST's reload and shear speeds at one normal stress are multiplied by
        (``options.dst_speed_by_stress``; 1 when off).

        The shear's inertial number I = (v / h_band) d / sqrt(sigma / rho_p) falls as 1 / sqrt(sigma) at a
        fixed speed; scaled by sqrt(sigma / sigma_0) above the fidelity's lowest DST stress sigma_0 it stays
        at the lowest load's, the speed factor's choice, at every load. Below sigma_0 the speed is unscaled.
        """
        o = self.spec.options.dst_speed_by_stress
        by_stress = bool(o) if o is not None else self.preset.dst_speed_by_stress
        if not by_stress:
            return 1.0
        return math.sqrt(max(normal_stress_pa / min(self.preset.dst_normal_stresses_pa), 1.0))

    @property
    def cct_max_stress_pa(self) -> float:
        o = self.spec.options.cct_max_stress_pa
        return float(o) if o is not None else self.preset.cct_max_stress_pa

    @property
    def cct_cycles(self) -> int:
        o = self.spec.options.cct_cycles
        return int(o) if o is not None else self.preset.cct_cycles

    @property
    def dst_normal_stresses_pa(self) -> list[float]:
        o = self.spec.options.dst_normal_stresses_pa
        stresses = list(o) if o else list(self.preset.dst_normal_stresses_pa)
        if any(not (math.isfinite(s) and s > 0) for s in stresses):
            raise SpecFieldError("options.dst_normal_stresses_pa", "every normal stress must be a finite number > 0 Pa")
        if len(set(stresses)) != len(stresses):
            # each load's results are keyed by its stress: two runs under one key could not be told apart
            raise SpecFieldError("options.dst_normal_stresses_pa", f"the stresses must be distinct, got {stresses}")
        return stresses

    @property
    def shear_distance_m(self) -> float:
        o = self.spec.options.shear_distance_m
        return float(o) if o is not None else self.preset.shear_distance_m

    @property
    def rain_drop_height_m(self) -> float:
        o = self.spec.options.fill_drop_height_m
        return float(o) if o is not None else self.preset.rain_drop_height_m

    def validate(self) -> None:
        """Refuse, before any simulation, what the options make impossible (``SpecFieldError`` names the
        field): the checks every test shares, then each planned test's own (``LabTest.check``)."""
        from engine.lab.registry import plan

        steps = plan(self.spec)
        for test, _ in steps:  # the rig sections each test runs in (a rig may hold only some)
            missing = [name for name in test.apparatus if getattr(self.preset.rig, name) is None]
            if missing:
                raise SpecFieldError("rig", f"rig {self.preset.rig_name!r} has no {missing[0]} section, which the "
                                            f"{test.name} test runs in; add it, or run the tests it has")
        if self.preset.rig.shear_box is not None:  # the shear box's options, checked where there is one
            self.dst_normal_stresses_pa  # noqa: B018  (raises on a non-positive stress)
            o = self.spec.options
            lo, hi = o.residual_window_strain
            if not 0 <= lo < hi:
                raise SpecFieldError("options.residual_window_strain", "need 0 <= lower < upper")
            if hi * self.preset.container_diameter_m > self.shear_distance_m:
                raise SpecFieldError(
                    "options.shear_distance_m",
                    f"{self.shear_distance_m * 1000:.1f} mm does not reach the residual window's "
                    f"upper strain {hi:.3f} (= {hi * self.preset.container_diameter_m * 1000:.1f} mm)")
            if o.moving_average_span % 2 == 0:
                raise SpecFieldError("options.moving_average_span", "must be odd")
            if self.cct_max_stress_pa <= 0:
                raise SpecFieldError("options.cct_max_stress_pa", "must be positive")
            from engine.lab.registry import get as lab_test

            # the CCT reports its stress-conditioned quantities only below the peak it loads to
            for name in sorted({q.stress_option for q in lab_test("cct").quantities if q.stress_option}):
                stresses = getattr(o, name)
                if stresses and max(stresses) >= self.cct_max_stress_pa:
                    raise SpecFieldError(
                        f"options.{name}",
                        f"every stress must be below the CCT maximum stress "
                        f"({self.cct_max_stress_pa:.6g} Pa; options.cct_max_stress_pa), got {max(stresses):.6g} Pa")
        self.check_rig()
        for test, _ in steps:
            if test.check is not None:
                test.check(self)

    def check_rig(self) -> None:
        """The rig against the particles it is filled with (``engine.lab.rigs.check_for_particles``): a gap
        they fall through is refused naming the spec field that sets them; a box too small for them runs
        with a warning, which the result's provenance (and so every report that uses it) repeats."""
        try:
            warnings = self.preset.rig_warnings()
        except SpecFieldError as exc:
            # the field that sets the particles' sizes: the screening radius, the preset, or (a material's own
            # particles, which coarse-graining only makes larger) the particles
            field = ("parameters.particle_radius_m" if self.spec.parameters.particle_radius_m is not None
                     else particles_field(self.spec) if is_preset(self.spec.resolution) else "particles")
            raise SpecFieldError(field, f"rig {self.preset.rig_name!r}, {exc.field}: {exc.message}") from None
        for warning in warnings:
            self.warn(f"rig {self.preset.rig_name!r}, {warning}")
        for note in setup_notes(self.spec):  # the coarse factor chosen, a particle target the standards capped
            self.warn(note)
        box = self.preset.rig.shear_box
        limit = box.max_normal_force_n if box is not None else None
        if limit is None:
            return
        area = self.preset.container_area_m2
        for field, stresses in (("options.dst_normal_stresses_pa", self.dst_normal_stresses_pa),
                                ("options.cct_max_stress_pa", [self.cct_max_stress_pa])):
            beyond = [s for s in stresses if s * area > limit * (1 + 1e-12)]
            if beyond:
                raise SpecFieldError(field, f"{beyond[0]:.6g} Pa is a lid force of {beyond[0] * area:.6g} N, beyond "
                                            f"rig {self.preset.rig_name!r}'s range (max_normal_force_n = {limit:g} N)")

    # ----------------------------------------------------------------- callbacks
    def phase(self, lo: float, hi: float) -> None:
        self._span = (lo, hi)

    def report(self, fraction_of_phase: float, phase: str) -> None:
        self._tally(phase)
        if self.should_cancel is not None and self.should_cancel():
            raise Cancelled(f"cancelled during {phase}")
        if self.progress is None:
            return
        lo, hi = self._span
        f = lo + (hi - lo) * min(max(fraction_of_phase, 0.0), 1.0)
        if f - self._last_progress >= 0.01 or f >= 1.0:
            self._last_progress = f
            self.progress(f, phase)

    def _tally(self, phase: str) -> None:
        """Charge what ran since the previous report (steps, wall time) to ``phase``."""
        now = time.perf_counter()
        mark = self._tally_mark or (self.started, 0, 0, 0.0)
        stage = self.stages.setdefault(phase, StageTally())
        stage.wall_time_s += now - mark[0]
        stage.steps += self.steps - mark[1]
        stage.particle_steps += self.particle_steps - mark[2]
        stage.simulated_time_s += self.simulated_time_s - mark[3]
        self._tally_mark = (now, self.steps, self.particle_steps, self.simulated_time_s)

    def count(self, steps: int, n_bodies: int, dt_s: float, n_spheres: int = 0) -> None:
        self.steps += steps
        self.particle_steps += steps * n_bodies
        self.sphere_steps += steps * n_spheres
        self.simulated_time_s += steps * dt_s

    def inertial_number(self, value: float, where: str) -> None:
        """Record an inertial number; warn or refuse above the spec's limit (once per test)."""
        if not math.isfinite(value):
            return
        if self.max_inertial_number is None or value > self.max_inertial_number:
            self.max_inertial_number = value
        limit = self.spec.options.max_inertial_number
        if value > limit:
            msg = (f"{where}: inertial number {value:.2e} exceeds the quasi-static limit {limit:.1e}; "
                   f"lower options.speed_factor (now {self.speed_factor:g})")
            if self.spec.options.inertial_number_action == "refuse":
                raise QuasiStaticError(msg)
            if not any(w.startswith(where + ":") for w in self.warnings):
                self.warnings.append(msg)

    def warn(self, message: str) -> None:
        if message not in self.warnings:
            self.warnings.append(message)

    @property
    def wall_time_s(self) -> float:
        return time.perf_counter() - self.started
