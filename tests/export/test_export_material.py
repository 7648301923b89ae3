"""The export's material structure: built from a lab job's parameters, and back for the proof run."""
from __future__ import annotations

import pytest

from calibration.export.material import ExportMaterial, from_micro_parameters
from calibration.export.verify import to_micro_parameters
from engine.lab.spec import MicroParameters


def test_screening_spheres_round_trip_to_the_lab():
    params = MicroParameters(friction_pp=0.5, effects={"rolling_epsd2": {"rolling_friction": 0.2}})
    material = from_micro_parameters(params)
    assert [s.radius_m for s in material.particles.spheres] == [0.020]  # the screening preset's spheres
    back = to_micro_parameters(material)
    assert back.particle_radius_m == 0.020 and back.friction_pp == 0.5
    assert back.effects == {"rolling_epsd2": {"rolling_friction": 0.2}}


def test_screening_clump_round_trip_keeps_the_grain():
    material = from_micro_parameters(MicroParameters(clump_aspect_ratio=1.5))
    back = to_micro_parameters(material)
    # the two-sphere clump of aspect ratio 1.5 keeps the 20 mm sphere's solid volume (engine/lab/shape.py)
    assert back.clump_aspect_ratio == pytest.approx(1.5, rel=1e-12)
    assert back.particle_radius_m == pytest.approx(0.020, rel=1e-12)


def test_thesis_size_ranges_become_volume_weighted_bins():
    material = from_micro_parameters(MicroParameters(), "thesis")
    spheres = material.particles.spheres
    # Table 4.9's sphere class: 15-16.2 mm, 20.8 % of the solid volume, three bins at 15.2, 15.6 and 16.0 mm
    assert [round(s.radius_m * 1000, 3) for s in spheres] == [15.2, 15.6, 16.0]
    assert sum(s.volume_fraction for s in spheres) == pytest.approx(0.208, rel=1e-9)
    assert len(material.particles.clumps) == 6 and len(material.notes) == 3


def test_the_proof_refuses_a_mix_it_cannot_run():
    with pytest.raises(ValueError, match="one sphere size or one two-sphere clump"):
        to_micro_parameters(from_micro_parameters(MicroParameters(), "thesis"))
    with pytest.raises(ValueError, match="damping ratio"):
        to_micro_parameters(ExportMaterial.model_validate({
            "particles": {"solid_density_kg_m3": 2500.0, "spheres": [{"radius_m": 0.02, "volume_fraction": 1.0}]},
            "contact": {"particle_stiffness_n_per_m": 1e6, "wall_stiffness_n_per_m": 1e7, "damping_ratio_normal": 0.5,
                        "damping_ratio_shear": 0.2, "friction_pp": 0.5, "friction_pw": 0.3}}))


def test_a_boolean_is_not_a_number():
    with pytest.raises(ValueError, match="friction_pp"):
        ExportMaterial.model_validate({
            "particles": {"solid_density_kg_m3": 2500.0, "spheres": [{"radius_m": 0.02, "volume_fraction": 1.0}]},
            "contact": {"particle_stiffness_n_per_m": 1e6, "wall_stiffness_n_per_m": 1e7, "damping_ratio_normal": 0.5,
                        "damping_ratio_shear": 0.5, "friction_pp": False, "friction_pw": 0.3}})


def _material_set_up(shapes):
    from engine.lab.resolution import setup_for
    from engine.lab.rigs import bundled_rig, rig_json
    from engine.lab.spec import JobSpec

    return setup_for(JobSpec(test="fill", resolution="as_measured", rig=rig_json(bundled_rig("appendix-a-400mm-shear-box")),
                             particles={"shapes": shapes}))


def test_a_uniform_size_becomes_three_equally_likely_sizes_weighted_by_volume():
    """Radii uniform in 19-21 mm (the LIGGGHTS comparison's spheres): three equal-width bins, each with a third
    of the number, at 19 1/3, 20 and 20 2/3 mm; their volume shares are r^3 / sum r^3."""
    setup = _material_set_up([{"shape": "sphere", "volume_fraction": 1.0,
                               "size": {"form": "uniform", "radius_min_m": 0.019, "radius_max_m": 0.021}}])
    material = from_micro_parameters(MicroParameters(), "as_measured", setup=setup)
    radii = [0.019 + 0.002 * (k + 0.5) / 3 for k in range(3)]
    assert [s.radius_m for s in material.particles.spheres] == pytest.approx(radii, rel=1e-12)
    cubes = [r ** 3 for r in radii]
    assert [s.volume_fraction for s in material.particles.spheres] == pytest.approx([c / sum(cubes) for c in cubes])


def test_a_sized_custom_clump_is_exported_at_its_drawn_sizes():
    """A custom two-sphere clump (radii 10 and 5 mm, centres 15 mm apart: touching) with its largest sphere's
    radius between 9 and 11 mm: each exported body keeps the template's shape, the small sphere half the large."""
    clump = {"shape": "custom", "volume_fraction": 1.0, "sphere_centres_m": [[0, 0, 0], [0.015, 0, 0]],
             "sphere_radii_m": [0.010, 0.005], "size": {"form": "uniform", "radius_min_m": 0.009, "radius_max_m": 0.011}}
    material = from_micro_parameters(MicroParameters(), "as_measured", setup=_material_set_up([clump]))
    bodies = material.particles.clumps
    assert len(bodies) == 3
    for body in bodies:
        large, small = sorted(body.sphere_radii_m, reverse=True)
        assert small == pytest.approx(0.5 * large, rel=1e-12) and 0.009 < large < 0.011
        gap = [a - b for a, b in zip(body.sphere_centres_m[0], body.sphere_centres_m[1])]
        assert sum(g * g for g in gap) ** 0.5 == pytest.approx(1.5 * large, rel=1e-12)
