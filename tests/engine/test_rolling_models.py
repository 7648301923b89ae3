"""Each rolling-resistance model against the published model it is named after.

A sphere seated on a floor and set rocking with a small rolling velocity stays below the rolling
cap, so sphere and contact form a linear two-degree-of-freedom system: the centre's displacement x
and the rotation theta, coupled by the tangential spring k_t on the slip u = x - a theta and held
by the rolling spring k_r (and, for EPSD, the rolling dashpot C_r):

    m x'' = -k_t (x - a theta)
    I theta'' = a k_t (x - a theta) - k_r theta - C_r theta'

Its exact solution (a matrix exponential) fixes the whole trajectory, so the test checks the rolling
stiffness of each model (EPSD2: k_t R*^2, Iwashita & Oda 1998 / LIGGGHTS `epsd2`; EPSD:
2.25 k_n mu_r^2 R*^2, Ai et al. 2011 / LIGGGHTS `epsd`) and EPSD's dashpot
C_r = eta_r 2 sqrt(I_r k_r) with I_r = 7/5 m R^2 for a sphere on a wall. The full-mobilisation
limit mu_r R* fn is checked by the stopping distance in test_effects.py.
"""
import math

import numpy as np
from scipy.linalg import expm

from engine.config import EffectSpec, MaterialSpec, PlaneGeom, SimulationConfig, WallSpec
from engine.simulation import Simulation

from engine_helpers import G, sphere_mass

R = 0.01
RHO = 2500.0
KP = 1.0e6
KW = 1.0e7
KN = KP * KW / (KP + KW)  # particle-wall contact: springs in series
MU_R = 0.5
ETA_R = 0.3


def _seated(effect: EffectSpec, safety_factor: float) -> Simulation:
    cfg = SimulationConfig(
        materials=[MaterialSpec(normal_stiffness_n_per_m=KP, density_kg_m3=RHO, friction=0.5,
                                damping_ratio_normal=0.5, damping_ratio_shear=0.0)],
        effects=[effect], gravity_m_s2=(0.0, 0.0, -G), safety_factor=safety_factor)
    sim = Simulation(cfg)
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), normal_stiffness_n_per_m=KW, friction=0.5))
    m = sphere_mass(R, RHO)
    sim.add_spheres([[0.0, 0.0, R - m * G / KN]], [R])
    sim.run(duration_s=0.02)  # seat the contact: the normal oscillation dies out
    return sim


def _linear_model(kr: float, cr: float):
    """State matrix of (x, theta, x', theta') and the slow mode's eigenvector and frequency."""
    m = sphere_mass(R, RHO)
    inertia = 0.4 * m * R * R
    a = R - 0.5 * m * G / KN  # lever arm to the contact point: radius less half the overlap
    kt = KN  # shear-to-normal stiffness ratio 1
    stiff = np.array([[kt, -a * kt], [-a * kt, a * a * kt + kr]])
    mass = np.diag([m, inertia])
    damp = np.diag([0.0, cr])
    minv = np.linalg.inv(mass)
    state = np.block([[np.zeros((2, 2)), np.eye(2)], [-minv @ stiff, -minv @ damp]])
    w2, vecs = np.linalg.eig(minv @ stiff)
    slow = int(np.argmin(w2.real))
    return state, vecs[:, slow].real, math.sqrt(w2[slow].real)


def _trajectory(sim: Simulation, v0, w0, periods: float, omega: float):
    """x velocity and y angular velocity of the sphere, sampled every step, for `periods` slow periods."""
    sim.set_velocities([[v0, 0.0, 0.0]], [[0.0, w0, 0.0]])
    t0 = sim.time_s
    n = int(periods * 2.0 * math.pi / omega / sim.timestep_s)
    times, vx, wy = [], [], []
    for _ in range(n):
        sim.run(steps=1)
        times.append(sim.time_s - t0)
        vx.append(sim.velocities_m_s()[0, 0])
        wy.append(sim.angular_velocities_rad_s()[0, 1])
    return np.array(times), np.array(vx), np.array(wy)


def _check_against_linear_model(effect, kr, cr, safety_factor=0.1):
    sim = _seated(effect, safety_factor)
    state, mode, omega = _linear_model(kr, cr)
    m = sphere_mass(R, RHO)
    cap = MU_R * R * m * G
    # rolling amplitude a quarter of the way to the cap: theta_max = w0 / omega
    w0 = 0.25 * cap / kr * omega
    v0 = w0 * mode[0] / mode[1]
    times, vx, wy = _trajectory(sim, v0, w0, periods=5.0, omega=omega)
    z0 = np.array([0.0, 0.0, v0, w0])
    expected = np.array([expm(state * t) @ z0 for t in times])
    # velocity Verlet's phase error over 5 periods is O((omega dt)^2), and a dashpot acting on the
    # half-step velocity errs by O(C dt / I): each about a percent of the amplitude at these steps
    assert np.max(np.abs(wy - expected[:, 3])) < 0.03 * w0
    assert np.max(np.abs(vx - expected[:, 2])) < 0.03 * abs(v0)
    return times, wy


def test_epsd2_rolling_spring_is_tangential_stiffness_times_radius_squared():
    effect = EffectSpec(name="rolling_epsd2", params={"rolling_friction": MU_R}, contact_types=["particle-wall"])
    _check_against_linear_model(effect, kr=KN * R * R, cr=0.0)


def test_epsd_rolling_spring_and_dashpot_follow_ai_et_al():
    effect = EffectSpec(name="rolling_epsd", params={"rolling_friction": MU_R, "rolling_damping_ratio": ETA_R},
                        contact_types=["particle-wall"])
    kr = 2.25 * KN * MU_R ** 2 * R * R
    inertia_roll = 1.4 * sphere_mass(R, RHO) * R * R
    # the dashpot's rate C_r / I is 1.2e4 /s: a step of a fifth of the usual keeps C_r dt / I at 3 %
    times, wy = _check_against_linear_model(effect, kr=kr, cr=ETA_R * 2.0 * math.sqrt(inertia_roll * kr),
                                            safety_factor=0.02)
    # the dashpot dissipates: the rocking has lost most of its amplitude after five periods
    last = times > times[-1] - 2.0 * math.pi / _linear_model(kr, 0.0)[2]
    assert np.max(np.abs(wy[last])) < 0.5 * np.max(np.abs(wy))

