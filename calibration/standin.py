"""Closed-form stand-in for a DEM battery, with every diagnosis candidate modelled.

Why: the calibration loop, and above all the missing-physics diagnosis, must be testable in
milliseconds on data whose hidden effect we know. The forms below are smooth caricatures of the
trends of the thesis (Tables 4.6-4.8, 5.3) and of the granular-physics literature summarised in
docs/diagnosis.md, not a substitute for the engine:

* solid fraction falls with sliding friction, wall friction, rolling resistance, elongation and
  cohesion (Table 4.8; Zhou et al. 2001; Azema & Radjai 2010); bulk density = rho_p x solid fraction
  (Table 4.6, slope ~0.56);
* the critical-state friction angle saturates with mu_pp at a ceiling that only rolling resistance
  or elongation lift (Estrada et al. 2008); dilatancy grows with both and falls slowly with stress;
  residual shear stress = c + (sigma_n + self weight) tan(phi_cv + 0.8 psi + box friction);
* E' grows with contact stiffness over grain size and with packing density; a linear contact gives a
  nearly flat E'(sigma) (log-log slope ~0.05, from rising coordination), a Hertzian one
  sigma^0.4 (Makse et al. 2004), its level set by Young's modulus instead of kp;
* cohesion adds a Mohr-Coulomb intercept (and a steeper pile, a larger pull-out force);
* angle of repose and anchor pull-out force add saturating terms of the same parameters.

Effects and their parameters are read through the engine's registry (``engine.effects``) and the
candidate declarations (``engine.candidates``), so the stand-in knows exactly the effects the engine
knows; an unknown name or parameter is refused as the engine refuses it.

``Gains`` holds every constant. ``Gains.perturbed`` returns another plausible world (other gains
and exponents, another saturation law) for hidden-effect "measurements": the model under test
never sees the functions that made its data (no inverse crime).
"""
from __future__ import annotations

import math
import zlib
from dataclasses import dataclass, fields, replace
from typing import Any, Mapping

import numpy as np

from engine.candidates import candidates
from engine.effects import get as get_effect
from engine.effects.base import STANDIN_TERMS
from engine.effects.hertz_mindlin import MATCH_STRESS_PA
from engine.lab.registry import quantity

G_M_S2 = 9.81
E_REF_STRESS_PA = 30.0e3          # E'(sigma) is written about this stress
PSI_REF_STRESS_PA = 24.0e3        # dilatancy is written about this stress (Table 3.1 second load)
SELF_WEIGHT_HEIGHT_M = 0.09       # half the screening box's upper half: the self-weight lever


@dataclass(frozen=True)
class Gains:
    # solid fraction
    solid_fraction_0: float = 0.605
    solid_loss_friction: float = 0.035
    solid_loss_wall: float = 0.006
    solid_loss_rolling: float = 0.040
    solid_loss_shape: float = 0.035
    solid_loss_cohesion: float = 0.020
    # friction and dilatancy (degrees)
    phi_floor_deg: float = 18.0
    phi_ceiling_deg: float = 28.0
    phi_ceiling_rolling_deg: float = 30.0
    phi_ceiling_shape_deg: float = 14.0
    friction_scale: float = 0.35
    psi_0_deg: float = 2.0
    psi_friction_deg: float = 6.0
    psi_rolling_deg: float = 5.0
    psi_shape_deg: float = 10.0
    psi_stress_exponent: float = 0.08
    psi_to_phi: float = 0.8
    box_friction_deg: float = 2.0
    # cohesion
    cohesion_max_pa: float = 12.0e3
    # half the maximum intercept at this surface energy of the adhesive contact (F_c = 3/2 pi Gamma R*)
    cohesion_half_j_m2: float = 100.0
    # modulus
    modulus_gain: float = 0.125
    modulus_friction_gain: float = 0.25
    modulus_shape_gain: float = 0.12
    modulus_linear_exponent: float = 0.05
    modulus_hertz_exponent: float = 0.40
    # angle of repose (degrees) and anchor
    aor_floor_deg: float = 16.0
    aor_friction_deg: float = 14.0
    aor_rolling_deg: float = 12.0
    aor_shape_deg: float = 9.0
    aor_cohesion_deg: float = 14.0
    anchor_wedge_volume_m3: float = 0.02
    anchor_shear_factor: float = 1.5
    anchor_surface_m2: float = 0.06
    # 1 - exp(-x) (None) or 1 - (1 + x/p)^-p: the same start and ceiling, another approach to it
    saturation_power: float | None = None
    # unload-reload modulus: E_ur = 3 E' at the reference stress (the Hardening Soil model's E_ur = 3 E_50,
    # Schanz et al. 1999), growing as sigma^n with the contact network (n for linear springs) and, for Hertzian
    # contacts, a further 1/3 (a fixed network of Hertzian contacts, Goddard 1990). In LATER_GAINS (perturbed).
    unload_reload_ratio: float = 3.0
    unload_reload_network_exponent: float = 0.10

    def sat(self, x: float) -> float:
        if self.saturation_power is None:
            return 1.0 - math.exp(-x)
        p = self.saturation_power
        return 1.0 - (1.0 + x / p) ** (-p)

    def perturbed(self, rng: np.random.Generator, relative: float = 0.05,
                  saturation_power: float = 4.0) -> "Gains":
        """Another world: every gain and exponent scaled by 1 + U(-relative, relative).

        The gains added after the test beds were fixed (``LATER_GAINS``) are drawn from a stream jumped ahead of
        ``rng``, which leaves ``rng`` where the earlier gains left it: a caller that goes on drawing from it (tier
        A's measurement noise) sees the same numbers as before, so its worlds and figures stay reproducible."""
        later = np.random.Generator(rng.bit_generator.jumped())
        changes = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "saturation_power" or value is None:
                continue
            source = later if f.name in LATER_GAINS else rng
            changes[f.name] = value * (1.0 + relative * float(source.uniform(-1.0, 1.0)))
        return replace(self, saturation_power=saturation_power, **changes)


