"""E' at the user's stresses (options.cct_window_stresses_pa) and DST loads keyed by the user's floats.

The synthetic record is a Hertz-like packing: on every loading branch sigma = A (eps - eps0)^(3/2), so
the tangent modulus is E'(sigma) = d sigma / d eps = 1.5 A^(2/3) sigma^(1/3) whatever the branch's
plastic offset eps0; the unloading branches are stiffer lines (elastic rebound), as split_cycles expects.
"""
import math

import numpy as np
import pytest

from engine.lab import battery
from engine.lab.context import RunContext
from engine.lab.presets import SCREENING
from engine.lab.procedures import cct as cct_procedure
from engine.lab.procedures import dst as dst_procedure
from engine.lab.procedures import fill as fill_procedure
from engine.lab.reducers import reduce_cct, reduce_dst
from engine.lab.reducers.cct import tangent_modulus_at
from engine.lab.spec import JobSpec

A_PA = 2.0e9  # sigma = A eps^1.5: 65.6 kPa at eps ~ 0.1 %
PEAK_PA = 65.6e3


def hertz_modulus_pa(sigma_pa: float) -> float:
    return 1.5 * A_PA ** (2.0 / 3.0) * sigma_pa ** (1.0 / 3.0)


def hertz_cycles(cycles: int = 4, n: int = 400, peak_pa: float = PEAK_PA):
    """Loading sigma = A (eps - eps0)^1.5 to the peak, unloading linear at 3 x the peak's tangent modulus
    down to zero stress; the next cycle's offset eps0 is where the unloading ended (a permanent strain)."""
    strain, stress = [], []
    eps0 = 0.0
    eps_peak_rel = (peak_pa / A_PA) ** (2.0 / 3.0)
    e_unload = 3.0 * hertz_modulus_pa(peak_pa)
    for _ in range(cycles):
        e = eps0 + np.linspace(0.0, eps_peak_rel, n)  # even in strain: a constant lid speed
        strain.extend(e)
        stress.extend(A_PA * (e - eps0) ** 1.5)
        s_un = np.linspace(peak_pa, 0.0, n // 4)[1:]
        top = eps0 + eps_peak_rel
        strain.extend(top - (peak_pa - s_un) / e_unload)
        stress.extend(s_un)
        eps0 = top - peak_pa / e_unload
    return np.array(strain), np.array(stress)


def test_tangent_modulus_at_requested_stresses_matches_hertz():
    strain, stress = hertz_cycles()
    requested = [2.5e3, 10.0e3, 24.0e3, 38.3e3, 52.4e3, 60.0e3]
    red = reduce_cct(strain, stress, 1.0, 1.0, window_stresses_pa=requested)
    assert red.window_stress_mid_pa == requested
    assert all(a is b or a == b for a, b in zip(red.window_stress_mid_pa, requested))
    for s, e in zip(red.window_stress_mid_pa, red.window_modulus_pa):
        assert e == pytest.approx(hertz_modulus_pa(s), rel=0.02), s
    # the tangent rises as sigma^(1/3): a factor 24 in stress is a factor 24^(1/3) = 2.88 in E'
    assert red.window_modulus_pa[-1] / red.window_modulus_pa[0] == pytest.approx(24 ** (1 / 3), rel=0.03)
    # the mean E' over the central band is unchanged by the option
    assert red.confined_modulus_pa == reduce_cct(strain, stress, 1.0, 1.0).confined_modulus_pa


def test_first_cycle_is_left_out_of_the_tangent():
    # a soft first (compaction) cycle, A / 4: were it used, E' would be ~20 % low at every stress
    strain, stress = hertz_cycles(cycles=3)
    first_end = int(np.argmax(stress))
    soft = strain.copy()
    soft[: first_end + 1] = strain[0] + (strain[: first_end + 1] - strain[0]) * 4 ** (2 / 3)
    shift = soft[first_end] - strain[first_end]
    soft[first_end + 1:] += shift
    red = reduce_cct(soft, stress, 1.0, 1.0, window_stresses_pa=[20e3])
    assert red.window_modulus_pa[0] == pytest.approx(hertz_modulus_pa(20e3), rel=0.02)


def test_window_with_too_few_points_gives_no_value():
    # 40 points per loading branch, sampled evenly in strain: near zero stress the window
    # 1 kPa (1 -+ 25 %) holds fewer than 3 of them
    strain, stress = hertz_cycles(n=40)
    branches_stress = [1.0e3, 30.0e3]
    red = reduce_cct(strain, stress, 1.0, 1.0, window_stresses_pa=branches_stress)
    assert red.window_stress_mid_pa == [30.0e3]
    assert red.window_modulus_pa[0] == pytest.approx(hertz_modulus_pa(30.0e3), rel=0.03)
    assert math.isnan(tangent_modulus_at(strain, stress, [(0, 39)], 1.0e3))
    # at or above the branch peak there is no centred window at all
    assert math.isnan(tangent_modulus_at(strain, stress, [(0, 39)], PEAK_PA))


def test_window_near_the_peak_stays_centred():
    # 0.95 of the peak: +-25 % would reach 1.19 x the peak; the window narrows to +-5 % instead of
    # being clipped on one side (which would read the slope at ~0.88 of the peak, 2.6 % low)
    strain, stress = hertz_cycles(n=2000)
    s = 0.95 * PEAK_PA
    red = reduce_cct(strain, stress, 1.0, 1.0, window_stresses_pa=[s])
    assert red.window_modulus_pa[0] == pytest.approx(hertz_modulus_pa(s), rel=0.005)


@pytest.mark.parametrize("value, message", [
    ([], "at least one"),
    ([-1.0], "> 0"),
    ([0.0], "> 0"),
    ([float("nan")], "finite"),
    ([float("inf")], "finite"),
    ([20e3, 10e3], "strictly increasing"),
    ([10e3, 10e3], "strictly increasing"),
])
def test_window_stresses_option_is_validated(value, message):
    with pytest.raises(ValueError, match=message):
        JobSpec(options={"cct_window_stresses_pa": value})


def test_window_stresses_must_be_below_the_cct_maximum():
    with pytest.raises(ValueError, match="cct_window_stresses_pa"):
        RunContext.from_spec(JobSpec(test="cct", options={"cct_window_stresses_pa": [SCREENING.cct_max_stress_pa]})
                             ).validate()
    with pytest.raises(ValueError, match="cct_window_stresses_pa"):
        RunContext.from_spec(JobSpec(test="cct", options={"cct_window_stresses_pa": [30e3],
                                                          "cct_max_stress_pa": 30e3})).validate()
    RunContext.from_spec(JobSpec(test="cct", options={"cct_window_stresses_pa": [30e3]})).validate()


@pytest.mark.parametrize("stresses", [[15e3, float("nan")], [15e3, 15e3]])
def test_dst_stresses_must_be_finite_and_distinct(stresses):
    with pytest.raises(ValueError, match="dst_normal_stresses_pa"):
        RunContext.from_spec(JobSpec(test="dst", options={"dst_normal_stresses_pa": stresses})).validate()


def _synthetic_procedures(monkeypatch):
    """The battery with its DEM procedures replaced by synthetic records run through the real reducers,
    so that what is checked is the keying from options to properties."""
    area, diameter, height = SCREENING.container_area_m2, SCREENING.container_diameter_m, 0.37

    def fake_fill(ctx):
        props = {"bulk_density_kg_m3": 1500.0, "porosity": 0.4, "voids_ratio": 2 / 3, "packing_height_m": height,
                 "bulk_mass_kg": 70.0, "particle_count": 800.0}
        return fill_procedure.FillOutcome({}, props, height)

    def fake_cct(ctx, fill):
        strain, stress = hertz_cycles(peak_pa=ctx.cct_max_stress_pa)
        red = reduce_cct(strain, stress, area, height, window_stresses_pa=ctx.spec.options.cct_window_stresses_pa)
        record = cct_procedure.LidRecord(time_s=[0.0], lid_z_m=[0.0], normal_stress_pa=[0.0], cycle=[1.0])
        return cct_procedure.CctOutcome(red, record, strain, {})

    def fake_run_one(ctx, precompressed, packing_height_m, target_pa):
        ds = np.linspace(0.0, ctx.shear_distance_m, 421)
        tau = 0.7 * target_pa * np.minimum(1.0, ds / diameter / 0.05)
        red = reduce_dst(ds, tau * area, np.full_like(ds, target_pa * area), 0.1 * ds, area, diameter)
        return dst_procedure.DstRun(target_pa, red, {})

    monkeypatch.setattr(fill_procedure, "run_fill", fake_fill)
    monkeypatch.setattr(cct_procedure, "run_cct", fake_cct)
    monkeypatch.setattr(dst_procedure, "run_one", fake_run_one)


def test_battery_keys_cct_and_dst_values_at_the_requested_floats(monkeypatch):
    _synthetic_procedures(monkeypatch)
    # floats that no arithmetic on round numbers reproduces, e.g. a stress read off a lab sheet
    cct_stresses = [3141.592653589793, 12345.678901234567, 41000.000000000004]
    dst_stresses = [15006.09, 27811.502, 0.1 + 40624.2]
    result = battery.run_job(JobSpec(test="battery", options={"cct_window_stresses_pa": cct_stresses,
                                                              "dst_normal_stresses_pa": dst_stresses}))
    windows = [p for p in result.properties if p.test == "cct" and p.condition]
    assert [p.condition for p in windows] == [{"normal_stress_pa": s} for s in cct_stresses]
    for p, s in zip(windows, cct_stresses):
        assert p.condition["normal_stress_pa"] == s  # exact, not approx
        assert p.value == pytest.approx(hertz_modulus_pa(s), rel=0.02)
        assert result.value("cct", "confined_modulus_pa", normal_stress_pa=s) == p.value
    assert result.curves["cct_modulus_vs_stress"]["normal_stress_pa"] == cct_stresses
    for quantity in ("residual_shear_stress_pa", "dilatancy_angle_deg"):
        conditions = [p.condition for p in result.properties if p.test == "dst" and p.quantity == quantity
                      and p.condition]
        assert conditions == [{"normal_stress_pa": s} for s in dst_stresses]
    for s in dst_stresses:
        assert result.value("dst", "residual_shear_stress_pa", normal_stress_pa=s) == pytest.approx(0.7 * s)


def test_battery_without_the_option_keeps_five_equal_windows(monkeypatch):
    _synthetic_procedures(monkeypatch)
    result = battery.run_job(JobSpec(test="cct"))
    mids = [p.condition["normal_stress_pa"] for p in result.properties if p.test == "cct" and p.condition]
    peak = SCREENING.cct_max_stress_pa
    assert mids == pytest.approx([peak * (k + 0.5) / 5 for k in range(5)], rel=1e-3)


@pytest.mark.slow
def test_screening_cct_reports_modulus_at_the_requested_stresses(cct_at_three_stresses):
    # a real DEM CCT (screening, 2 cycles): every requested stress is a key, with a positive modulus
    from lab_runs import CCT_WINDOW_STRESSES_PA

    requested = list(CCT_WINDOW_STRESSES_PA)
    result = cct_at_three_stresses
    got = [p for p in result.properties if p.test == "cct" and p.quantity == "confined_modulus_pa" and p.condition]
    assert [p.condition for p in got] == [{"normal_stress_pa": s} for s in requested]
    # the tangent at each stress is the same stiffness as the central-band E' within what a packing's
    # stress dependence allows: E' ~ sigma^m with m <= 1/2 (Hertzian 1/3, jammed harmonic packings up to
    # 1/2) moves E' by at most (33.5 / 7.5)^(1/2) = 2.1 between 7.5 kPa and the band's centre
    mean_modulus = result.value("cct", "confined_modulus_pa")
    for p in got:
        assert mean_modulus / 3 < p.value < 3 * mean_modulus, p
