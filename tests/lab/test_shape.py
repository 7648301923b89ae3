"""Particle shape: a mix's spheres made two-sphere clumps of a given elongation (engine/lab/shape.py), at the
screening fidelity (every grain) and the thesis fidelity (its round grains, Table 4.2's 20.8 %).

Analytic: two equal spheres of radius r at centre distance d are (d + 2 r) / (2 r) long per width, and
their union has the volume 2 (4/3) pi r^3 - pi (4 r + d) (2 r - d)^2 / 12 (the shared lens once).
"""
import math

import numpy as np
import pytest

from engine.candidates import get as candidate
from engine.lab.context import RunContext
from engine.lab.presets import SCREENING, THESIS, fidelity
from engine.lab.procedures.fill import rain_packing, shape_mix
from engine.lab.shape import CANDIDATE, aspect_ratio_of, elongated_clump, screening_shapes
from engine.lab.spec import JobSpec
from engine.particles.templates import sphere

RATIOS = [1.05, 1.2, 1.5, 1.8, 2.0]


def _extent(template, direction):
    """Extent of the sphere union along a unit direction: max minus min of (centre . u) -+ r."""
    proj = template.sphere_offsets_m @ np.asarray(direction, float)
    return float(np.max(proj + template.sphere_radii_m) - np.min(proj - template.sphere_radii_m))


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("radius_m", [0.02, 0.0125])
def test_clump_has_the_requested_elongation_and_the_sphere_volume(ratio, radius_m):
    t = elongated_clump(ratio, radius_m)
    assert t.n_spheres == 2
    r = float(t.sphere_radii_m[0])
    assert t.sphere_radii_m[1] == r
    # bounding length along the principal axis of the two centres, width across it
    axis = t.sphere_offsets_m[1] - t.sphere_offsets_m[0]
    axis = axis / np.linalg.norm(axis)
    across = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    across /= np.linalg.norm(across)
    length, width = _extent(t, axis), _extent(t, across)
    assert width == pytest.approx(2 * r, rel=1e-12)
    assert length / width == pytest.approx(ratio, rel=1e-9)
    assert aspect_ratio_of(t) == pytest.approx(ratio, rel=1e-9)
    # volume: the overlap-corrected union equals the sphere it replaces
    v_sphere = 4.0 / 3.0 * math.pi * radius_m**3
    assert t.volume_m3 == pytest.approx(v_sphere, rel=1e-3)
    d = float(np.linalg.norm(t.sphere_offsets_m[1] - t.sphere_offsets_m[0]))
    union = 2 * 4 / 3 * math.pi * r**3 - math.pi * (4 * r + d) * (2 * r - d) ** 2 / 12
    assert union == pytest.approx(v_sphere, rel=1e-9)
    # the centre of mass is midway between the spheres (the template's origin)
    assert np.allclose(t.sphere_offsets_m.sum(axis=0), 0.0, atol=1e-15)


def test_longer_clumps_have_smaller_spheres():
    radii = [float(elongated_clump(a, 0.02).sphere_radii_m[0]) for a in RATIOS]
    assert all(b < a for a, b in zip(radii, radii[1:]))
    # aspect ratio 2: two touching spheres, each of half the volume: r = R / 2^(1/3)
    assert radii[-1] == pytest.approx(0.02 / 2 ** (1 / 3), rel=1e-12)


def test_ratio_one_is_todays_screening_preset_and_fill_bit_for_bit():
    assert elongated_clump(1.0, 0.02).volume_m3 == sphere(0.02).volume_m3
    assert screening_shapes(1.0, 0.02) == SCREENING.shapes
    assert fidelity("screening") is SCREENING
    assert fidelity("screening", None, 1.0) is SCREENING
    default = RunContext.from_spec(JobSpec(seed=5))
    explicit = RunContext.from_spec(JobSpec(seed=5, parameters={"clump_aspect_ratio": 1.0}))
    assert explicit.preset == default.preset
    bulk = SCREENING.container_area_m2 * SCREENING.packing_height_m
    a, top_a = rain_packing(default.preset, 5, bulk, SCREENING.container_radius_m)
    b, top_b = rain_packing(explicit.preset, 5, bulk, SCREENING.container_radius_m)
    assert top_a == top_b and a.n_bodies == b.n_bodies
    assert np.array_equal(a.positions_m, b.positions_m) and np.array_equal(a.orientations, b.orientations)
    assert all(t.name == "sphere" and t.sphere_radii_m[0] == 0.02 for t in a.templates)