LATER_GAINS = frozenset({"unload_reload_ratio", "unload_reload_network_exponent"})


# Seed-to-seed scatter of one simulated battery (packing randomness): a relative sd for
# quantities that scale, an absolute one (degrees) for angles. Half the laboratory's scatter.
SIMULATOR_SD = {
    ("fill", "bulk_density_kg_m3"): ("relative", 0.005),
    ("cct", "confined_modulus_pa"): ("relative", 0.04),
    ("cct", "unload_reload_modulus_pa"): ("relative", 0.04),
    ("dst", "residual_shear_stress_pa"): ("relative", 0.02),
    ("dst", "dilatancy_angle_deg"): ("absolute", 0.75),
    ("aor", "angle_of_repose_deg"): ("absolute", 0.5),
    ("anchor", "peak_pull_force_n"): ("relative", 0.03),
}


@dataclass(frozen=True)
class Conditions:
    """Which conditions a battery reports (normal stresses of the DST loads, E' stresses)."""

    dst_normal_stresses_pa: tuple[float, ...] = (10.5e3, 24.0e3, 38.3e3, 52.4e3)
    cct_window_stresses_pa: tuple[float, ...] = ()
    cct_unload_reload_stresses_pa: tuple[float, ...] = ()
    cct_max_stress_pa: float = 65.6e3
    include_aor: bool = False
    include_anchor: bool = False


def _rational(x: float, half: float) -> float:
    return x / (x + half) if x > 0 else 0.0


def standin_terms(parameters: Mapping[str, Any]) -> dict[str, float]:
    """The stand-in's physical terms (``engine.effects.base.STANDIN_TERMS``) in a parameter set.

    Why through declarations: each contact effect says how the stand-in represents it
    (``Effect.standin``, its parameters validated by the engine's own model), and a candidate that is a
    micro parameter names its term (``Candidate.standin_term``, its strength above the value at which
    it vanishes), so the stand-in names no effect. Terms of several effects add (two rolling models);
    an effect without a closed form here (SJKR cohesion on a linear spring gives no intercept) feeds none.
    """
    terms: dict[str, float] = {}
    for name, params in (parameters.get("effects") or {}).items():
        effect = get_effect(name)            # ValueError naming the known effects
        if effect.standin is not None:
            for term, value in effect.standin(effect.params_model.model_validate(dict(params))).items():
                terms[term] = terms.get(term, 0.0) + value
    for c in candidates().values():
        if c.standin_term is not None and c.factor in parameters:
            terms[c.standin_term] = terms.get(c.standin_term, 0.0) + float(parameters[c.factor]) - (c.off_value or 0.0)
    unknown = set(terms) - set(STANDIN_TERMS)
    if unknown:
        raise ValueError(f"the stand-in has no term {sorted(unknown)} (it knows {', '.join(STANDIN_TERMS)})")
    return terms


