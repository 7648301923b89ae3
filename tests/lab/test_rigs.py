"""Rigs as data: the bundled records rebuild exactly the set-ups the fidelity presets were, from the numbers
the thesis prints (chapter 3-5, Table 3.1, Appendix A Table A.7), and a bad rig is refused naming its field."""
from __future__ import annotations

import json
import math

import pytest
from pydantic import ValidationError

from engine.lab import presets
from engine.lab.errors import SpecFieldError
from engine.lab.geometry import lid_wall, shear_box_walls
from engine.lab.rigs import RECORDS_DIR, Rig, bundled_rig, bundled_rigs, check_for_particles
from engine.particles.description import Particles, thesis_particles

THESIS_RIG = "thesis-590mm-shear-box"
APPENDIX_A_RIG = "appendix-a-400mm-shear-box"


def _record(name: str) -> dict:
    return json.loads(next(p for p in RECORDS_DIR.glob("*.json") if json.loads(p.read_text())["name"] == name)
                      .read_text())


def _error_loc(exc: ValidationError) -> tuple:
    return exc.errors()[0]["loc"]


def test_bundled_records_are_the_two_rigs_the_fidelities_name():
    assert set(bundled_rigs()) == {THESIS_RIG, APPENDIX_A_RIG}
    assert presets.FIDELITY_RIGS == {"thesis": THESIS_RIG, "screening": APPENDIX_A_RIG}
    assert presets.THESIS.rig_name == THESIS_RIG and presets.SCREENING.rig_name == APPENDIX_A_RIG


def test_thesis_preset_is_the_590mm_box_of_the_thesis():
    t = presets.THESIS
    # chapter 3 / section 4.5: 590 mm inner diameter, 330 mm deep, split at 165 mm with a 1 mm DEM gap
    assert t.container_diameter_m == 0.590 and t.container_radius_m == 0.295
    assert t.container_height_m == 0.330 and t.packing_height_m == 0.330
    assert t.split_height_m == 0.165 and t.gap_m == 0.001
    assert t.lid_start_gap_m == 0.030  # lid started 30 mm above the packing
    # Table 3.1: 10.5, 24.0, 38.3, 52.4 kPa; CCT to 65.6 kPa
    assert t.dst_normal_stresses_pa == (10.5e3, 24.0e3, 38.3e3, 52.4e3)
    assert t.cct_max_stress_pa == 65.6e3 and t.cct_cycles == 4
    assert (t.lab_lid_speed_m_s, t.lab_shear_speed_m_s, t.shear_distance_m) == (0.001, 0.001, 0.070)
    # particles poured from 0.1-4.7 m: the ~1 m simulated column starts 1.9 m higher
    assert t.rain_drop_height_m == 1.9
    # section 5.2: bucket 260/290 mm diameter, 370 mm high, plastic 0.67 on plywood 0.86, lifted at 5 mm/s
    a = t.aor
    assert (a.bucket_bottom_radius_m, a.bucket_top_radius_m, a.bucket_height_m) == (0.130, 0.145, 0.370)
    assert (a.lift_speed_m_s, a.bucket_friction, a.floor_friction, a.wide_end_down) == (0.005, 0.67, 0.86, False)
    # Table 5.4 / 5.3.1: 50 mm tube 1 m long on a 110 x 5 mm plate, 320 mm packing, 27 mm/s, bare steel 0.54
    n = t.anchor
    assert (n.tube_width_m, n.tube_length_m, n.plate_width_m, n.plate_thickness_m) == (0.050, 1.0, 0.110, 0.005)
    assert (n.packing_height_m, n.pull_speed_m_s, n.anchor_friction) == (0.320, 0.027, 0.54)
    # Table 4.2 / 4.9: the clump mix, radii Gaussian between R_min and R_max
    assert [(s.shape, s.radius_min_m, s.radius_max_m, s.volume_fraction) for s in t.shapes] == [
        ("pyramid", 0.0075, 0.0105, 0.375), ("double_clump", 0.0120, 0.0150, 0.417), ("sphere", 0.0150, 0.0162, 0.208)]
    assert all(s.size is None and s.overlap_factor == 1.0 for s in t.shapes)  # C = 1, Table 4.2
    assert t.default_speed_factor == 10.0


