"""The material an exporter reads: particles, contact law and effects, SI, as plain data.

This is the minimal structure the LIGGGHTS export needs; the neutral material card (issue 30 item 1)
carries more (intervals, rig, provenance) and is adapted to it. Fields mirror ``engine.lab.spec.
MicroParameters`` so that demcal's own names travel unchanged:

```yaml
name: screening aggregate
particles:
  solid_density_kg_m3: 2500
  spheres:                       # discrete sphere sizes, each its own LIGGGHTS atom type
    - {radius_m: 0.02, volume_fraction: 1.0}
  clumps:                        # rigid multi-sphere bodies (centres in any frame), each its own type
    - {name: elongated, sphere_centres_m: [[0,0,0],[0.016,0,0]], sphere_radii_m: [0.016,0.016],
       volume_fraction: 0.0}
contact:
  particle_stiffness_n_per_m: 1.72e6   # PFC-style per-entity kp (contact: kp kw / (kp + kw))
  wall_stiffness_n_per_m: 1.0e7        # kw
  shear_to_normal_stiffness_ratio: 1.0
  damping_ratio_normal: 0.8
  damping_ratio_shear: 0.8
  friction_pp: 0.5
  friction_pw: 0.3
  local_damping: 0.0                   # Cundall non-viscous damping (LIGGGHTS has none)
effects:                               # engine.effects.REGISTRY names and parameters, SI
  rolling_epsd2: {rolling_friction: 0.2}
```
Volume fractions are solid-volume (= mass) shares over spheres and clumps together and sum to 1. A
continuous size range (the thesis's Gaussian classes) is given as a few discrete sizes
(``from_micro_parameters`` does it) so that every contact's damping can be set exactly per type pair.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

# strict like the lab's job specs (engine.lab.spec.STRICT_INPUT): no false for a number, no NaN or infinity
_STRICT = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


class SphereClass(BaseModel):
    model_config = _STRICT
    radius_m: float = Field(gt=0)
    volume_fraction: float = Field(ge=0, le=1)


class ClumpClass(BaseModel):
    model_config = _STRICT
    name: str = Field(min_length=1, max_length=64)
    sphere_centres_m: list[list[float]] = Field(min_length=1, max_length=500, description="[x, y, z] per sphere, m")
    sphere_radii_m: list[float] = Field(min_length=1, max_length=500)
    volume_fraction: float = Field(ge=0, le=1)

    @model_validator(mode="after")
    def _same_length(self) -> "ClumpClass":
        if any(len(c) != 3 for c in self.sphere_centres_m):
            raise ValueError(f"clump {self.name}: every sphere centre is [x, y, z]")
        if len(self.sphere_centres_m) != len(self.sphere_radii_m):
            raise ValueError(f"clump {self.name}: sphere_centres_m and sphere_radii_m differ in length")
        if any(r <= 0 for r in self.sphere_radii_m):
            raise ValueError(f"clump {self.name}: every sphere radius must be > 0")
        return self

    def template(self):
        """demcal's rigid-body template (CoM at the origin, principal frame, overlap-net volume)."""
        from engine.particles.templates import from_spheres

        return from_spheres(np.asarray(self.sphere_centres_m, float), np.asarray(self.sphere_radii_m, float),
                            name=self.name)


class ParticleSpec(BaseModel):
    model_config = _STRICT
    solid_density_kg_m3: float = Field(gt=0)
    spheres: list[SphereClass] = Field(default_factory=list, max_length=64)
    clumps: list[ClumpClass] = Field(default_factory=list, max_length=64)

    @model_validator(mode="after")
    def _fractions(self) -> "ParticleSpec":
        if not self.spheres and not self.clumps:
            raise ValueError("particles: give at least one sphere size or clump")
        total = sum(s.volume_fraction for s in self.spheres) + sum(c.volume_fraction for c in self.clumps)
        if abs(total - 1.0) > 1e-6:
            raise ValueError(f"particles: volume fractions must sum to 1, got {total:.6g}")
        return self


class ContactSpec(BaseModel):
    model_config = _STRICT
    particle_stiffness_n_per_m: float = Field(gt=0)
    wall_stiffness_n_per_m: float = Field(gt=0)
    shear_to_normal_stiffness_ratio: float = Field(1.0, ge=0)
    damping_ratio_normal: float = Field(ge=0, lt=1)
    damping_ratio_shear: float = Field(ge=0, lt=1)
    friction_pp: float = Field(ge=0)
    friction_pw: float = Field(ge=0)
    local_damping: float = Field(0.0, ge=0, lt=1)


