"""Closed-form stand-in for a DEM test battery.

Why: the calibration loop (designs, fits, optimiser, campaigns, the web pages)
must be testable in milliseconds, and demonstrable on data with a *hidden
effect*. The relations below are smooth, monotone caricatures of the trends the
thesis measured (Tables 4.6-4.8, 5.3, A.9), not a substitute for the engine:

* solid fraction falls with inter-particle and wall friction (Table 4.8:
  frictionless packing is denser);
* bulk density = particle density x solid fraction (Table 4.6, slope ~0.56);
* confined modulus grows with particle stiffness over particle size (Table 4.7);
* friction angle grows with inter-particle friction but saturates near 42 deg
  for round particles; only rolling resistance (the ``rolling_epsd2`` effect,
  standing in for particle shape) lifts it to the 60 deg a crushed aggregate
  shows. A material measured with angular particles therefore cannot be
  reached by a model without that effect: the hidden effect the
  model-vs-measurement loop must discover.

Responses carry seeded Gaussian scatter so centre replicates give pure error.
``DEMCAL_ANALYTIC_DURATION_S`` (environment) makes a job take that long in
wall time, reporting progress and honouring cancellation, for queue fault tests.
"""
from __future__ import annotations

import math
import os
import time

import numpy as np

import engine
from engine.lab import presets
from engine.lab.result import BulkProperty, Cancelled, LabResult, Provenance, QUANTITIES
from engine.lab.spec import JobSpec

# Relative (or absolute, for angles) scatter of one realisation.
_REL_SD_DENSITY = 0.003
_REL_SD_MODULUS = 0.03
_SD_SHEAR_REL = 0.02
_SD_AOR_DEG = 1.0


def _rolling_friction(spec: JobSpec) -> float:
    effect = spec.parameters.effects.get("rolling_epsd2") or spec.parameters.effects.get("rolling_cdt")
    return float(effect.get("rolling_friction", 0.0)) if effect else 0.0


def dst_normal_stresses_pa(spec: JobSpec) -> list[float]:
    if spec.options.dst_normal_stresses_pa:
        return list(spec.options.dst_normal_stresses_pa)
    return list(presets.fidelity(spec.fidelity).dst_normal_stresses_pa)


def _mean_particle_diameter_m(preset: presets.Fidelity) -> float:
    """Solid-volume-weighted mean sphere diameter of the preset's shape mix."""
    return sum(s.volume_fraction * (s.radius_min_m + s.radius_max_m) for s in preset.shapes)


def _prop(test: str, quantity: str, value: float, **condition: float) -> BulkProperty:
    return BulkProperty(test=test, quantity=quantity, value=float(value),
                        unit=QUANTITIES[test][quantity], condition=condition)


def _wait(duration_s: float, progress, should_cancel) -> None:
    start = time.monotonic()
    while True:
        if should_cancel is not None and should_cancel():
            raise Cancelled("cancelled")
        elapsed = time.monotonic() - start
        if progress is not None:
            progress(min(1.0, elapsed / duration_s) if duration_s > 0 else 1.0, "analytic")
        if elapsed >= duration_s:
            return
        time.sleep(min(0.1, duration_s - elapsed))


def run_analytic(spec: JobSpec, progress=None, should_cancel=None) -> LabResult:
    started = time.perf_counter()
    _wait(float(os.environ.get("DEMCAL_ANALYTIC_DURATION_S", "0") or 0.0), progress, should_cancel)
    p = spec.parameters
    rng = np.random.default_rng(spec.seed)
    preset = presets.fidelity(spec.fidelity, p.particle_radius_m)
    diameter_m = _mean_particle_diameter_m(preset)
    height_m = preset.packing_height_m
    area_m2 = preset.container_area_m2
    mu_r = _rolling_friction(spec)

    solid_fraction = (
        0.584
        - 0.025 * (1.0 - math.exp(-p.friction_pp / 0.08))
        - 0.004 * (1.0 - math.exp(-p.friction_pw / 0.1))
        - 0.030 * mu_r / (mu_r + 0.1)
    ) * (1.0 + _REL_SD_DENSITY * rng.standard_normal())
    porosity = 1.0 - solid_fraction
    bulk_density = p.particle_density_kg_m3 * solid_fraction
    modulus_pa = (
        0.125 * p.particle_stiffness_n_per_m / diameter_m
        * (solid_fraction / 0.56) ** 3
        * (1.0 + 0.25 * p.friction_pp / (p.friction_pp + 0.2))
    ) * (1.0 + _REL_SD_MODULUS * rng.standard_normal())
    phi_true_deg = 12.0 + 30.0 * (1.0 - math.exp(-p.friction_pp / 0.35)) + 25.0 * mu_r / (mu_r + 0.08)
    phi_true_deg = min(phi_true_deg, 80.0)

    stresses = dst_normal_stresses_pa(spec)
    shear = [s * math.tan(math.radians(phi_true_deg)) * (1.0 + _SD_SHEAR_REL * rng.standard_normal())
             for s in stresses]
    slope, intercept = np.polyfit(stresses, shear, 1)
    predicted = slope * np.asarray(stresses) + intercept
    ss_res = float(np.sum((np.asarray(shear) - predicted) ** 2))
    ss_tot = float(np.sum((np.asarray(shear) - np.mean(shear)) ** 2))
    dilatancy_deg = max(0.0, 0.35 * (phi_true_deg - 12.0)) + 0.5 * rng.standard_normal()

    props = [
        _prop("fill", "bulk_density_kg_m3", bulk_density),
        _prop("fill", "porosity", porosity),
        _prop("fill", "voids_ratio", porosity / solid_fraction),
        _prop("fill", "packing_height_m", height_m),
        _prop("fill", "bulk_mass_kg", bulk_density * area_m2 * height_m),
        _prop("cct", "confined_modulus_pa", modulus_pa),
        _prop("cct", "bulk_stiffness_n_per_m", area_m2 / height_m * modulus_pa),
        _prop("dst", "friction_angle_deg", math.degrees(math.atan(slope))),
        _prop("dst", "cohesion_pa", intercept),
        _prop("dst", "mohr_coulomb_r2", 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0),
        # the thesis's measured dilatancy (13.2 deg) is a mean over loads: no condition
        _prop("dst", "dilatancy_angle_deg", dilatancy_deg),
    ]
    for stress, tau in zip(stresses, shear):
        props.append(_prop("dst", "residual_shear_stress_pa", tau, normal_stress_pa=stress))
        props.append(_prop("dst", "dilatancy_angle_deg", dilatancy_deg, normal_stress_pa=stress))
    if spec.options.include_aor or spec.test == "aor":
        aor = 12.0 + 28.0 * (1.0 - math.exp(-p.friction_pp / 0.3)) + 15.0 * mu_r / (mu_r + 0.05)
        props.append(_prop("aor", "angle_of_repose_deg", aor + _SD_AOR_DEG * rng.standard_normal()))

    if spec.test != "battery":
        props = [prop for prop in props if prop.test == spec.test]
    return LabResult(
        test=spec.test,
        properties=props,
        curves={"mohr_coulomb": {"normal_stress_pa": list(stresses), "residual_shear_stress_pa": shear}},
        provenance=Provenance(
            parameters=p.model_dump(), seed=spec.seed, fidelity=spec.fidelity,
            engine_version=f"analytic-{engine.__version__}", wall_time_s=time.perf_counter() - started,
        ),
    )
