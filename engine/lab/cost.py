"""The cost of a job spec before it runs: the one model behind every limit (jobs, campaigns, schedules).

Why beside the procedures: each test's declaration (``engine/lab/labtests/``) estimates its own stage from
its procedure's stop rules (``engine.lab.stops``) and the same option defaults the procedure reads
(``RunContext``), so the estimate cannot drift from what runs. Both numbers are ceilings, not guesses:

* particles: the largest packing any test builds (the shear-box fill, the angle-of-repose bucket, the
  anchor bin), solids volume x the preset's fill margin / the volume per sphere;
* simulated time: every test the job runs, each at most what its procedure allows: settling phases stop
  at their ceilings, a lid stroke at ``LID_MAX_TRAVEL_FRACTION`` of the packing height at the lab lid
  speed x ``speed_factor``, the angle of repose's lift at three bucket heights.

Each stage names the spec field that lowers it, so the service's refusal names that field directly
(``service.limits``). A spec the lab cannot run at all raises ``SpecFieldError``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from engine.lab.context import RunContext
from engine.lab.presets import ShapeFraction
from engine.lab.registry import StageCost, joined_by, plan
from engine.lab.spec import JobSpec
from engine.lab.stops import LID_MAX_TRAVEL_FRACTION


@dataclass
class Cost:
    """Per test of the job, in run order."""

    stages: dict[str, StageCost] = field(default_factory=dict)

    @property
    def stages_s(self) -> dict[str, float]:
        return {name: s.simulated_time_s for name, s in self.stages.items()}

    @property
    def simulated_time_s(self) -> float:
        return sum(self.stages_s.values())

    @property
    def particles_stage(self) -> str:
        """The test that builds the largest packing (the first such, in run order)."""
        return max(self.stages, key=lambda name: self.stages[name].particles)

    @property
    def particles(self) -> int:
        return self.stages[self.particles_stage].particles if self.stages else 0

    @property
    def particles_field(self) -> str:
        return self.stages[self.particles_stage].particles_field

    @property
    def time_stage(self) -> str:
        return max(self.stages, key=lambda name: self.stages[name].simulated_time_s)

    @property
    def time_field(self) -> str:
        """The field that shortens the stage that costs most."""
        return self.stages[self.time_stage].time_field


def packing_spheres(solid_m3: float, margin: float, shapes: tuple[ShapeFraction, ...]) -> int:
    """Spheres of a packing (what a step costs): bodies from the solids volume, times the spheres of each
    body. A shape with its own template (the elongated clumps) counts its template's volume at the mean
    sphere radius and its spheres; the others count as one sphere of their mean radius."""
    spheres_per_m3 = 0.0
    for s in shapes:
        if s.template is not None and s.size is not None:  # a custom clump scaled to a mean-sized largest sphere
            scale = 0.5 * (s.radius_min_m + s.radius_max_m) / float(max(s.template.sphere_radii_m))
            volume, spheres = s.template.volume_m3 * scale**3, s.template.n_spheres
        elif s.template is not None:
            # the template scaled to the fraction's mean sphere radius (a given body when the range is one radius)
            scale = 1.0 if s.radius_min_m == s.radius_max_m else \
                0.5 * (s.radius_min_m + s.radius_max_m) / float(max(s.template.sphere_radii_m))
            volume, spheres = s.template.volume_m3 * scale**3, s.template.n_spheres
        elif s.size is not None:  # a sieve curve's number mean lies far below its mid-size: sample it
            radii = s.size.sample(np.random.default_rng(0), 4096)
            volume, spheres = float(np.mean(4.0 / 3.0 * math.pi * radii**3)), 1
        else:
            volume, spheres = 4.0 / 3.0 * math.pi * (0.5 * (s.radius_min_m + s.radius_max_m)) ** 3, 1
        spheres_per_m3 += s.volume_fraction / volume * spheres
    return int(math.ceil(solid_m3 * margin * spheres_per_m3))


def lid_stroke_s(ctx: RunContext) -> float:
    """One lid stroke of the CCT or the DST's reload, at most: its travel limit at the test's lid speed."""
    return LID_MAX_TRAVEL_FRACTION * ctx.preset.packing_height_m / ctx.lid_speed_m_s


def estimate(spec: JobSpec) -> Cost:
    """Particles and simulated time per test of ``spec``; see the module docstring."""
    ctx = RunContext.from_spec(spec)
    steps = plan(spec)
    planned = frozenset(test.name for test, _ in steps)
    cost = Cost()
    for test, _ in steps:
        stage = test.cost(ctx, planned)
        if stage.particles_field is None:
            stage = replace(stage, particles_field=joined_by(spec, test))
        cost.stages[test.name] = stage
    return cost


def estimated_particles(spec: JobSpec) -> int:
    return estimate(spec).particles


def estimated_simulated_time_s(spec: JobSpec) -> float:
    return estimate(spec).simulated_time_s


def contact_law(spec: JobSpec) -> str:
    """The contact effects that set the time step ("linear" for none): two jobs of one set-up run at about the
    same step only under the same law (a Hertzian battery takes about 3x the steps of a linear one, engine.timestep)."""
    from engine.effects import REGISTRY

    names = sorted(name for name in spec.parameters.effects
                   if REGISTRY[name].contact_stiffness is not None or REGISTRY[name].timestep_limit is not None)
    return "+".join(names) or "linear"


def estimate_view(spec: JobSpec) -> dict:
    """What a job will cost where it runs, as shown when it is created: the rig, the resolution and its size
    factor, the particles of the largest packing and the simulated time (ceilings, per test)."""
    from engine.lab.resolution import label, setup_for

    setup, cost = setup_for(spec), estimate(spec)
    return {"rig": setup.rig_name, "resolution": label(spec.resolution, spec.fidelity),
            "scale_factor": setup.scale_factor, "contact_law": contact_law(spec), "particles": cost.particles,
            "particles_stage": cost.particles_stage if cost.stages else None,
            "simulated_time_s": cost.simulated_time_s, "stages_s": cost.stages_s}
