"""The slow lab tests' DEM runs, by name (tests/lab/conftest.py runs them in a pool and turns each into a
fixture; GROUPS name lists of runs one fixture returns together).

A module of its own, not the conftest, so that a spawned pool process can import `call` by a unique name.
"""
from __future__ import annotations

import io
import json
from contextlib import redirect_stdout
from pathlib import Path

from engine.lab import run_job
from engine.lab.context import RunContext
from engine.lab.procedures.cct import run_cct
from engine.lab.procedures.fill import run_fill
from engine.lab.result import LabResult
from engine.lab.spec import JobSpec

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "screening-battery.json"

# Tables 4.6 / 4.7 held mu_pp = 0.1, mu_pw = 0.62 fixed while varying rho_p and k_p
TABLE_46_47 = {"friction_pp": 0.1, "friction_pw": 0.62}


def _fill_and_cct(**parameters):
    ctx = RunContext.from_spec(JobSpec(test="cct", seed=3, parameters=parameters, options={"cct_cycles": 4}))
    fill = run_fill(ctx)
    cct = run_cct(ctx, fill)
    return fill.properties, cct.reduction


def _example_battery() -> LabResult:
    """docs/examples/screening-battery.json through the CLI, as a user would run it."""
    from engine.lab.cli import main

    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["run", str(EXAMPLE)]) == 0
    return LabResult.model_validate(json.loads(out.getvalue()))


def _fill_rained_frictionless_tested_at_086():
    """A packing rained at mu_pp = 0 (fill_friction_pp) for tests at mu_pp = 0.86: (fill properties, the
    friction its checkpoint carries on)."""
    from engine.simulation import Simulation

    ctx = RunContext.from_spec(JobSpec(test="fill", seed=3, parameters={"friction_pp": 0.86},
                                       options={"fill_friction_pp": 0.0}))
    fill = run_fill(ctx)
    return fill.properties, Simulation.from_checkpoint(fill.checkpoint).config.materials[0].friction


def _run(spec: dict) -> LabResult:
    return run_job(JobSpec(**spec))


# fixture name -> (function, keyword arguments), longest first (the pool starts them in this order, so the last
# to start is short): one registry, read by the pool and by the fixtures
RUNS = {
    # mu_pp = 0 (Table 4.8's first column): fill, short CCT and a two-load DST
    "frictionless_battery": (_run, dict(spec=dict(test="battery", seed=3, parameters={"friction_pp": 0.0},
                                                  options={"cct_cycles": 2,
                                                           "dst_normal_stresses_pa": [15.0e3, 53.8e3]}))),
    "example_battery": (_example_battery, {}),
    # rho_p 2,500, k_p 1.0 MN/m (Table 4.6/4.7 fixed set)
    "soft_light": (_fill_and_cct, dict(particle_density_kg_m3=2500.0, particle_stiffness_n_per_m=1.0e6,
                                       **TABLE_46_47)),
    "soft_heavy": (_fill_and_cct, dict(particle_density_kg_m3=10000.0, particle_stiffness_n_per_m=1.0e6,
                                       **TABLE_46_47)),
    "stiff_light": (_fill_and_cct, dict(particle_density_kg_m3=2500.0, particle_stiffness_n_per_m=2.3e6,
                                        **TABLE_46_47)),
    "rained_frictionless_fill": (_fill_rained_frictionless_tested_at_086, {}),
    # mu_pp = 0.1 (Table 4.8's second column), four loads: little dilation and stick-slip, so the residual
    # stresses of a ~10-grain-wide screening box settle; at mu_pp 0.3 the shear stress still climbs and
    # slips by +-15 % inside the 8-10 % window, scattering R^2 between 0.86 and 0.97 with the seed.
    "low_friction_dst": (_run, dict(spec=dict(test="dst", seed=3, parameters={"friction_pp": 0.1}))),
    # mu_pp = 0.3, four loads: the middle point of the phi(mu_pp) trend
    "mid_friction_dst": (_run, dict(spec=dict(test="dst", seed=3, parameters={"friction_pp": 0.3}))),
}


# Seeds of the angle-of-repose trend, in two stages (test_trends.test_angle_of_repose_rises_with_friction says
# why): the first stage's piles start with the session, the second's only when the first is inconclusive.
AOR_STAGES = ((3, 4, 5), (6, 7, 8))
AOR_FRICTIONS = (0.1, 0.86)


def aor_pile(mu: float, seed: int) -> str:
    return f"aor_pile_mu{mu}_seed{seed}"


for _stage in AOR_STAGES:
    for _mu in AOR_FRICTIONS:
        for _seed in _stage:
            RUNS[aor_pile(_mu, _seed)] = (_run, dict(spec=dict(test="aor", seed=_seed, parameters={"friction_pp": _mu})))
RUNS["anchor_pull"] = (_run, dict(spec=dict(test="anchor", seed=3, options={"anchor_packing_height_m": 0.17,
                                                                            "anchor_pull_distance_m": 0.03})))
# a real screening CCT, 2 cycles, E' asked at three stresses
CCT_WINDOW_STRESSES_PA = (7.5e3, 21.3e3, 44.4e3)
RUNS["cct_at_three_stresses"] = (_run, dict(spec=dict(test="cct", seed=3, options={
    "cct_cycles": 2, "cct_window_stresses_pa": list(CCT_WINDOW_STRESSES_PA)})))

# fixture name -> the runs it returns as a list, in this order; a run in no group and no fixture a test
# names up front (the second stage's piles) starts only when a test asks the `lab_run` fixture for it
GROUPS = {"aor_piles": [aor_pile(mu, seed) for mu in AOR_FRICTIONS for seed in AOR_STAGES[0]]}


def call(name: str):
    function, keywords = RUNS[name]
    return function(**keywords)