def _hertz_equivalent_stiffness(young_modulus_pa: float, poisson_ratio: float, radius_m: float) -> float:
    """kp whose linear contact matches a Hertzian one of this modulus at MATCH_STRESS_PA.

    The inverse of ``engine.effects.hertz_mindlin.matched_young_modulus_pa``.
    """
    e_star = young_modulus_pa / (2.0 * (1.0 - poisson_ratio**2))
    force_n = MATCH_STRESS_PA * (2.0 * radius_m) ** 2
    kn = (e_star * math.sqrt(6.0 * force_n * 0.5 * radius_m)) ** (2.0 / 3.0)
    return 2.0 * kn


def bulk_values(parameters: Mapping[str, Any], conditions: Conditions, gains: Gains = Gains()) -> list[dict]:
    """Noise-free bulk values: a list of {test, quantity, condition, value} (SI)."""
    g = gains
    rho_p = float(parameters.get("particle_density_kg_m3", 2500.0))
    mu = float(parameters.get("friction_pp", 0.86))
    mu_w = float(parameters.get("friction_pw", 0.62))
    kp = float(parameters.get("particle_stiffness_n_per_m", 1.72e6))
    radius = float(parameters.get("particle_radius_m") or 0.020)
    terms = standin_terms(parameters)
    elongation = terms.get("elongation", 0.0)
    mu_r = terms.get("rolling_friction", 0.0)
    gamma = terms.get("surface_energy_j_m2", 0.0)
    hertz_modulus_pa = terms.get("hertz_young_modulus_pa")

    solid = (g.solid_fraction_0 - g.solid_loss_friction * g.sat(mu / 0.25) - g.solid_loss_wall * g.sat(mu_w / 0.2)
             - g.solid_loss_rolling * _rational(mu_r, 0.2) - g.solid_loss_shape * _rational(elongation, 0.3)
             - g.solid_loss_cohesion * _rational(gamma, 80.0))
    rho_b = rho_p * solid
    cohesion_pa = g.cohesion_max_pa * _rational(gamma, g.cohesion_half_j_m2)
    ceiling = (g.phi_ceiling_deg + g.phi_ceiling_rolling_deg * _rational(mu_r, 0.2)
               + g.phi_ceiling_shape_deg * _rational(elongation, 0.3))
    phi_cv = g.phi_floor_deg + (ceiling - g.phi_floor_deg) * g.sat(mu / g.friction_scale)
    psi_ref = (g.psi_0_deg + g.psi_friction_deg * g.sat(mu / 0.4) + g.psi_rolling_deg * _rational(mu_r, 0.2)
               + g.psi_shape_deg * _rational(elongation, 0.4))
    self_weight_pa = rho_b * G_M_S2 * SELF_WEIGHT_HEIGHT_M

    def psi(stress):
        return psi_ref * (stress / PSI_REF_STRESS_PA) ** (-g.psi_stress_exponent)

    def phi_peak(stress):
        return phi_cv + g.psi_to_phi * psi(stress) + g.box_friction_deg * mu_w

    def tau(stress):
        return cohesion_pa + (stress + self_weight_pa) * math.tan(math.radians(min(phi_peak(stress), 85.0)))

    if hertz_modulus_pa is not None:
        k_level, exponent = _hertz_equivalent_stiffness(hertz_modulus_pa, terms["hertz_poisson_ratio"], radius), \
            g.modulus_hertz_exponent
    else:
        k_level, exponent = kp, g.modulus_linear_exponent
    e_ref = (g.modulus_gain * k_level / (2.0 * radius) * (solid / 0.56) ** 3
             * (1.0 + g.modulus_friction_gain * mu / (mu + 0.2))
             * (1.0 + g.modulus_shape_gain * _rational(elongation, 0.5)))

    def modulus(stress):
        return e_ref * (stress / E_REF_STRESS_PA) ** exponent

    ur_exponent = g.unload_reload_network_exponent + (1.0 / 3.0 if hertz_modulus_pa is not None else 0.0)

    out = [
        ("fill", "bulk_density_kg_m3", rho_b, {}),
        ("fill", "porosity", 1.0 - solid, {}),
        ("fill", "voids_ratio", (1.0 - solid) / solid, {}),
        ("cct", "confined_modulus_pa", modulus(0.5 * conditions.cct_max_stress_pa), {}),
    ]
    out += [("cct", "confined_modulus_pa", modulus(s), {"normal_stress_pa": s})
            for s in conditions.cct_window_stresses_pa]
    out += [("cct", "unload_reload_modulus_pa", g.unload_reload_ratio * e_ref * (s / E_REF_STRESS_PA) ** ur_exponent,
             {"normal_stress_pa": s}) for s in conditions.cct_unload_reload_stresses_pa]
    for s in conditions.dst_normal_stresses_pa:
        out.append(("dst", "residual_shear_stress_pa", tau(s), {"normal_stress_pa": s}))
        out.append(("dst", "dilatancy_angle_deg", psi(s), {"normal_stress_pa": s}))
    if conditions.include_aor:
        aor = (g.aor_floor_deg + g.aor_friction_deg * g.sat(mu / 0.4) + g.aor_rolling_deg * _rational(mu_r, 0.15)
               + g.aor_shape_deg * _rational(elongation, 0.3) + g.aor_cohesion_deg * _rational(cohesion_pa, 3.0e3)
               + 1.5 * mu_w)
        out.append(("aor", "angle_of_repose_deg", aor, {}))
    if conditions.include_anchor:
        wedge_n = rho_b * G_M_S2 * g.anchor_wedge_volume_m3
        shear = g.anchor_shear_factor * math.tan(math.radians(min(phi_peak(5.0e3), 85.0)))
        force = wedge_n * (1.0 + shear) + cohesion_pa * g.anchor_surface_m2
        out.append(("anchor", "peak_pull_force_n", force, {}))
    return [{"test": t, "quantity": q, "value": float(v), "unit": quantity(t, q).unit, "condition": dict(c)}
            for t, q, v, c in out]


