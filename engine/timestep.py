"""Critical time step of the explicit integrator, accounting for damping and rotation.

For a damped oscillator (frequency w, damping ratio z) velocity Verlet with the dashpot on the
half-step velocity is stable for w dt < 2 (sqrt(1 + z^2) - z). The tangential mode of a contact
couples rotation: its mass is m_eff / (1 + m r^2 / I) (2/7 of m_eff for a solid sphere), so it is
sqrt(3.5) = 1.87x faster and its damping ratio is 1.87x higher; with a tangential dashpot at 0.8 that
mode limits the step (the instability LIGGGHTS showed at dt = 0.2 sqrt(m/kn)). The recommended step is
safety_factor x the critical one, leaving room for several contacts per particle.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class TimestepReport:
    critical_s: float
    timestep_s: float
    limiting_mode: str
    safety_factor: float


def _mode_limit(omega: float, zeta: float) -> float:
    if omega <= 0.0:
        return math.inf
    a = 2.0 * (math.sqrt(1.0 + zeta * zeta) - zeta)
    if zeta > 0.0:
        a = min(a, 1.0 / zeta)
    return a / omega


def critical_timestep(body_mass, body_rot_factor, sphere_kp, sphere_body, wall_kn, props, n_mat,
                      extra_limits=(), effect_stiffness=()) -> tuple[float, str]:
    """Smallest stable step over the normal and tangential modes of particle-particle and -wall contacts.

    ``effect_stiffness``: (label, contact_type, kn, kt) of a contact law that replaces the linear springs (Hertz
    at its reference overlap), judged with the same masses, damping and rotation as the linear modes."""
    m_min = float(body_mass.min())
    rot = float(body_rot_factor.max())
    kp = float(sphere_kp.max())
    nn = n_mat * n_mat
    modes = {}
    pp, pw = props[:nn], props[nn:]
    contact_types = {"particle-particle": (0.5 * m_min, pp), "particle-wall": (m_min, pw)}

    def add(label, k, ks, m_eff, rows):
        zn, zs = float(rows[:, 1].max()), float(rows[:, 2].max())
        modes[f"{label} normal"] = _mode_limit(math.sqrt(k / m_eff), zn)
        if ks > 0:
            modes[f"{label} tangential"] = _mode_limit(math.sqrt(ks * rot / m_eff), zs * math.sqrt(rot))

    for label, k in (("particle-particle", 0.5 * kp),
                     ("particle-wall", kp * float(wall_kn.max()) / (kp + float(wall_kn.max())) if wall_kn.size else 0.0)):
        if k <= 0.0:
            continue
        m_eff, rows = contact_types[label]
        add(label, k, float(rows[:, 0].max()) * k, m_eff, rows)
    for label, contact_type, kn, kt in effect_stiffness:
        m_eff, rows = contact_types[contact_type]
        if kn > 0.0:
            add(f"{label} {contact_type}", kn, kt, m_eff, rows)
    for label, dt in extra_limits:
        modes[label] = dt
    name = min(modes, key=modes.get)
    return modes[name], name


def effect_limits(effects, density_kg_m3: float, r_min_m: float) -> tuple[list, list]:
    """(extra_limits, effect_stiffness) for ``critical_timestep`` from the active contact effects, given as
    (name, effect, validated params): each effect's own step limit and the stiffness of a law that replaces the
    linear springs. One place for the simulation and for the step an export hands to LIGGGHTS."""
    extra, stiff = [], []
    for name, eff, params in effects:
        if eff.timestep_limit is not None:
            extra.append((name, eff.timestep_limit(params, density_kg_m3, r_min_m)))
        if eff.contact_stiffness is not None:
            for contact_type in ("particle-particle", "particle-wall"):
                stiff.append((name, contact_type, *eff.contact_stiffness(params, contact_type, r_min_m)))
    return extra, stiff


def rotation_factor(mass, inertia, reach) -> np.ndarray:
    """1 + m r^2 / I_min per body: how much rotation speeds up a tangential contact mode."""
    return 1.0 + mass * reach * reach / inertia.min(axis=1)
