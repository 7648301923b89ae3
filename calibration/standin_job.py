"""The closed-form stand-in battery (``calibration.standin``) as a lab job: the 'analytic' evaluator.

Why: the calibration loop (designs, fits, optimiser, campaigns, the diagnosis, the web pages)
must be testable in milliseconds and demonstrable on data with a hidden effect. The physics of
the stand-in, every candidate effect included, lives in calibration/standin.py; this module only
turns a JobSpec into a LabResult, as ``engine.lab.run_job`` does for the DEM lab: the spec's conditions
(DST loads, E' stresses, AoR, anchor), the seed's packing scatter, the test filter. It is declared
as a backend in ``calibration.evaluator_registry``, which is how workers and notebooks reach it.

``DEMCAL_ANALYTIC_DURATION_S`` (environment) makes a job take that long in wall time, reporting
progress and honouring cancellation, for queue fault tests.
"""
from __future__ import annotations

import os
import time

import engine
from calibration import standin
from engine.lab.resolution import label, setup_for
from engine.lab.result import BulkProperty, Cancelled, LabResult, Provenance
from engine.lab.spec import JobSpec


def dst_normal_stresses_pa(spec: JobSpec) -> list[float]:
    if spec.options.dst_normal_stresses_pa:
        return list(spec.options.dst_normal_stresses_pa)
    return list(setup_for(spec).dst_normal_stresses_pa)


def conditions(spec: JobSpec) -> standin.Conditions:
    preset = setup_for(spec)
    o = spec.options
    windows = getattr(o, "cct_window_stresses_pa", None) or ()
    return standin.Conditions(
        dst_normal_stresses_pa=tuple(dst_normal_stresses_pa(spec)),
        cct_window_stresses_pa=tuple(windows),
        cct_unload_reload_stresses_pa=tuple(getattr(o, "cct_unload_reload_stresses_pa", None) or ()),
        cct_max_stress_pa=float(o.cct_max_stress_pa or preset.cct_max_stress_pa),
        include_aor=bool(o.include_aor or spec.test == "aor"),
        include_anchor=bool(o.include_anchor or spec.test == "anchor"),
    )


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
    preset = setup_for(spec)  # the rig the job runs in: its container sets the bulk mass and height
    parameters = spec.parameters.model_dump()
    records = standin.battery(parameters, spec.seed, conditions(spec))
    density = next(r["value"] for r in records if r["quantity"] == "bulk_density_kg_m3")
    records += [
        {"test": "fill", "quantity": "packing_height_m", "value": preset.packing_height_m, "unit": "m",
         "condition": {}},
        {"test": "fill", "quantity": "bulk_mass_kg", "unit": "kg", "condition": {},
         "value": density * preset.container_area_m2 * preset.packing_height_m},
    ]
    modulus = next(r["value"] for r in records if r["quantity"] == "confined_modulus_pa" and not r["condition"])
    records.append({"test": "cct", "quantity": "bulk_stiffness_n_per_m", "unit": "N/m", "condition": {},
                    "value": preset.container_area_m2 / preset.packing_height_m * modulus})
    if spec.test != "battery":
        records = [r for r in records if r["test"] == spec.test]
    props = [BulkProperty(**r) for r in records]
    shear = [(r["condition"]["normal_stress_pa"], r["value"]) for r in records
             if r["quantity"] == "residual_shear_stress_pa"]
    curves = {}
    if shear:
        curves["mohr_coulomb"] = {"normal_stress_pa": [s for s, _ in shear],
                                  "residual_shear_stress_pa": [t for _, t in shear]}
    return LabResult(
        test=spec.test, properties=props, curves=curves,
        provenance=Provenance(
            parameters=spec.parameters.model_dump(), seed=spec.seed, fidelity=label(spec.resolution, spec.fidelity),
            rig=preset.rig_name, scale_factor=preset.scale_factor,
            engine_version=f"analytic-{engine.__version__}", wall_time_s=time.perf_counter() - started,
        ),
    )
