"""The battery's shorter stages (issue 34, docs/lab.md "Fewer steps per battery"): a record stopped where
``options.stop_after_reduced`` stops it reduces to the same values, to the bit, as the whole record; and
the DST's speed by stress holds the shear's inertial number at the lowest load's."""
import math

import numpy as np
import pytest

from engine.lab.context import RunContext
from engine.lab.reducers import reduce_cct, reduce_dst
from engine.lab.reducers.dst import samples_needed_past_window
from engine.lab.spec import JobSpec

DIAMETER_M = 0.40
AREA_M2 = math.pi * 0.20**2


def _noisy_shear_record(n=800, distance_m=0.042, seed=3):
    """A shear record with force chatter (so the smoothing matters) and a dilating lid."""
    rng = np.random.default_rng(seed)
    ds = np.linspace(distance_m / n, distance_m, n)
    strain = ds / DIAMETER_M
    shear = AREA_M2 * 20e3 * np.minimum(1.0, strain / 0.05) * (1 + 0.05 * rng.standard_normal(n))
    normal = AREA_M2 * 24e3 * (1 + 0.03 * rng.standard_normal(n))
    lid = 0.1 * ds + 1e-5 * rng.standard_normal(n)
    return ds, shear, normal, lid


def _stop_index(ds, window_end_strain, span):
    """Samples kept by the DST's stop rule: up to the one that makes ``samples_needed_past_window``."""
    past = 0
    for i, d in enumerate(ds):
        if d / DIAMETER_M > window_end_strain:
            past += 1
            if past >= samples_needed_past_window(span):
                return i + 1
    raise AssertionError("the record never passes the window")


@pytest.mark.parametrize("span", [21, 5, 1])
def test_a_shear_record_stopped_after_the_window_reduces_to_the_same_values(span):
    ds, shear, normal, lid = _noisy_shear_record()
    window = (0.08, 0.10)
    full = reduce_dst(ds, shear, normal, lid, AREA_M2, DIAMETER_M, window=window, span=span)
    k = _stop_index(ds, window[1], span)
    assert k < ds.size  # the rule does stop before the shear distance
    cut = reduce_dst(ds[:k], shear[:k], normal[:k], lid[:k], AREA_M2, DIAMETER_M, window=window, span=span)
    assert cut.residual_shear_stress_pa == full.residual_shear_stress_pa
    assert cut.residual_normal_stress_pa == full.residual_normal_stress_pa
    assert cut.dilatancy_angle_deg == full.dilatancy_angle_deg
    if span > 1:  # one sample fewer and the smoothing of the window's last point loses a neighbour
        short = reduce_dst(ds[:k - 1], shear[:k - 1], normal[:k - 1], lid[:k - 1], AREA_M2, DIAMETER_M,
                           window=window, span=span)
        assert short.residual_shear_stress_pa != full.residual_shear_stress_pa


def _noisy_cyclic_record(cycles=4, n=300, seed=5):
    """Loading branches (softer first, compaction), unloading stiffer, chatter on the stress."""
    rng = np.random.default_rng(seed)
    strain, stress = [], []
    eps0, peak, modulus = 0.0, 67e3, 12e6
    for c in range(cycles):
        e_load = modulus / 3 if c == 0 else modulus
        s = np.linspace(0, peak, n) * (1 + 0.02 * rng.standard_normal(n))
        s[-1] = peak
        strain.extend(eps0 + np.linspace(0, peak, n) / e_load)
        stress.extend(s)
        top = eps0 + peak / e_load
        s_un = np.linspace(peak, 0, n)[1:]
        strain.extend(top - (peak - s_un) / (2 * modulus))
        stress.extend(s_un)
        eps0 = top - peak / (2 * modulus)
    return np.array(strain), np.array(stress), n


@pytest.mark.parametrize("windows", [None, [10e3, 30e3, 60e3]])
def test_a_cct_record_without_its_last_unloading_reduces_to_the_same_values(windows):
    strain, stress, n = _noisy_cyclic_record()
    last_peak = strain.size - (n - 1)  # the last loading branch ends where its unloading starts
    full = reduce_cct(strain, stress, AREA_M2, 0.37, window_stresses_pa=windows)
    cut = reduce_cct(strain[:last_peak], stress[:last_peak], AREA_M2, 0.37, window_stresses_pa=windows)
    assert cut.modulus_per_cycle_pa == full.modulus_per_cycle_pa
    assert cut.confined_modulus_pa == full.confined_modulus_pa
    assert cut.window_stress_mid_pa == full.window_stress_mid_pa
    assert cut.window_modulus_pa == full.window_modulus_pa


def _inertial_number(speed_m_s, stress_pa, band_m=0.37, d_m=0.04, rho=2500.0):
    """docs/lab.md: I = (v / h_band) d / sqrt(P / rho_p)."""
    return speed_m_s / band_m * d_m / math.sqrt(stress_pa / rho)


def test_dst_speed_by_stress_holds_the_lowest_loads_inertial_number():
    ctx = RunContext.from_spec(JobSpec(test="battery", fidelity="screening", options={"dst_speed_by_stress": True}))
    loads = ctx.dst_normal_stresses_pa
    lowest = min(loads)
    v = ctx.shear_speed_m_s
    for s in loads:
        assert _inertial_number(v * ctx.dst_speed_scale(s), s) == pytest.approx(_inertial_number(v, lowest))
    assert ctx.dst_speed_scale(0.5 * lowest) == 1.0  # never slower than the speed factor's speed
    # Table A.7's heaviest load, 6,760 N, against its lightest, 1,885 N: sqrt(6760 / 1885) = 1.894
    assert ctx.dst_speed_scale(max(loads)) == pytest.approx(math.sqrt(6760 / 1885))


# off unless asked for: at 35 mm it changed what the loop concluded (docs/lab.md, "Fewer steps per battery")
@pytest.mark.parametrize("fidelity, options", [("screening", {}), ("screening", {"dst_speed_by_stress": False}),
                                               ("thesis", {})])
def test_dst_speed_by_stress_off_is_one_speed(fidelity, options):
    ctx = RunContext.from_spec(JobSpec(test="battery", fidelity=fidelity, options=options))
    assert all(ctx.dst_speed_scale(s) == 1.0 for s in ctx.dst_normal_stresses_pa)


def test_stop_after_reduced_defaults_by_fidelity():
    assert RunContext.from_spec(JobSpec(fidelity="screening")).stop_after_reduced is True
    assert RunContext.from_spec(JobSpec(fidelity="thesis")).stop_after_reduced is False
    assert RunContext.from_spec(JobSpec(options={"stop_after_reduced": False})).stop_after_reduced is False
