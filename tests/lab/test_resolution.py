"""Resolution instead of fidelity (issue 29 item 3): a material's particles, as measured or coarse-grained, in the
rig its measurements were made in; the old fidelity names as aliases of the presets. No DEM runs: set-ups,
the cost model's packing count and the analytic stand-in only (well under a second)."""
from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from calibration.conditions import run_spec
from calibration.settings import LoopSettings
from calibration.standin_job import run_analytic
from engine.lab import presets
from engine.lab.errors import SpecFieldError
from engine.lab.registry import get as get_test
from engine.lab.resolution import (Resolution, coarse_grained, factor_for_target, incomparable, largest_valid_factor,
                                   material_setup, packing_particles, scale_factor, setup_for)
from engine.lab.rigs import bundled_rig, rig_json
from engine.lab.spec import JobSpec
from engine.particles.description import Particles, thesis_particles

THESIS_RIG = "thesis-590mm-shear-box"
FACTORS = [{"name": "friction_pp", "low": 0.3, "high": 1.0}]
# a gravel of 8-16 mm sieve sizes, half spheres, half elongated clumps (issue 29's "material of your own")
GRAVEL = Particles.model_validate({
    "solid_density_kg_m3": 2650.0,
    "size": {"form": "sieve", "sieve_sizes_m": [0.008, 0.0112, 0.016], "passing_fractions": [0.0, 0.4, 1.0]},
    "shapes": [{"shape": "sphere", "volume_fraction": 0.5},
               {"shape": "elongated", "aspect_ratio": 1.8, "volume_fraction": 0.5}]})


def _material_spec(resolution, particles: Particles = thesis_particles(), **extra) -> JobSpec:
    return JobSpec.model_validate({"test": "fill", "resolution": resolution, "rig": rig_json(bundled_rig(THESIS_RIG)),
                                   "particles": particles.model_dump(mode="json", exclude_none=True), **extra})


def test_a_factor_of_two_leaves_an_eighth_of_the_particles():
    """In a container of fixed volume the count goes as 1/s^3: the cost model's packing estimate at sizes x 2
    is an eighth of the as-measured one (to the one particle its rounding up adds), and the factor proposed for
    that eighth as a target is 2."""
    rig = bundled_rig(THESIS_RIG)
    for particles in (thesis_particles(), GRAVEL):
        as_measured = packing_particles(rig, particles)
        doubled = packing_particles(rig, coarse_grained(particles, 2.0))
        assert doubled == pytest.approx(as_measured / 8.0, abs=1.0)
        assert factor_for_target(as_measured, as_measured / 8.0) == pytest.approx(2.0)
    assert factor_for_target(1000, 5000) == 1.0  # more particles than measured: as measured, never finer


def test_a_particle_target_proposes_the_factor_that_meets_it():
    rig = bundled_rig(THESIS_RIG)
    as_measured = packing_particles(rig, GRAVEL)
    target = as_measured // 27  # a factor of 3: within the standards for 16 mm grains in the 590 mm box
    factor, notes = scale_factor(rig, GRAVEL, Resolution(mode="coarse", target_particles=target))
    assert factor == pytest.approx((as_measured / target) ** (1 / 3)) and notes == []
    assert packing_particles(rig, coarse_grained(GRAVEL, factor)) == pytest.approx(target, rel=0.01)


def test_the_proposal_stops_at_the_direct_shear_standards_sizes():
    """The thesis's box was designed for its aggregate (largest particle: a pyramid of 10.5 mm spheres, 42 mm
    sieve size): 590 mm across is 14.0 of them and the 330 mm specimen 7.9; the standards' 10 and 6 allow sizes
    x min(590 / 420, 330 / 252) = x 1.31 at most. A target that needs more is met only that far, and said so."""
    rig, particles = bundled_rig(THESIS_RIG), thesis_particles()
    assert particles.largest_particle_size_m == pytest.approx(0.042)
    limit = min(0.590 / (10 * 0.042), 0.330 / (6 * 0.042))
    assert largest_valid_factor(rig, particles) == pytest.approx(limit)
    factor, notes = scale_factor(rig, particles, Resolution(mode="coarse", target_particles=100))
    assert factor == pytest.approx(limit) and "beyond" in notes[0] and THESIS_RIG in notes[0]
    # a factor the user sets beyond it runs, with the rig's warnings (the box is 5.6 particles across at x 2.5)
    setup, _ = material_setup(rig, particles, Resolution(mode="coarse", scale_factor=2.5))
    assert any("container_diameter_m" in w for w in setup.rig_warnings())


