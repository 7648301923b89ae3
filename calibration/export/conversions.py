"""demcal's contact conventions turned into LIGGGHTS-PUBLIC 3.8.0's, one pure function each.

Why a module of its own: a factor of 2 in stiffness or a rolling spring 20 times too soft silently
voids a calibration, so every conversion is one small function with its source, unit-tested against
a hand calculation (tests/export/test_liggghts_conversions.py).

demcal (engine/config.py, engine/kernel_template.py):
* stiffness is PFC-style: every entity has a normal stiffness (particle kp, wall kw) and a contact
  is the two springs in series, kn = k1 k2 / (k1 + k2); ks = (shear/normal ratio) kn;
* the dashpot is c = 2 zeta sqrt(k m*) with the contact's stiffness k and effective mass
  m* = m1 m2 / (m1 + m2) (the particle's mass for a wall contact; the clump's mass for a clump).

LIGGGHTS-PUBLIC 3.8.0 (src/normal_model_hooke_stiffness.h, normal_model_hertz.h, pair_gran_base.h):
* ``model hooke/stiffness`` takes kn, kt per type pair (N/m) and, with ``absolute_damping off`` (the
  default), c = m* gamman: gamman is a damping *per unit effective mass* (1/s); m* = mi mj/(mi + mj)
  of the atoms' masses (pair_gran_base.h), the particle's mass for a wall. A sphere of a multisphere
  body carries the body's mass as its atom mass (checked in 3.8.0: a dump of a two-sphere clump's
  atoms shows the clump's mass on each), so m* is the body mass for clumps, as in demcal;
* ``model hertz`` takes Young's modulus and Poisson's ratio per type and a restitution coefficient
  per type pair: c = -2 sqrt(5/6) beta sqrt(S m*), S = 2 Y* sqrt(R* delta), beta = ln e /
  sqrt(ln^2 e + pi^2); the tangential dashpot uses the same beta with St = 8 G* sqrt(R* delta).
"""
from __future__ import annotations

import math

SQRT_FIVE_SIXTHS = math.sqrt(5.0 / 6.0)
# LIGGGHTS refuses coefficientRestitution <= 0.05 ("0.05 < coefficientRestitution <= 1 required",
# src/global_properties.cpp, seen running the export): the smallest value it takes, just above the bound
LIGGGHTS_MIN_RESTITUTION = 0.05
LIGGGHTS_SMALLEST_RESTITUTION = 0.0500001


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return value


def _damping_ratio(zeta: float) -> float:
    zeta = float(zeta)
    if not (math.isfinite(zeta) and 0.0 <= zeta < 1.0):
        raise ValueError(f"damping ratio must be in [0, 1), got {zeta!r}")
    return zeta


def _in_series(name: str, a: float, b: float | None) -> float:
    """a b / (a + b), the one combination of two springs, masses or radii of a pair; ``b`` None is a wall
    (infinitely stiff, heavy, flat): a."""
    a = _positive(f"{name}1", a)
    if b is None:
        return a
    b = _positive(f"{name}2", b)
    return a * b / (a + b)


def series_stiffness_n_per_m(k1_n_per_m: float, k2_n_per_m: float) -> float:
    """Contact stiffness of two PFC-style entity springs in series: k1 k2 / (k1 + k2)."""
    return _in_series("k", k1_n_per_m, _positive("k2", k2_n_per_m))


def effective_mass_kg(m1_kg: float, m2_kg: float | None = None) -> float:
    """m* = m1 m2 / (m1 + m2); ``m2_kg`` None is a wall (infinitely heavy): m* = m1."""
    return _in_series("m", m1_kg, m2_kg)


def effective_radius_m(r1_m: float, r2_m: float | None = None) -> float:
    """R* = r1 r2 / (r1 + r2); ``r2_m`` None is a wall: R* = r1 (both codes)."""
    return _in_series("r", r1_m, r2_m)


def sphere_mass_kg(density_kg_m3: float, radius_m: float) -> float:
    return _positive("density", density_kg_m3) * 4.0 / 3.0 * math.pi * _positive("radius", radius_m) ** 3


def damping_coefficient_n_s_per_m(damping_ratio: float, stiffness_n_per_m: float, effective_mass: float) -> float:
    """demcal's dashpot: c = 2 zeta sqrt(k m*), N s/m."""
    return 2.0 * _damping_ratio(damping_ratio) * math.sqrt(
        _positive("stiffness", stiffness_n_per_m) * _positive("effective mass", effective_mass))


def hooke_gamma_per_unit_mass_1_s(damping_ratio: float, stiffness_n_per_m: float, effective_mass: float) -> float:
    """LIGGGHTS hooke/stiffness gamman (absolute_damping off, c = m* gamman) giving demcal's c:
    gamman = c / m* = 2 zeta sqrt(k / m*), 1/s."""
    return damping_coefficient_n_s_per_m(damping_ratio, stiffness_n_per_m, effective_mass) / effective_mass