def test_screening_preset_is_appendix_a_400mm_box():
    s = presets.SCREENING
    # Table A.7: container radius 200 mm, packing depth 370 mm, spheres of radius 20 mm
    assert s.container_radius_m == 0.200 and s.packing_height_m == 0.370 and s.split_height_m == 0.185
    assert [(x.shape, x.radius_min_m, x.radius_max_m, x.volume_fraction) for x in s.shapes] == [
        ("sphere", 0.020, 0.020, 1.0)]
    # DST loads 1,885 / 3,495 / 5,105 / 6,760 N and the CCT's 8,415 N over pi (0.2 m)^2
    area = math.pi * 0.200 ** 2
    assert s.dst_normal_stresses_pa == tuple(f / area for f in (1885.0, 3495.0, 5105.0, 6760.0))
    assert s.cct_max_stress_pa == 8415.0 / area
    assert s.cct_max_stress_pa == pytest.approx(67.0e3, abs=50)  # "67.0 kPa" (presets docstring, by hand)
    assert s.shear_distance_m == 0.042 and s.default_speed_factor == 40.0 and s.rain_drop_height_m == 0.0
    # the thesis's bucket scaled by 0.6 on its wide rim, lifted at 20 mm/s; pyramids of half the radius
    a = s.aor
    assert (a.bucket_bottom_radius_m, a.bucket_top_radius_m, a.bucket_height_m, a.fill_height_m) == (
        0.6 * 0.130, 0.6 * 0.145, 0.6 * 0.370, 0.6 * 0.370)
    assert (a.scale, a.wide_end_down, a.lift_speed_m_s) == (1.0, True, 0.02)
    assert s.aor_shapes[0].shape == "pyramid" and s.aor_shapes[0].radius_min_m == 0.010
    assert s.anchor.bin_width_m == 0.40


def test_walls_come_from_the_record():
    """The geometry built from the rig: a floor disc of the record's radius, the halves split at 165 mm + 1 mm."""
    walls = {w.name: w for w in shear_box_walls(presets.THESIS, 1.5, 1e7, 0.62, 0.0075, 0.1)}
    assert walls["floor"].geometry.radius_m == 0.295
    assert walls["bottom_cylinder"].geometry.height_m == 0.165
    assert walls["top_cylinder"].geometry.base_m[2] == pytest.approx(0.166)
    assert lid_wall(presets.SCREENING, 0.4, 1e7, 0.62).geometry.radius_m == 0.200


def test_fidelity_aliases_keep_their_options():
    assert presets.fidelity("thesis") is presets.THESIS
    assert presets.fidelity("screening", 0.025).shapes[0].radius_min_m == 0.025
    with pytest.raises(SpecFieldError) as err:
        presets.fidelity("thesis", 0.025)
    assert err.value.field == "parameters.particle_radius_m"


def _rig(**changes) -> dict:
    body = _record(THESIS_RIG)
    body["name"] = "my rig"
    for path, value in changes.items():
        section, key = path.split("__")
        body[section][key] = value
    return body