def test_coarse_graining_keeps_density_fractions_and_the_curves_shape():
    coarse = coarse_grained(GRAVEL, 1.5)
    assert coarse.solid_density_kg_m3 == GRAVEL.solid_density_kg_m3
    assert [s.volume_fraction for s in coarse.shapes] == [s.volume_fraction for s in GRAVEL.shapes]
    assert coarse.shapes[1].aspect_ratio == 1.8
    assert coarse.size.passing_fractions == GRAVEL.size.passing_fractions
    assert coarse.size.sieve_sizes_m == pytest.approx([0.012, 0.0168, 0.024])
    with pytest.raises(SpecFieldError) as err:  # 16 mm x 100 = 1.6 m: beyond the lab's largest particle
        coarse_grained(GRAVEL, 100.0)
    assert err.value.field == "resolution.scale_factor"


def test_the_thesis_aggregate_at_screening_runs_in_its_own_rig():
    """Issue 29's founding mismatch: 'screening' put the thesis aggregate in the 400 mm box and compared that
    box's bulk mass with the 590 mm box's measurement. At a coarse resolution the job runs in the rig the
    material was measured in: its container holds pi (0.295 m)^2 x 0.330 m = 0.0902 m^3 (chapter 3), so the
    stand-in's bulk mass is its bulk density times that volume, and nothing the apparatus sets is left out but the
    level the packing is struck off at."""
    settings = LoopSettings.model_validate({
        "resolution": {"mode": "coarse", "scale_factor": 1.3}, "factors": FACTORS,
        "rig": rig_json(bundled_rig(THESIS_RIG)), "particles": thesis_particles().model_dump(mode="json")})
    spec = run_spec(settings, {"friction_pp": 0.6}, 0)
    setup = setup_for(spec)
    volume_m3 = math.pi * 0.295 ** 2 * 0.330
    assert setup.rig_name == THESIS_RIG and setup.scale_factor == 1.3
    assert setup.container_area_m2 * setup.packing_height_m == pytest.approx(volume_m3)
    values = {p.quantity: p.value for p in run_analytic(spec).properties if not p.condition}
    assert values["bulk_mass_kg"] / values["bulk_density_kg_m3"] == pytest.approx(volume_m3)
    measured_rig, measured = bundled_rig(THESIS_RIG), thesis_particles()
    for test, quantity in (("fill", "bulk_mass_kg"), ("cct", "bulk_stiffness_n_per_m"),
                           ("anchor", "peak_pull_force_n")):
        assert incomparable(get_test(test).quantity(quantity), measured_rig, measured, setup) is None
    # struck off at the brim as the laboratory did (Table 4.5: 329-330 mm for the 330 mm level), the packing
    # height is the rig's level: a number of the apparatus, left out and said so; the presets keep the thesis's
    # DEM rule (the highest sphere top, Table 4.10's 340 mm), so there it is compared
    height = get_test("fill").quantity("packing_height_m")
    assert setup.fill_height_rule == "struck_off"
    assert "struck off at (0.33 m" in incomparable(height, measured_rig, measured, setup)
    assert presets.THESIS.fill_height_rule == "highest_sphere_top"
    assert incomparable(height, measured_rig, measured, presets.THESIS) is None
    # the old preset's box is 0.4 m wide and 0.37 m deep: another volume, so its bulk mass is left out, named
    old = setup_for(JobSpec(test="fill", fidelity="screening"))
    assert old.container_area_m2 * old.packing_height_m == pytest.approx(math.pi * 0.2 ** 2 * 0.37)
    why = incomparable(get_test("fill").quantity("bulk_mass_kg"), measured_rig, measured, old)
    assert "appendix-a-400mm-shear-box" in why and "shear_box" in why
    # a particle count scales as 1/s^3: not comparable once coarse-grained, comparable as measured
    count = get_test("fill").quantity("particle_count")
    assert "coarse-grained" in incomparable(count, measured_rig, measured, setup)
    assert incomparable(count, measured_rig, measured, setup_for(_material_spec("as_measured"))) is None
    assert incomparable(count, measured_rig, measured, presets.THESIS) is None


def test_old_fidelity_names_are_aliases_of_the_presets():
    for name in ("thesis", "screening"):
        by_alias = JobSpec.model_validate({"test": "fill", "resolution": name})
        assert by_alias.fidelity == name and setup_for(by_alias) is presets.FIDELITIES[name]
        assert JobSpec.model_validate(by_alias.model_dump(mode="json")) == by_alias  # round trip
        stored = JobSpec.model_validate({"test": "fill", "fidelity": name, "seed": 3})  # a job stored before
        assert stored.resolution is None and setup_for(stored) is presets.FIDELITIES[name]
        settings = LoopSettings.model_validate({"resolution": name, "factors": FACTORS})
        assert settings.fidelity == name and run_spec(settings, {"friction_pp": 0.5}, 0).fidelity == name
    material = _material_spec({"mode": "coarse", "target_particles": 2000})
    assert JobSpec.model_validate(material.model_dump(mode="json")) == material


