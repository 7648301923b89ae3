"""The CCT's unload-reload modulus (options.cct_unload_reload_stresses_pa) against analytic cases.

The reducer on a synthetic record: a small unloading at a known modulus, with the stress jump that reversing the
lid sends through the packing at its first sample. The procedure on the analytic packing: one layer of spheres,
apart from each other, resting on the floor and pressed by the lid (as tests/export/test_paired_cct.py's layer).
Each sphere is two particle-wall contacts in series carrying the same force F = sigma A / N (the floor's also
the sphere's weight), so the layer's unloading modulus is E_ur = N k_series H / A with H = 2 r:
* linear springs (PFC-style, demcal's wall contact k_pw = kp kw / (kp + kw)): k_series = k_pw / 2 at every stress;
* Hertz (a sphere on a flat wall, R* = r, E* from the sphere's and the wall's moduli): a contact's overlap is
  delta(F) = (3 F / (4 E* sqrt(r)))^(2/3), so the layer's strain is eps(sigma) = (delta(F) + delta(F + m g)) / H
  and E_ur between two stresses is the secant of that curve; its stiffness grows as F^(1/3).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from engine.effects.hertz_mindlin import Params as HertzParams
from engine.effects.hertz_mindlin import pair_props
from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.geometry import lid_wall, shear_box_walls
from engine.lab.procedures.lid import (UNLOAD_RELOAD_FRACTION, LidRecord, hold_stress, load_to, place_lid,
                                       unload_slowly)
from engine.lab.reducers.cct import UNLOAD_RELOAD_SKIP_FRACTION, reduce_unload_reload, unload_reload_modulus
from engine.lab.spec import JobSpec
from engine.particles.generation import Packing
from engine.particles.templates import sphere

RADIUS_M = 0.02
KP_N_M = 2.0e6
KW_N_M = 10.0e6
DENSITY_KG_M3 = 2650.0
YOUNG_PA = 1.0e9
POISSON = 0.25


def test_the_reducer_reads_the_slope_past_the_reversal_jump():
    """A small unloading at E = 20 MPa whose first sample dropped by a jump of 30 % of the drop (the bulk's
    impedance): the fit past the first fifth of the drop reads 20 MPa exactly; fitting everything reads it stiffer."""
    modulus, top, drop = 20.0e6, 30.0e3, 3.0e3
    jump = 0.3 * drop
    stress = np.concatenate([[top], top - jump - np.linspace(0.0, drop - jump, 40)])
    strain = np.concatenate([[1.0e-3], 1.0e-3 - np.linspace(0.0, drop - jump, 40) / modulus])
    assert unload_reload_modulus(strain, stress) == pytest.approx(modulus, rel=1e-9)
    assert unload_reload_modulus(strain, stress, skip_fraction=0.0) > 1.05 * modulus
    assert math.isnan(unload_reload_modulus(strain[:2], stress[:2]))


def test_a_stress_whose_unloading_gave_no_modulus_is_left_out_of_both_lists():
    """Two held stresses in one record: the first unloading linear at 12 MPa, the second two samples long (NaN):
    only the first stress and its modulus are reported, paired."""
    modulus = 12.0e6
    first = 20.0e3 - np.linspace(0.0, 2.0e3, 30)
    stress = np.concatenate([first, [40.0e3, 39.0e3]])
    strain = np.concatenate([2.0e-3 - (20.0e3 - first) / modulus, [3.0e-3, 2.9e-3]])
    out = reduce_unload_reload(strain, stress, [20.0e3, 40.0e3], [(0, 30), (30, 32)])
    assert out.stress_pa == [20.0e3]
    assert out.modulus_pa == [pytest.approx(modulus, rel=1e-9)]


def _layer_run(parameters: dict, stresses_pa: list[float]):
    """The layer under the lid in the screening box: per stress, load, hold and unload slowly as the CCT does; the
    record, each unloading's index range, the sphere count and the box's area."""
    ctx = RunContext.from_spec(JobSpec(test="cct", fidelity="screening", seed=1, parameters=parameters))
    preset = ctx.preset
    spacing = 2.5 * RADIUS_M
    reach = preset.container_radius_m - 1.5 * RADIUS_M
    grid = np.arange(-reach, reach + 1e-9, spacing)
    xy = np.array([(x, y) for x in grid for y in grid if math.hypot(x, y) <= reach])
    positions = np.column_stack([xy, np.full(len(xy), RADIUS_M)])
    packing = Packing(templates=[sphere(RADIUS_M)], template_index=np.zeros(len(xy), np.int64),
                      positions_m=positions, orientations=np.tile([1.0, 0.0, 0.0, 0.0], (len(xy), 1)))
    params = ctx.spec.parameters
    walls = shear_box_walls(preset, 0.2, params.wall_stiffness_n_per_m, params.friction_pw, RADIUS_M,
                            ring_width_m=3 * RADIUS_M)
    walls.append(lid_wall(preset, 0.15, params.wall_stiffness_n_per_m, params.friction_pw))
    sim = labsim.new_simulation(params, walls, packing)
    labsim.settle(ctx, sim, "layer: settling", min_time_s=0.02, max_time_s=1.0)
    height = float(np.max(labsim.sphere_tops_m(sim)))
    place_lid(sim, RADIUS_M)
    record, ranges = LidRecord(), []
    for target in stresses_pa:
        load_to(ctx, sim, target, ctx.lid_speed_m_s, record, 1, "layer: loading", height, 0.5 * height)
        hold_stress(ctx, sim, target, ctx.lid_speed_m_s, "layer: holding")
        # the layer's own modulus sets the speed and sampling (any estimate of the right order does)
        expected = len(xy) * 0.5 * KP_N_M * height / preset.container_area_m2
        density = float(np.sum(sim.body_masses_kg())) / (preset.container_area_m2 * height)
        ranges.append(unload_slowly(ctx, sim, math.sqrt(density * expected), expected, height, record, 1,
                                    "layer: unloading"))
    return record, ranges, len(xy), preset.container_area_m2, height


def _modulus(record: LidRecord, rng: tuple[int, int], height_m: float) -> tuple[float, np.ndarray]:
    a, b = rng
    stress = np.asarray(record.normal_stress_pa[a:b])
    strain = -np.asarray(record.lid_z_m[a:b]) / height_m  # up to a constant: the slope is what counts
    return unload_reload_modulus(strain, stress), stress


@pytest.mark.slow
def test_a_layer_of_linear_springs_unloads_at_its_series_stiffness_at_every_stress():
    parameters = {"particle_density_kg_m3": DENSITY_KG_M3, "particle_stiffness_n_per_m": KP_N_M,
                  "wall_stiffness_n_per_m": KW_N_M, "friction_pp": 0.5, "friction_pw": 0.5}
    record, ranges, n, area, height = _layer_run(parameters, [5.0e3, 40.0e3])
    k_pw = KP_N_M * KW_N_M / (KP_N_M + KW_N_M)
    expected = n * 0.5 * k_pw * height / area
    for rng in ranges:
        modulus, stress = _modulus(record, rng, height)
        assert stress[0] - stress.min() >= 0.99 * UNLOAD_RELOAD_FRACTION * stress[0]  # the drop was made
        assert rng[1] - rng[0] >= 20  # tens of samples
        assert modulus == pytest.approx(expected, rel=0.01)


@pytest.mark.slow
def test_a_layer_of_hertzian_contacts_unloads_stiffer_as_the_cube_root_of_its_stress():
    parameters = {"particle_density_kg_m3": DENSITY_KG_M3, "particle_stiffness_n_per_m": KP_N_M,
                  "wall_stiffness_n_per_m": KW_N_M, "friction_pp": 0.5, "friction_pw": 0.5,
                  "effects": {"hertz_mindlin": {"young_modulus_pa": YOUNG_PA, "poisson_ratio": POISSON}}}
    record, ranges, n, area, height = _layer_run(parameters, [5.0e3, 40.0e3])
    e_star, _ = pair_props(HertzParams(young_modulus_pa=YOUNG_PA, poisson_ratio=POISSON), "particle-wall", None, None)
    weight_n = DENSITY_KG_M3 * 4.0 / 3.0 * math.pi * RADIUS_M**3 * 9.81

    def strain(sigma_pa: float) -> float:
        force = sigma_pa * area / n
        overlap = lambda f: (3.0 * f / (4.0 * e_star * math.sqrt(RADIUS_M))) ** (2.0 / 3.0)  # noqa: E731
        return (overlap(force) + overlap(force + weight_n)) / height

    moduli = []
    for rng in ranges:
        modulus, stress = _modulus(record, rng, height)
        # the secant over the stresses the reducer fits: past the first fifth of the drop, to its end
        top, bottom = stress[0], stress.min()
        upper = top - UNLOAD_RELOAD_SKIP_FRACTION * (top - bottom)
        expected = (upper - bottom) / (strain(upper) - strain(bottom))
        assert modulus == pytest.approx(expected, rel=0.02)
        moduli.append(modulus)
    # a factor 8 in stress is a factor 8^(1/3) = 2 in the contacts' stiffness (the weight's share aside)
    assert moduli[1] / moduli[0] == pytest.approx(2.0, rel=0.03)


def test_unload_reload_stresses_are_refused_naming_the_field():
    from pydantic import ValidationError

    from engine.lab.errors import SpecFieldError

    with pytest.raises(ValidationError, match="strictly increasing"):
        JobSpec(test="cct", options={"cct_unload_reload_stresses_pa": [30e3, 10e3]})
    with pytest.raises(ValidationError, match="no unload-reload"):
        JobSpec(test="cct", options={"cct_unload_reload_stresses_pa": []})
    # above the CCT's peak (67 kPa on the screening box) nothing could be held there
    with pytest.raises(SpecFieldError) as refused:
        RunContext.from_spec(JobSpec(test="cct", options={"cct_unload_reload_stresses_pa": [1.0e5]})).validate()
    assert refused.value.field == "options.cct_unload_reload_stresses_pa"


@pytest.mark.slow
def test_a_cct_packing_asked_for_unload_reload_reports_it_without_changing_its_cycles():
    """A screening CCT on a poured packing, asked for E_ur at 10 and 40 kPa: a property and a curve point at exactly
    those stresses, each stiffer than the loading E' at the same stress (unloading is elastic, loading also slides
    and rearranges contacts: Schanz et al. 1999), and the cycles' E' the same as without the option (the loops
    come after the cycles are reduced; same seed, same packing)."""
    from engine.lab.battery import run_job

    stresses = [10.0e3, 40.0e3]
    parameters = {"particle_density_kg_m3": DENSITY_KG_M3, "particle_stiffness_n_per_m": KP_N_M,
                  "friction_pp": 0.6, "friction_pw": 0.5}
    options = {"cct_window_stresses_pa": stresses}
    plain = run_job(JobSpec(test="cct", fidelity="screening", seed=2, parameters=parameters, options=options))
    asked = run_job(JobSpec(test="cct", fidelity="screening", seed=2, parameters=parameters,
                            options={**options, "cct_unload_reload_stresses_pa": stresses}))
    assert asked.value("cct", "confined_modulus_pa") == plain.value("cct", "confined_modulus_pa")
    for stress in stresses:
        loading = asked.value("cct", "confined_modulus_pa", normal_stress_pa=stress)
        assert loading == plain.value("cct", "confined_modulus_pa", normal_stress_pa=stress)
        assert asked.value("cct", "unload_reload_modulus_pa", normal_stress_pa=stress) > loading
    assert asked.curves["cct_unload_reload_modulus_vs_stress"]["normal_stress_pa"] == stresses
    assert "cct_unload_reload_modulus_vs_stress" not in plain.curves


class _LidOff:
    """A simulation whose lid carries no load: the state the servo left a stirred packing in (session 32)."""

    time_s = 1.0

    @staticmethod
    def wall_force(name):
        return np.zeros(3)

    @staticmethod
    def wall_position(name):
        return np.array([0.0, 0.0, 0.3])


def test_an_unloading_with_no_load_on_the_lid_reads_nothing_and_says_so():
    """Unloading from zero has no drop to read: before the guard the speed from a zero drop divided by zero and
    failed the whole battery (a DEM campaign with it)."""
    ctx = RunContext.from_spec(JobSpec(test="cct", fidelity="screening", seed=1))
    record = LidRecord()
    start, end = unload_slowly(ctx, _LidOff(), 2.0e5, 3.0e7, 0.3, record, 3, "cct: unload-reload at 30 kPa: unloading")
    assert (start, end) == (0, 1) and record.normal_stress_pa == [0.0]
    assert any("carries no load" in w for w in ctx.warnings)
    assert math.isnan(unload_reload_modulus(np.zeros(1), np.zeros(1)))  # and the reducer reports no value for it


def test_a_stress_the_packing_does_not_rest_at_ends_the_unload_reload_sequence(monkeypatch):
    """The servo holds 3 and 10 kPa, not 30: the 3 and 10 kPa unloadings are read, and none at 30 or 60 kPa, where
    the unloading would start from a moving packing and the next from one the servo stirred; a warning names them."""
    from engine.lab.procedures import cct

    held, unloaded = [], []
    monkeypatch.setattr(cct, "load_to", lambda *a, **k: None)
    monkeypatch.setattr(cct, "hold_stress", lambda ctx, sim, target, speed, phase: held.append(target) or target < 30e3)
    monkeypatch.setattr(cct, "unload_slowly", lambda *a: unloaded.append(a[-1]) or (len(unloaded), len(unloaded) + 1))

    class _Sim:
        @staticmethod
        def body_masses_kg():
            return np.ones(10)

    ctx = RunContext.from_spec(JobSpec(test="cct", fidelity="screening", seed=1))
    ranges = cct.unload_reload(ctx, _Sim(), 0.3, LidRecord(), 3, [3e3, 10e3, 30e3, 60e3], 3.0e7)
    assert held == [3e3, 10e3, 30e3] and len(unloaded) == len(ranges) == 2
    (warning,) = [w for w in ctx.warnings if "did not come to rest" in w]
    assert warning.endswith("no unload-reload modulus at 30, 60 kPa")