def linear_restitution_coefficient(damping_ratio: float) -> float:
    """Restitution of a linear spring-dashpot at damping ratio zeta (continuous time):
    e = exp(-pi zeta / sqrt(1 - zeta^2)). What a user of ``model hooke`` would set; the export keeps
    hooke/stiffness with gamma so that no integrator detail enters (RESULTS.md: at zeta 0.8 the
    discrete restitution is 0.0008-0.003 against 0.015)."""
    zeta = _damping_ratio(damping_ratio)
    return math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta * zeta))


def hertz_beta(restitution: float) -> float:
    """LIGGGHTS' beta = ln e / sqrt(ln^2 e + pi^2) (negative for e < 1)."""
    e = float(restitution)
    if not 0.0 < e <= 1.0:
        raise ValueError(f"restitution must be in (0, 1], got {restitution!r}")
    log_e = math.log(e)
    return log_e / math.sqrt(log_e * log_e + math.pi * math.pi)


def hertz_restitution_for_damping_ratio(damping_ratio: float) -> float:
    """coefficientRestitution for LIGGGHTS ``model hertz`` whose dashpot equals demcal's Hertz dashpot.

    demcal: c = 2 zeta sqrt(S m*) with S = 2 E* sqrt(R* delta) (the tangent stiffness);
    LIGGGHTS: c = -2 sqrt(5/6) beta sqrt(S m*). Equal when -beta = zeta sqrt(6/5) =: b, i.e.
    ln e = -pi b / sqrt(1 - b^2). Needs b < 1 (zeta < sqrt(5/6) = 0.913): LIGGGHTS' Hertz dashpot
    cannot be stronger than that, and a higher ratio is refused rather than clipped.
    """
    zeta = _damping_ratio(damping_ratio)
    b = zeta / SQRT_FIVE_SIXTHS
    if b >= 1.0:
        raise ValueError(f"damping ratio {zeta:g} exceeds sqrt(5/6) = {SQRT_FIVE_SIXTHS:.4f}, the strongest "
                         "dashpot LIGGGHTS' hertz model can express (restitution 0)")
    return math.exp(-math.pi * b / math.sqrt(1.0 - b * b))


def hertz_damping_ratio_of_restitution(restitution: float) -> float:
    """The damping ratio LIGGGHTS' hertz dashpot gives at restitution e: zeta = -sqrt(5/6) beta(e)."""
    return -SQRT_FIVE_SIXTHS * hertz_beta(restitution)


def hertz_effective_moduli_pa(e1_pa: float, nu1: float, e2_pa: float, nu2: float) -> tuple[float, float]:
    """(Y*, G*) of LIGGGHTS' hertz and demcal's hertz_mindlin: 1/Y* = (1-nu1^2)/E1 + (1-nu2^2)/E2,
    1/G* = 2 (2-nu1)(1+nu1)/E1 + 2 (2-nu2)(1+nu2)/E2."""
    e1, e2 = _positive("E1", e1_pa), _positive("E2", e2_pa)
    y_star = 1.0 / ((1 - nu1 ** 2) / e1 + (1 - nu2 ** 2) / e2)
    g_star = 1.0 / (2 * (2 - nu1) * (1 + nu1) / e1 + 2 * (2 - nu2) * (1 + nu2) / e2)
    return y_star, g_star


def epsd2_rolling_stiffness_n_m_per_rad(tangential_stiffness_n_per_m: float, effective_radius: float) -> float:
    """EPSD2 rolling spring, k_r = k_t R*^2 (both codes: LIGGGHTS src/rolling_model_epsd2.h
    ``kr = cdata.kt*reff*reff``; demcal engine/effects/rolling_epsd2.py). Nothing to convert: the
    rolling friction coefficient mu_r goes across as coefficientRollingFriction."""
    return _positive("kt", tangential_stiffness_n_per_m) * _positive("R*", effective_radius) ** 2


def epsd_rolling_stiffness_n_m_per_rad(normal_stiffness_n_per_m: float, rolling_friction: float,
                                       effective_radius: float) -> float:
    """EPSD rolling spring, k_r = 2.25 k_n mu_r^2 R*^2 (LIGGGHTS src/rolling_model_epsd.h; Ai et al. 2011;
    demcal engine/effects/rolling_epsd.py)."""
    mu_r = float(rolling_friction)
    if not (math.isfinite(mu_r) and mu_r >= 0):
        raise ValueError(f"rolling friction must be a finite number >= 0, got {rolling_friction!r}")
    return 2.25 * _positive("kn", normal_stiffness_n_per_m) * mu_r * mu_r * _positive("R*", effective_radius) ** 2


def stiffness_ratio_tangential_n_per_m(normal_n_per_m: float, shear_to_normal_ratio: float) -> float:
    """kt = (ks/kn) kn: demcal's shear stiffness is a ratio of the contact's normal stiffness."""
    ratio = float(shear_to_normal_ratio)
    if not (math.isfinite(ratio) and ratio >= 0):
        raise ValueError(f"shear/normal stiffness ratio must be >= 0, got {shear_to_normal_ratio!r}")
    return ratio * _positive("kn", normal_n_per_m)