@pytest.mark.parametrize("body, field", [
    ({"resolution": "fine"}, "resolution"),
    ({"resolution": {"mode": "coarse", "scale_factor": 0.5}}, "resolution"),
    ({"resolution": {"mode": "as_measured", "scale_factor": 2.0}}, "resolution"),
    ({"resolution": {"mode": "coarse", "scale_factor": 2.0, "target_particles": 900}}, "resolution"),
    ({"resolution": "coarse"}, "rig"),  # a material resolution needs the rig and the particles
    ({"resolution": "thesis", "rig": rig_json(bundled_rig(THESIS_RIG))}, "rig"),  # a preset brings its own
    ({"resolution": "thesis", "fidelity": "thesis"}, None),  # the same preset twice is fine
    ({"resolution": "screening", "fidelity": "thesis"}, "resolution"),
])
def test_bad_resolutions_are_refused_naming_the_field(body, field):
    if field is None:
        JobSpec.model_validate(body)
        return
    with pytest.raises(ValidationError) as err:
        JobSpec.model_validate(body)
    assert err.value.errors()[0]["loc"][0] == field


def test_a_screening_radius_is_refused_at_a_material_resolution():
    with pytest.raises(ValidationError) as err:
        _material_spec("as_measured", parameters={"particle_radius_m": 0.02})
    assert err.value.errors()[0]["loc"][0] == "resolution" and "particle_radius_m" in str(err.value)
    with pytest.raises(ValidationError):
        LoopSettings.model_validate({"resolution": "coarse", "factors": [
            {"name": "particle_radius_m", "low": 0.01, "high": 0.02}]})


def test_the_bundled_material_as_measured_is_the_thesis_preset():
    """The thesis tables' set-up is the bundled material's particles as measured in its own rig: the same
    apparatus and the same shapes, so either way the same batteries."""
    setup, notes = material_setup(bundled_rig(THESIS_RIG), thesis_particles(), "as_measured")
    assert notes == [] and setup.rig == presets.THESIS.rig and setup.scale_factor == 1.0
    assert [(s.shape, s.radius_min_m, s.radius_max_m, s.volume_fraction) for s in setup.shapes] == \
        [(s.shape, s.radius_min_m, s.radius_max_m, s.volume_fraction) for s in presets.THESIS.shapes]


def test_particles_that_fall_through_the_gap_are_refused_naming_particles():
    """0.4 mm spheres pass the thesis box's 1 mm gap: refused before any simulation, naming ``particles``."""
    from engine.lab.context import RunContext

    sand = Particles.model_validate({"size": {"form": "constant", "radius_m": 0.0002},
                                     "shapes": [{"shape": "sphere", "volume_fraction": 1.0}]})
    with pytest.raises(SpecFieldError) as err:
        RunContext.from_spec(_material_spec("as_measured", sand)).check_rig()
    assert err.value.field == "particles" and "shear_box.gap_m" in err.value.message


def _box_only_rig():
    """A 300 mm direct-shear laboratory (issue 29's "material of your own"): shear box and fill, nothing else."""
    from engine.lab.rigs import Rig

    record = rig_json(bundled_rig(THESIS_RIG))
    record.update(name="lab-300mm-shear-box", angle_of_repose=None, anchor=None)
    record["shear_box"].update(container_diameter_m=0.300, bottom_half_height_m=0.100, top_half_height_m=0.100,
                               shear_distance_m=0.040)
    record["fill"].update(level_height_m=0.200, drop_height_m=0.0)
    return Rig.model_validate({k: v for k, v in record.items() if v is not None})


def test_a_rig_with_only_a_shear_box_runs_the_tests_it_has():
    """A laboratory that only shears: the battery (fill, CCT, DST) runs in its 300 mm box, pi 0.15^2 x 0.2 m^3;
    asking for the angle of repose is refused naming ``rig``, the section it lacks named."""
    from engine.lab.context import RunContext

    rig = _box_only_rig()
    spec = JobSpec.model_validate({"test": "battery", "resolution": "as_measured", "rig": rig_json(rig),
                                   "particles": GRAVEL.model_dump(mode="json", exclude_none=True)})
    ctx = RunContext.from_spec(spec)
    ctx.validate()
    assert ctx.preset.container_area_m2 * ctx.preset.packing_height_m == pytest.approx(math.pi * 0.15 ** 2 * 0.2)
    # 16 mm grains: 18.8 across and 12.5 thick, within the standards
    assert ctx.preset.rig_warnings() == []
    with pytest.raises(SpecFieldError) as err:
        RunContext.from_spec(spec.model_copy(update={"options": spec.options.model_copy(
            update={"include_aor": True})})).validate()
    assert err.value.field == "rig" and "angle_of_repose" in err.value.message
