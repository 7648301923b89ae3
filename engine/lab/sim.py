"""Thin adapter between the lab's plain-data inputs and the engine's ``Simulation``.

It maps ``MicroParameters`` to the engine's material/effect config, adds particles from a
``Packing``, and runs the simulation in short chunks so procedures can watch wall forces, stop
on a condition, count particle-steps and honour cancellation between chunks.
"""
from __future__ import annotations

import numpy as np

from engine.config import EffectSpec, MaterialSpec, SimulationConfig, WallSpec
from engine.lab.context import RunContext
from engine.lab.spec import MicroParameters
from engine.simulation import Simulation

GRAVITY_M_S2 = 9.81


def simulation_config(params: MicroParameters) -> SimulationConfig:
    material = MaterialSpec(
        name="particles",
        density_kg_m3=params.particle_density_kg_m3,
        normal_stiffness_n_per_m=params.particle_stiffness_n_per_m,
        shear_to_normal_stiffness_ratio=params.shear_to_normal_stiffness_ratio,
        friction=params.friction_pp,
        damping_ratio_normal=params.damping_ratio,
        damping_ratio_shear=params.damping_ratio,
        local_damping=params.local_damping,
    )
    effects = [EffectSpec(name=name, params=dict(values)) for name, values in params.effects.items()]
    return SimulationConfig(materials=[material], effects=effects, gravity_m_s2=(0.0, 0.0, -GRAVITY_M_S2))


def new_simulation(params: MicroParameters, walls: list[WallSpec], packing=None, velocities_m_s=None) -> Simulation:
    sim = Simulation(simulation_config(params))
    if packing is not None:
        sim.add_packing(packing, velocities_m_s=velocities_m_s)
    for spec in walls:
        sim.add_wall(spec)
    return sim


def restore(state: dict) -> Simulation:
    return Simulation.from_checkpoint(state)


def advance(ctx: RunContext, sim: Simulation, steps: int) -> None:
    steps = max(int(steps), 1)
    sim.run(steps=steps)
    ctx.count(steps, sim.n_bodies, sim.timestep_s, sim.n_spheres)


def steps_for(sim: Simulation, duration_s: float) -> int:
    return max(1, int(round(duration_s / sim.timestep_s)))


def mean_diameter_m(sim: Simulation) -> float:
    """Mean body size: twice the mean volume-equivalent radius."""
    volume = sim.body_masses_kg() / sim.config.materials[0].density_kg_m3
    return float(2.0 * np.mean((3.0 * volume / (4.0 * np.pi)) ** (1.0 / 3.0)))


def kinetic_energy_ratio(sim: Simulation, diameter_m: float) -> float:
    """KE / (M g d): the kinetic energy against that of lifting the whole mass one grain size.

    1e-5 means the mean speed is sqrt(2e-5 g d), ~3 mm/s for 40 mm grains: a packing at rest.
    """
    mass = float(np.sum(sim.body_masses_kg()))
    return sim.kinetic_energy() / (mass * GRAVITY_M_S2 * diameter_m) if mass > 0 else 0.0


def settle(ctx: RunContext, sim: Simulation, phase: str, threshold: float = 1e-5, min_time_s: float = 0.05,
           max_time_s: float = 5.0, check_every_s: float = 0.02, record: list | None = None) -> bool:
    """Run until the kinetic energy ratio is below ``threshold`` (after ``min_time_s``).

    Returns False (and records a warning) when ``max_time_s`` passes first.
    """
    d = mean_diameter_m(sim)
    chunk = steps_for(sim, check_every_s)
    t0 = sim.time_s
    while True:
        advance(ctx, sim, chunk)
        ratio = kinetic_energy_ratio(sim, d)
        elapsed = sim.time_s - t0
        if record is not None:
            record.append((sim.time_s, ratio))
        ctx.report(min(elapsed / max_time_s, 1.0), phase)
        if elapsed >= min_time_s and ratio < threshold:
            return True
        if elapsed >= max_time_s:
            ctx.warn(f"{phase}: kinetic energy ratio {ratio:.1e} still above {threshold:.0e} after {max_time_s} s")
            return False


def sphere_tops_m(sim: Simulation) -> np.ndarray:
    return sim.sphere_positions_m()[:, 2] + sim.sphere_radii_m()