def test_screening_fill_rains_clumps_of_the_same_solid_volume():
    preset = RunContext.from_spec(JobSpec(parameters={"clump_aspect_ratio": 1.8})).preset
    assert preset.shapes[0].shape == "custom"
    mix = shape_mix(preset)
    templates, _ = mix.sample(np.random.default_rng(0), count=5)
    for t in templates:
        assert t.n_spheres == 2 and aspect_ratio_of(t) == pytest.approx(1.8)
        assert t.volume_m3 == pytest.approx(4 / 3 * math.pi * 0.02**3, rel=1e-12)
    bulk = preset.container_area_m2 * preset.packing_height_m
    packing, _ = rain_packing(preset, 1, bulk, preset.container_radius_m)
    spheres = rain_packing(SCREENING, 1, bulk, SCREENING.container_radius_m)[0]
    # same solid volume per grain, so about as many grains as spheres for the same solid volume
    assert packing.n_bodies == spheres.n_bodies
    centres, radii, body = packing.sphere_positions()
    assert len(radii) == 2 * packing.n_bodies
    # every sphere inside the rainfall column's cylinder
    assert np.all(np.hypot(centres[:, 0], centres[:, 1]) + radii <= preset.container_radius_m * (1 + 1e-9))


def test_particle_radius_and_aspect_ratio_combine():
    preset = fidelity("screening", 0.025, 1.5)
    t = preset.shapes[0].template
    assert t.volume_m3 == pytest.approx(4 / 3 * math.pi * 0.025**3, rel=1e-12)
    assert aspect_ratio_of(t) == pytest.approx(1.5)
    assert preset.aor_shapes == fidelity("screening", 0.025).aor_shapes


def test_the_thesis_mix_elongates_its_round_grains_only():
    preset = fidelity("thesis", None, 1.5)
    pyramids, clumps, round_grains = preset.shapes
    assert (pyramids, clumps) == THESIS.shapes[:2]  # the thesis's elongated clumps are already at C = 1
    spheres = THESIS.shapes[2]
    assert round_grains.shape == "custom" and round_grains.volume_fraction == spheres.volume_fraction
    t = round_grains.template
    assert aspect_ratio_of(t) == pytest.approx(1.5)
    # the smallest grain has the volume of the smallest sphere it replaces; the spread keeps its shape
    assert t.volume_m3 == pytest.approx(4 / 3 * math.pi * spheres.radius_min_m**3, rel=1e-12)
    assert round_grains.radius_max_m / round_grains.radius_min_m == pytest.approx(spheres.radius_max_m / spheres.radius_min_m)
    # as packed: every round grain a 1.5 clump with the volume of a sphere inside the thesis's radius range
    component = shape_mix(preset).components[2]
    grains = component.make(np.random.default_rng(3), 200)
    equivalent = np.array([(3 * g.volume_m3 / (4 * math.pi)) ** (1 / 3) for g in grains])
    assert all(aspect_ratio_of(g) == pytest.approx(1.5) for g in grains)
    assert equivalent.min() >= spheres.radius_min_m * (1 - 1e-9) and equivalent.max() <= spheres.radius_max_m * (1 + 1e-9)
    built = RunContext.from_spec(JobSpec(fidelity="thesis", parameters={"clump_aspect_ratio": 1.5})).preset.shapes
    assert [(s.shape, s.radius_min_m, s.radius_max_m, s.volume_fraction) for s in built] == \
        [(s.shape, s.radius_min_m, s.radius_max_m, s.volume_fraction) for s in preset.shapes]
    assert fidelity("thesis", None, 1.0) is THESIS
    assert CANDIDATE.applies_to("thesis") and CANDIDATE.applies_to("screening")


def test_beyond_two_spheres_that_touch_is_refused():
    with pytest.raises(ValueError, match="clump_aspect_ratio"):
        elongated_clump(2.5, 0.02)
    with pytest.raises(ValueError, match="clump_aspect_ratio"):
        RunContext.from_spec(JobSpec(parameters={"clump_aspect_ratio": 2.5}))
    with pytest.raises(ValueError):
        elongated_clump(0.9, 0.02)


def test_candidate_is_declared_and_its_plausible_range_is_buildable():
    assert candidate("particle_shape") is CANDIDATE
    assert CANDIDATE.factor == "clump_aspect_ratio"
    low, high = CANDIDATE.plausible_range
    for a in (low, high, CANDIDATE.off_value + CANDIDATE.step):
        assert aspect_ratio_of(elongated_clump(a, 0.02)) == pytest.approx(a)
