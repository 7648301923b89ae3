"""The one (test, quantity, condition) key and its one tolerance."""
from calibration.keys import ResponseKey, find, responses_of, select
from calibration.records import Measured


def test_a_converted_stress_matches_and_another_stress_does_not():
    measured = ResponseKey.of("dst", "residual_shear_stress_pa", {"normal_stress_pa": 24.0 * 1000.0000000000001})
    simulated = [ResponseKey.of("dst", "residual_shear_stress_pa", {"normal_stress_pa": s})
                 for s in (10500.0, 24000.0, 38300.0)]
    assert find(simulated, measured) == simulated[1]
    assert find(simulated, ResponseKey.of("dst", "residual_shear_stress_pa", {"normal_stress_pa": 24100.0})) is None
    assert find(simulated, ResponseKey.of("dst", "dilatancy_angle_deg", {"normal_stress_pa": 24000.0})) is None
    assert simulated[1].name == "dst__residual_shear_stress_pa__normal_stress_pa_24000"


def test_a_condition_must_have_the_same_names():
    a = ResponseKey.of("cct", "confined_modulus_pa", {})
    b = ResponseKey.of("cct", "confined_modulus_pa", {"normal_stress_pa": 30000.0})
    assert not a.matches(b) and not b.matches(a)


def test_responses_and_selection_use_the_key():
    result = {"properties": [{"test": "fill", "quantity": "bulk_density_kg_m3", "value": 1400.0, "unit": "kg/m3"}]}
    assert responses_of(result) == {"fill__bulk_density_kg_m3": {
        "test": "fill", "quantity": "bulk_density_kg_m3", "condition": {}, "unit": "kg/m3", "value": 1400.0}}
    records = [{"test": "fill", "quantity": "bulk_density_kg_m3", "condition": {}, "values": [1.0]},
               {"test": "dst", "quantity": "friction_angle_deg", "condition": {}, "values": [2.0]}]
    assert select(records, [{"test": "dst", "quantity": "friction_angle_deg"}]) == [records[1]]
    assert select(records, None) == records


def test_measured_noise_from_replicates_stated_or_assumed():
    key = ResponseKey.of("fill", "bulk_density_kg_m3")
    reps = Measured(key, (1390.0, 1400.0, 1410.0))
    v = reps.mean_variance(0.05)
    assert v.source == "replicates" and v.df == 2 and abs(v.variance - 100.0 / 3) < 1e-9   # s^2 = 100, n = 3
    assert Measured(key, (1400.0,), stated_uncertainty=7.0).mean_variance(0.05).variance == 49.0
    assumed = Measured(key, (1400.0,)).mean_variance(0.05)
    assert assumed.source == "assumed" and abs(assumed.variance - 70.0**2) < 1e-6


def test_the_battery_computes_the_measured_conditions_exactly():
    from calibration.conditions import battery_options

    keys = [ResponseKey.of("dst", "residual_shear_stress_pa", {"normal_stress_pa": s}) for s in (24e3, 10.5e3)]
    keys += [ResponseKey.of("cct", "confined_modulus_pa", {"normal_stress_pa": 15e3}),
             ResponseKey.of("anchor", "peak_pull_force_n", {"packing_height_m": 0.32})]
    options = battery_options(keys, {"speed_factor": 20.0})
    assert options == {"speed_factor": 20.0, "dst_normal_stresses_pa": [10.5e3, 24e3],
                       "cct_window_stresses_pa": [15e3]}
    # a user's explicit choice wins
    assert battery_options(keys, {"dst_normal_stresses_pa": [5e3, 9e3]})["dst_normal_stresses_pa"] == [5e3, 9e3]
    # each CCT quantity's stresses go to its own option: E_ur at 3 kPa is no E' window
    unload_reload = [ResponseKey.of("cct", "unload_reload_modulus_pa", {"normal_stress_pa": s}) for s in (60e3, 3e3)]
    options = battery_options(keys + unload_reload)
    assert options["cct_window_stresses_pa"] == [15e3]
    assert options["cct_unload_reload_stresses_pa"] == [3e3, 60e3]