@pytest.mark.parametrize("path, value, loc", [
    ("shear_box__container_diameter_m", -0.3, ("shear_box", "container_diameter_m")),
    ("shear_box__bottom_half_height_m", 0.0, ("shear_box", "bottom_half_height_m")),
    ("shear_box__gap_m", 0.2, ("shear_box", "gap_m")),  # wider than a 165 mm half
    ("shear_box__shear_distance_m", 0.6, ("shear_box", "shear_distance_m")),  # past the 590 mm box
    ("angle_of_repose__fill_height_m", 0.5, ("angle_of_repose", "fill_height_m")),  # above the 370 mm rim
    ("anchor__bin_width_m", 0.1, ("anchor", "bin_width_m")),  # narrower than the 110 mm plate
    ("fill__level_height_m", 0.4, ("fill",)),  # above the 330 mm brim
    ("fill__height_rule", "by eye", ("fill", "height_rule")),  # neither the laboratory's nor the thesis DEM's
])
def test_bad_rig_is_refused_naming_the_field(path, value, loc):
    with pytest.raises(ValidationError) as err:
        Rig.model_validate(_rig(**{path: value}))
    assert _error_loc(err.value)[:len(loc)] == loc


def test_loads_beyond_the_rigs_range_are_refused_naming_the_load():
    # a 10 kN loading system on the 590 mm box: 52.4 kPa x pi 0.295^2 = 14.3 kN is beyond it, 38.3 kPa (10.5 kN)
    # too; 24 kPa (6.6 kN) is within
    body = _rig(shear_box__max_normal_force_n=10_000.0)
    with pytest.raises(ValidationError) as err:
        Rig.model_validate(body)
    assert _error_loc(err.value) == ("shear_box", "dst_normal_stresses_pa")
    assert "load 3" in str(err.value) and "10000 N" in str(err.value)
    body["shear_box"]["dst_normal_stresses_pa"] = [10.5e3, 24.0e3]
    body["shear_box"]["cct_max_stress_pa"] = 65.6e3  # 17.9 kN
    with pytest.raises(ValidationError) as err:
        Rig.model_validate(body)
    assert _error_loc(err.value) == ("shear_box", "cct_max_stress_pa")
    body["shear_box"]["cct_max_stress_pa"] = 30e3  # 8.2 kN
    assert Rig.model_validate(body).shear_box.max_normal_force_n == 10_000.0


def test_stresses_or_forces_not_both():
    body = _rig(shear_box__dst_normal_forces_n=[1000.0, 2000.0])
    with pytest.raises(ValidationError, match="exactly one of dst_normal_stresses_pa and dst_normal_forces_n"):
        Rig.model_validate(body)


def test_gap_a_particle_falls_through_is_refused_naming_the_gap():
    spheres = Particles.model_validate({"shapes": [{"shape": "sphere", "volume_fraction": 1.0,
                                                    "size": {"form": "constant", "radius_m": 0.002}}]})
    rig = Rig.model_validate(_rig(shear_box__gap_m=0.005))  # the thesis's experimental 5 mm gap
    with pytest.raises(SpecFieldError) as err:
        check_for_particles(rig, spheres)  # 4 mm spheres
    assert err.value.field == "shear_box.gap_m"
    assert check_for_particles(bundled_rig(THESIS_RIG), spheres) == []  # 1 mm gap


def test_too_small_box_is_accepted_with_a_warning():
    # the thesis aggregate's largest particle: a pyramid of 10.5 mm spheres passes a 4 x 10.5 = 42 mm hole
    aggregate = thesis_particles()
    assert aggregate.largest_particle_size_m == pytest.approx(0.042)
    # its own box: 590 mm >= 10 x 42 mm and a 330 mm specimen >= 6 x 42 mm
    assert check_for_particles(bundled_rig(THESIS_RIG), aggregate) == []
    # Appendix A's 400 mm box is 9.5 of them across (< 10); its 370 mm specimen is 8.8 thick (>= 6)
    warnings = check_for_particles(bundled_rig(APPENDIX_A_RIG), aggregate)
    assert len(warnings) == 1 and warnings[0].startswith("shear_box.container_diameter_m")
    # a 300 mm box filled 200 mm deep: 7.1 across and 4.8 thick, both warned
    small = Rig.model_validate(_rig(shear_box__container_diameter_m=0.300, shear_box__bottom_half_height_m=0.100,
                                    shear_box__top_half_height_m=0.100, fill__level_height_m=0.200))
    assert [w.split(":")[0] for w in check_for_particles(small, aggregate)] == [
        "shear_box.container_diameter_m", "fill.level_height_m"]