def _key_seed(seed: int, record: dict) -> list[int]:
    """Per-(seed, key) stream: the same seed gives the same packing noise on every quantity,
    whatever else the battery reports (common random numbers across parameter sets)."""
    text = f"{record['test']}/{record['quantity']}/" + ",".join(
        f"{k}={v:.9g}" for k, v in sorted(record["condition"].items()))
    return [int(seed), zlib.crc32(text.encode())]


def add_simulator_noise(records: list[dict], seed: int, scale: float = 1.0) -> list[dict]:
    """Seed-to-seed scatter of SIMULATOR_SD on every quantity that has one (derived ones follow)."""
    out = []
    for rec in records:
        kind = SIMULATOR_SD.get((rec["test"], rec["quantity"]))
        value = rec["value"]
        if kind is not None:
            z = float(np.random.default_rng(_key_seed(seed, rec)).standard_normal())
            sd = kind[1] * abs(value) if kind[0] == "relative" else kind[1]
            value = value + scale * sd * z
        out.append({**rec, "value": float(value)})
    return out


def battery(parameters: Mapping[str, Any], seed: int, conditions: Conditions = Conditions(),
            gains: Gains = Gains(), noise_scale: float = 1.0) -> list[dict]:
    """One simulated battery: noise-free values plus the seed's scatter, and the quantities the lab
    derives from them (friction angle and cohesion of the Mohr-Coulomb line, mean dilatancy)."""
    records = add_simulator_noise(bulk_values(parameters, conditions, gains), seed, noise_scale)
    for rec in records:
        if rec["quantity"] == "porosity":
            density = next(r for r in records if r["quantity"] == "bulk_density_kg_m3")["value"]
            rho_p = float(parameters.get("particle_density_kg_m3", 2500.0))
            rec["value"] = 1.0 - density / rho_p
        if rec["quantity"] == "voids_ratio":
            density = next(r for r in records if r["quantity"] == "bulk_density_kg_m3")["value"]
            solid = density / float(parameters.get("particle_density_kg_m3", 2500.0))
            rec["value"] = (1.0 - solid) / solid
    shear = [(r["condition"]["normal_stress_pa"], r["value"]) for r in records
             if r["quantity"] == "residual_shear_stress_pa"]
    if len({s for s, _ in shear}) >= 2:
        sigma, tau = (np.array(v) for v in zip(*shear))
        slope, intercept = np.polyfit(sigma, tau, 1)
        fitted = slope * sigma + intercept
        ss_tot = float(np.sum((tau - tau.mean()) ** 2))
        r2 = 1.0 - float(np.sum((tau - fitted) ** 2)) / ss_tot if ss_tot > 0 else 1.0
        records += [
            {"test": "dst", "quantity": "friction_angle_deg", "value": math.degrees(math.atan(slope)),
             "unit": "deg", "condition": {}},
            {"test": "dst", "quantity": "cohesion_pa", "value": float(intercept), "unit": "Pa", "condition": {}},
            {"test": "dst", "quantity": "mohr_coulomb_r2", "value": r2, "unit": "1", "condition": {}},
        ]
    psis = [r["value"] for r in records if r["quantity"] == "dilatancy_angle_deg"]
    if psis:
        records.append({"test": "dst", "quantity": "dilatancy_angle_deg", "value": float(np.mean(psis)),
                        "unit": "deg", "condition": {}})
    return records
