"""Fidelity presets: the old names of two (bundled rig, bundled particles, resolution) triples.

The apparatus (dimensions, gap, loads, speeds) is data: the bundled rig records of ``engine/lab/rig_records``
(``engine.lab.rigs``); the particles are a ``Particles`` description (``engine.particles.description``); a
resolution says how finely they are built (``engine.lab.resolution``). A preset names one of each, plus the
speed factor that no apparatus holds; ``engine.lab.setup.lab_setup`` turns them into the set-up the
procedures read. Both presets build their particles as described ("as measured"): the old fidelity names
are aliases of these triples, so stored jobs and campaigns replay with the same numbers.

"thesis" is the set-up of chapters 4 and 5 (590 x 330 mm shear box split at mid-height with a
1 mm gap, the three clump shapes of Tables 4.2/4.9, loads of Table 3.1). "screening" is the
Appendix A set-up (Table A.7: container radius 200 mm, packing depth 370 mm, mono-sized spheres
of radius 20 mm, ~840 particles, DST loads 1,885 / 3,495 / 5,105 / 6,760 N and a CCT force of
8,415 N), whose forces are turned into stresses over the container area, so that conditions
are stresses at both fidelities (8,415 N over pi 0.2^2 is 67.0 kPa, close to the 65.6 kPa of
Table 3.1: Appendix A chose its forces to give the same stresses in the smaller box).

Lab speeds are the thesis's (lid 1 mm/s; shear 1 mm/s, 0.3 mm/s in Appendix A; bucket 5 mm/s);
the default speed factors are what keeps a run affordable while the inertial number stays
in the quasi-static range (docs/lab.md).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

from engine.lab.errors import SpecFieldError
from engine.lab.resolution import AS_MEASURED, Resolution
from engine.lab.rigs import bundled_rig
# the set-up's names, imported from here by the procedures, the geometry and the cost model
from engine.lab.setup import (AnchorGeometry, AorGeometry, Fidelity, ShapeFraction, lab_setup,  # noqa: F401
                              particles_of, shape_fractions)
from engine.particles.description import Particles, thesis_particles


@dataclass(frozen=True)
class Preset:
    """An old fidelity name: a bundled rig, bundled particles at a resolution, and the speed factor.
    ``aor_particles``: the angle of repose's own particles where the fill's cannot form a pile."""

    rig_name: str
    particles: Particles
    resolution: Resolution
    default_speed_factor: float
    aor_particles: Particles | None = None
    # the battery's step savings (docs/lab.md, "Fewer steps per battery"): on where the loop runs its batteries
    stop_after_reduced: bool = False
    dst_speed_by_stress: bool = False

    def setup(self, name: str) -> Fidelity:
        if self.resolution.mode != AS_MEASURED:  # a preset is a fixed set-up: its particles as they are
            raise ValueError(f"preset {name!r}: bundled particles are built as measured")
        aor = None if self.aor_particles is None else shape_fractions(self.aor_particles)
        return lab_setup(name, bundled_rig(self.rig_name), shape_fractions(self.particles),
                         default_speed_factor=self.default_speed_factor, aor_shapes=aor, particles=self.particles,
                         stop_after_reduced=self.stop_after_reduced, dst_speed_by_stress=self.dst_speed_by_stress)


def _spheres(shape: str, radius_m: float) -> Particles:
    return Particles.model_validate({"size": {"form": "constant", "radius_m": radius_m},
                                     "shapes": [{"shape": shape, "volume_fraction": 1.0}]})


# the fidelities' rigs: the old word names the bundled record it always meant
FIDELITY_RIGS = {"thesis": "thesis-590mm-shear-box", "screening": "appendix-a-400mm-shear-box"}

PRESETS = {
    # The thesis's own particles (Table 4.2 clump mix) in its own rig (the 590 mm box).
    "thesis": Preset(FIDELITY_RIGS["thesis"], thesis_particles(), Resolution(mode=AS_MEASURED), 10.0),

    # Appendix A: mono-sized spheres of radius 20 mm in the 400 mm box (~840 particles).
    # Spheres without rolling resistance roll away on a flat floor and form no pile at all, so the
    # screening angle of repose uses pyramid clumps (four spheres of half the screening radius, about
    # the same grain size) in the rig's bucket, the thesis's scaled by 0.6 (~120 clumps after levelling
    # instead of ~600). Its 156 mm opening is only ~4 clump sizes (the thesis's: ~7): narrow end down, the
    # converging wall wedges the grains and a slow lift carries a plug up with the bucket, so the scaled
    # bucket stands on its wide rim. Lift 20 mm/s, not 5 mm/s: at 50 or 100 mm/s the column collapses
    # instead of draining through the gap under the rim, and the pile comes out flatter. docs/lab.md.
    "screening": Preset(FIDELITY_RIGS["screening"], _spheres("sphere", 0.020), Resolution(mode=AS_MEASURED), 40.0,
                        aor_particles=_spheres("pyramid", 0.010), stop_after_reduced=True),
}
THESIS = PRESETS["thesis"].setup("thesis")
SCREENING = PRESETS["screening"].setup("screening")
FIDELITIES = {"thesis": THESIS, "screening": SCREENING}


def fidelity(name: str, particle_radius_m: float | None = None, clump_aspect_ratio: float = 1.0) -> Fidelity:
    """The preset by name; at screening, ``particle_radius_m`` replaces the 20 mm spheres (the thesis
    fidelity has its own clump mix, Table 4.2). ``clump_aspect_ratio`` > 1 makes the mix's spheres
    two-sphere clumps of that length/width with the solid volume of the sphere they replace
    (``engine/lab/shape.py``): every shear-box (and anchor-bin) grain at screening, the round 20.8 % at
    the thesis fidelity. The screening angle of repose keeps its pyramids (spheres would roll away, see
    the preset), so the shape does not reach it there.
    """
    try:
        preset = FIDELITIES[name]
    except KeyError:
        raise SpecFieldError("fidelity", f"unknown fidelity {name!r}; choose one of {sorted(FIDELITIES)}") from None
    if particle_radius_m is not None:
        if name != "screening":
            raise SpecFieldError("parameters.particle_radius_m", "particle_radius_m applies to the screening fidelity only")
        half = 0.5 * particle_radius_m
        preset = replace(preset, shapes=(ShapeFraction("sphere", particle_radius_m, particle_radius_m, 1.0),),
                         aor_shapes=(ShapeFraction("pyramid", half, half, 1.0),), particles=None)
    if clump_aspect_ratio != 1.0:
        from engine.lab.shape import elongated_shapes

        preset = replace(preset, shapes=elongated_shapes(clump_aspect_ratio, preset.shapes), particles=None)
    return preset