def test_job_checks_its_rig_against_its_particles():
    from engine.lab.context import RunContext
    from engine.lab.spec import JobSpec

    def ctx(**parameters):
        return RunContext.from_spec(JobSpec.model_validate({"test": "fill", "fidelity": "screening",
                                                            "parameters": parameters}))

    # 0.8 mm spheres fall through the 1 mm gap: refused naming the spec field that sets them
    with pytest.raises(SpecFieldError) as err:
        ctx(particle_radius_m=0.0004).validate()
    assert err.value.field == "parameters.particle_radius_m" and "shear_box.gap_m" in err.value.message
    # 60 mm spheres: the 400 mm box is 6.7 across (< 10), run with a warning the result carries
    big = ctx(particle_radius_m=0.030)
    big.validate()
    assert len(big.warnings) == 1 and "shear_box.container_diameter_m" in big.warnings[0]
    # the presets as they are: no warning (400 mm / 40 mm spheres = 10; 590 mm / 42 mm = 14)
    plain = ctx()
    plain.validate()
    assert plain.warnings == []


def test_a_materials_particles_reach_the_fill():
    """A sieve curve and a custom clump go through the lab's shape list into the fill's mix unchanged."""
    from dataclasses import replace

    import numpy as np

    from engine.lab.procedures.fill import shape_mix

    gravel = Particles.model_validate({
        "size": {"form": "sieve", "sieve_sizes_m": [0.008, 0.016], "passing_fractions": [0.0, 1.0]},
        "shapes": [{"shape": "sphere", "volume_fraction": 0.5},
                   {"shape": "custom", "volume_fraction": 0.5, "sphere_centres_m": [[0, 0, 0], [0.01, 0, 0]],
                    "sphere_radii_m": [0.01, 0.005]}]})
    preset = replace(presets.SCREENING, shapes=presets.shape_fractions(gravel))
    templates, component = shape_mix(preset).sample(np.random.default_rng(3), count=400)
    largest = np.array([float(max(t.sphere_radii_m)) for t in templates])
    # every body's largest sphere is drawn from the 8-16 mm curve (radii 4-8 mm), the custom clump scaled to it
    assert np.all((largest >= 0.004) & (largest <= 0.008))
    custom = [t for t, k in zip(templates, component) if k == 1]
    assert custom and all(t.n_spheres == 2 and np.isclose(min(t.sphere_radii_m) / max(t.sphere_radii_m), 0.5)
                          for t in custom)
    # the check sees the same particles: a 8 mm sphere is the smallest, the custom clump end on 16 mm the largest
    assert presets.particles_of(preset.shapes).largest_particle_size_m == pytest.approx(0.016)


def test_job_loads_beyond_the_rigs_range_are_refused():
    """A rig with a 20 kN loading system: the 590 mm box's 65.6 kPa CCT (17.9 kN) runs, 80 kPa (21.9 kN) not."""
    from dataclasses import replace

    from engine.lab.context import RunContext
    from engine.lab.spec import JobSpec

    body = _record(THESIS_RIG)
    body["shear_box"]["max_normal_force_n"] = 20_000.0
    preset = replace(presets.THESIS, rig=Rig.model_validate(body))

    def ctx(**options):
        return RunContext(JobSpec.model_validate({"test": "cct", "fidelity": "thesis", "options": options}), preset)

    ctx().validate()
    with pytest.raises(SpecFieldError) as err:
        ctx(cct_max_stress_pa=80e3).validate()
    assert err.value.field == "options.cct_max_stress_pa" and "20000 N" in err.value.message
    with pytest.raises(SpecFieldError) as err:
        ctx(dst_normal_stresses_pa=[10e3, 80e3]).validate()
    assert err.value.field == "options.dst_normal_stresses_pa"