class ExportMaterial(BaseModel):
    model_config = _STRICT
    name: str = Field("demcal material", max_length=200)
    particles: ParticleSpec
    contact: ContactSpec
    effects: dict[str, dict[str, Any]] = Field(default_factory=dict)
    notes: list[str] = Field(default_factory=list, max_length=50,
                             description="how the particles were derived (e.g. a size range discretised)")

    @field_validator("effects")
    @classmethod
    def _known(cls, effects: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
        from engine.effects import REGISTRY

        for name, params in effects.items():
            if name not in REGISTRY:
                raise ValueError(f"effects: unknown contact effect {name!r}; known: {sorted(REGISTRY)}")
            REGISTRY[name].params_model.model_validate(params)
        return effects

    def effect(self, name: str):
        """The effect's validated parameter model, or None when it is off."""
        from engine.effects import REGISTRY

        if name not in self.effects:
            return None
        return REGISTRY[name].params_model.model_validate(self.effects[name])


def _bins_of_size(size, r_min: float, r_max: float, bins: int) -> list[tuple[float, float]]:
    """(radius, number probability) of ``bins`` equal-width bins of a material's size distribution
    (``engine.particles.distributions.bin_shares``: closed form where there is one, else sampled)."""
    from engine.particles import distributions as dist

    if r_min == r_max or isinstance(size, dist.ConstantSize):
        return [(r_min, 1.0)]
    edges = np.linspace(r_min, r_max, bins + 1)
    p = dist.bin_shares(size, edges)
    return [(float(0.5 * (a + b)), float(q)) for a, b, q in zip(edges[:-1], edges[1:], p) if q > 0]


def from_micro_parameters(parameters, fidelity: str = "screening", bins_per_range: int = 3,
                          setup=None) -> ExportMaterial:
    """The material of a lab job's ``MicroParameters`` at a fidelity's particles (engine/lab/presets.py), or
    at ``setup`` (engine.lab.setup.Fidelity: a material's particles at a resolution; ``fidelity`` then names it).

    A size range (the thesis's Gaussian classes) becomes ``bins_per_range`` discrete sizes, each
    volume share = its number probability x its body volume, renormalised within the class.
    """
    from engine.lab.presets import fidelity as preset_of
    from engine.particles import distributions as dist
    from engine.particles import templates as tpl

    preset = setup if setup is not None else \
        preset_of(fidelity, parameters.particle_radius_m, parameters.clump_aspect_ratio)
    spheres: list[SphereClass] = []
    clumps: list[ClumpClass] = []
    builders = {"pyramid": tpl.pyramid, "double_clump": lambda r: tpl.double_clump(r, r)}
    for shape in preset.shapes:
        if shape.template is not None and shape.size is not None:  # a material's custom clump at each drawn size
            template = shape.template
            builders[shape.shape] = lambda r, t=template: t.scaled(r / float(max(t.sphere_radii_m)))
        if shape.template is not None and shape.size is None:
            t = shape.template
            clumps.append(ClumpClass(name=t.name, sphere_centres_m=[[float(x) for x in c] for c in t.sphere_offsets_m],
                                     sphere_radii_m=[float(r) for r in t.sphere_radii_m],
                                     volume_fraction=shape.volume_fraction))
            continue
        # a range without a size form is the fill's truncated Gaussian at its defaults (midpoint, range / 6)
        size = shape.size if shape.size is not None or shape.radius_min_m == shape.radius_max_m else \
            dist.TruncatedGaussian(shape.radius_min_m, shape.radius_max_m)
        bins = _bins_of_size(size, shape.radius_min_m, shape.radius_max_m, bins_per_range)
        if shape.shape == "sphere":
            volumes = [p * r ** 3 for r, p in bins]
            for (r, _), v in zip(bins, volumes):
                spheres.append(SphereClass(radius_m=r, volume_fraction=shape.volume_fraction * v / sum(volumes)))
        elif shape.shape in builders:
            templates = [(builders[shape.shape](r), p) for r, p in bins]
            volumes = [p * t.volume_m3 for t, p in templates]
            for (t, _), v in zip(templates, volumes):
                r = float(t.sphere_radii_m[0])
                clumps.append(ClumpClass(name=f"{shape.shape}_{r * 1000:.2f}mm",
                                         sphere_centres_m=[[float(x) for x in c] for c in t.sphere_offsets_m],
                                         sphere_radii_m=[float(x) for x in t.sphere_radii_m],
                                         volume_fraction=shape.volume_fraction * v / sum(volumes)))
        else:
            raise ValueError(f"fidelity {fidelity}: shape {shape.shape!r} has no export")
    notes = []
    for shape in preset.shapes:
        if shape.template is None and shape.radius_min_m != shape.radius_max_m:
            form = "truncated Gaussian" if shape.size is None else type(shape.size).__name__
            notes.append(f"{shape.shape} radii {shape.radius_min_m * 1000:g}-{shape.radius_max_m * 1000:g} mm "
                         f"(demcal: {form}) as {bins_per_range} discrete sizes at the bin centres"
                         + ("; demcal draws the two spheres of a double clump independently, the export makes "
                            "them equal" if shape.shape == "double_clump" else ""))
    total = sum(s.volume_fraction for s in spheres) + sum(c.volume_fraction for c in clumps)
    for item in (*spheres, *clumps):  # exact sum after float rounding of the shares
        item.volume_fraction = item.volume_fraction / total
    return ExportMaterial(
        name=f"demcal {fidelity} material",
        particles=ParticleSpec(solid_density_kg_m3=parameters.particle_density_kg_m3, spheres=spheres, clumps=clumps),
        contact=ContactSpec(
            particle_stiffness_n_per_m=parameters.particle_stiffness_n_per_m,
            wall_stiffness_n_per_m=parameters.wall_stiffness_n_per_m,
            shear_to_normal_stiffness_ratio=parameters.shear_to_normal_stiffness_ratio,
            damping_ratio_normal=parameters.damping_ratio, damping_ratio_shear=parameters.damping_ratio,
            friction_pp=parameters.friction_pp, friction_pw=parameters.friction_pw,
            local_damping=parameters.local_damping),
        effects={k: dict(v) for k, v in parameters.effects.items()},
        notes=notes,
    )


def body_masses_kg(material: ExportMaterial) -> list[float]:
    """Mass of one body of each atom type (spheres first, then clumps: the export's type order)."""
    rho = material.particles.solid_density_kg_m3
    masses = [rho * 4.0 / 3.0 * math.pi * s.radius_m ** 3 for s in material.particles.spheres]
    masses += [c.template().mass_kg(rho) for c in material.particles.clumps]
    return masses
