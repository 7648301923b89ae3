"""A calibrated material as a LIGGGHTS-PUBLIC 3.8.0 input include (issue 30, item 2).

``render(material)`` returns the include's text and the list of places where LIGGGHTS cannot express
demcal's model exactly. The include defines, after the user's ``create_box N`` (N in its header):

* one atom type per sphere size and per clump template, the last type for walls;
* ``fix property/global`` blocks per type pair: kn/kt and gamman/gammat (``model hooke/stiffness``,
  demcal's linear law) or Young's modulus, Poisson's ratio and restitution (``model hertz``, when the
  material has ``hertz_mindlin``), coefficientFriction, and the rolling/cohesion coefficients;
* ``pair_style gran`` with tangential history and the rolling / cohesion sub-models;
* ``variable demcal_wall_model`` / ``demcal_wall_settings`` holding the same contact model for the
  user's ``fix wall/gran`` lines (model before the wall's shape, settings after it), ``demcal_wall_type``, and the particle templates with a distribution
  ``demcal_pdd`` for the user's insertion fix (multisphere templates and ``fix multisphere`` for clumps);
* ``variable demcal_dt``: demcal's own time step rule (0.3 x the critical step of its integrator).

Every conversion is a function of ``calibration.export.conversions`` and is listed in the header.
Where LIGGGHTS-PUBLIC has no exact counterpart (demcal's adhesive contact with a tensile branch,
Cundall local damping, Hertz with a shear damping ratio other than the normal one) the include says
so, names the nearest LIGGGHTS model and its expected difference, and leaves that model commented
out: an include that only looks equivalent would void the calibration silently.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from calibration.export import conversions as cv
from calibration.export.material import ExportMaterial, body_masses_kg

LIGGGHTS_VERSION = "LIGGGHTS-PUBLIC 3.8.0"
# demcal's lab runs at this fraction of the critical step (engine.config.SimulationConfig.safety_factor)
DEMCAL_SAFETY_FACTOR = 0.3
# LIGGGHTS' fix multisphere needs a finer step than demcal's clumps: measured on the screening rig's two-sphere
# clumps (docs/export.md), the lid force's sample-to-sample jump at high load was 4.6 % of the peak at demcal's
# step, 0.40 % at half of it and 0.42 % at a quarter (single spheres: 0.3-0.4 % at demcal's step)
MULTISPHERE_STEP_FACTOR = 0.5
_HANDLED_EFFECTS = ("hertz_mindlin", "rolling_epsd2", "rolling_epsd", "rolling_constant_torque",
                    "cohesion_sjkr", "cohesion_adhesive")


@dataclass
class LiggghtsExport:
    text: str
    n_atom_types: int
    wall_type: int
    particle_types: list[int]
    distribution_id: str
    timestep_s: float
    conversions: list[str] = field(default_factory=list)
    inexact: list[str] = field(default_factory=list)
    has_clumps: bool = False


# What the two engines were measured to differ by, on the same packings (docs/export.md, "E' on the same packings";
# bench/engine_difference.py, 2026-11-28): (LIGGGHTS - demcal) / demcal, mean +- standard error over packings of the
# screening rig's CCT, 20 mm spheres, 4 cycles. Carried in the include's header so that a user comparing a production
# run with the calibration knows what is the engines' and what is not.
MEASURED_DIFFERENCES = {
    "hooke/stiffness": (
        "E' (confined modulus, mean of CCT cycles 2-4) on the same packing: LIGGGHTS -1.8 % +- 1.9 % (12 packings; "
        "with the tangential dashpot, the wall friction, then all friction switched off in both: -2.5, -3.4, "
        "+3.0 % +- 2-3 %); with EPSD2 rolling resistance 0.2: -3.7 % +- 1.7 % (10 packings); in the window just "
        "below the CCT's peak stress -6.8 % +- 1.9 % (without rolling) and -3.9 % +- 2.0 % (with)",
        "one packing's E' differs between the engines by sd 6.6 % (4 cycles) to 13 % (one cycle), as much as "
        "between two restarts of demcal on the same packing: compare means over packings, never one run",
        "bulk density of each engine's own fill: LIGGGHTS 1.4-1.9 % lighter (docs/export.md)",
    ),
    "hertz": (
        "E' (mean of CCT cycles 2-4) on the same packing: LIGGGHTS +1.0 % +- 3.1 % (10 packings); in the window "
        "just below the CCT's peak stress -11.6 % +- 2.2 %",
        "one packing's E' differs between the engines by sd 10 %, as much as between two restarts of demcal: "
        "compare means over packings, never one run",
        "bulk density of each engine's own fill: LIGGGHTS 1.4 % lighter (docs/export.md)",
    ),
}
CLUMP_DIFFERENCE = ("clumps (two-sphere, aspect 1.5, at half demcal's step), each engine's own fills, 6 packings: "
                    "LIGGGHTS' E' -18 % +- 5.5 % (-28 to -33 % above 45 kPa), bulk density -2.1 % +- 0.5 %. Where "
                    "from: on demcal's packings with the bodies as fix rigid, LIGGGHTS' E' matches demcal's (-0.9 % "
                    "+- 2.5 %, 7 packings); LIGGGHTS' own packings restarted as fix rigid are +18.6 % +- 5.5 % "
                    "stiffer than under fix multisphere (+34 to +39 % above 45 kPa). The softness is fix "
                    "multisphere's in LIGGGHTS-PUBLIC 3.8.0, not demcal's; expect it in multisphere runs "
                    "(docs/export.md)")


def _primes_above(start: int, count: int) -> list[int]:
    """LIGGGHTS wants distinct prime seeds > 10000 for its templates and distributions."""
    out, n = [], start
    while len(out) < count:
        n += 1
        if n % 2 and all(n % d for d in range(3, int(math.isqrt(n)) + 1, 2)):
            out.append(n)
    return out


def _fmt(x: float) -> str:
    return f"{x:.10g}"


def _pair_table(values: dict[tuple[int, int], float], n: int) -> str:
    """Row-major n x n values of a ``peratomtypepair`` property (symmetric)."""
    return " ".join(_fmt(values[(min(i, j), max(i, j))]) for i in range(1, n + 1) for j in range(1, n + 1))


def demcal_timestep_s(material: ExportMaterial) -> float:
    """demcal's step for this material: 0.3 x the critical step of its integrator over the normal and
    tangential (rotation-coupled) modes of particle and wall contacts (engine/timestep.py)."""
    from engine.effects import REGISTRY
    from engine.timestep import critical_timestep, effect_limits, rotation_factor

    rho = material.particles.solid_density_kg_m3
    c = material.contact
    masses, inertias, reaches, r_min = [], [], [], math.inf
    for s in material.particles.spheres:
        m = cv.sphere_mass_kg(rho, s.radius_m)
        masses.append(m)
        inertias.append([0.4 * m * s.radius_m ** 2] * 3)
        reaches.append(s.radius_m)
        r_min = min(r_min, s.radius_m)
    for cl in material.particles.clumps:
        t = cl.template()
        masses.append(t.mass_kg(rho))
        inertias.append(list(t.principal_inertia_kg_m2(rho)))
        reaches.append(t.bounding_radius_m)
        r_min = min(r_min, float(np.min(t.sphere_radii_m)))
    mass = np.asarray(masses)
    rot = rotation_factor(mass, np.asarray(inertias), np.asarray(reaches))
    row = [c.shear_to_normal_stiffness_ratio, c.damping_ratio_normal, c.damping_ratio_shear, c.friction_pp]
    props = np.asarray([row, row], dtype=float)
    extra, stiff = effect_limits([(name, REGISTRY[name], REGISTRY[name].params_model.model_validate(params))
                                  for name, params in material.effects.items()], rho, r_min)
    crit, _ = critical_timestep(mass, rot, np.asarray([c.particle_stiffness_n_per_m]), np.zeros(1, dtype=np.int64),
                                np.asarray([c.wall_stiffness_n_per_m]), props, 1, extra, stiff)
    return DEMCAL_SAFETY_FACTOR * crit


def render(material: ExportMaterial, timestep_s: float | None = None) -> LiggghtsExport:
    """The include for ``material``; ``timestep_s`` None: demcal's own step for it."""
    unknown = set(material.effects) - set(_HANDLED_EFFECTS)
    if unknown:  # a new effect in engine/effects must get an export before a material using it leaves
        raise ValueError(f"effects {sorted(unknown)} have no LIGGGHTS export yet")
    p, c = material.particles, material.contact
    masses = body_masses_kg(material)
    n_part = len(masses)
    wall = n_part + 1
    n = wall
    kinds = ["sphere"] * len(p.spheres) + ["clump"] * len(p.clumps)
    names = [f"sphere r={s.radius_m * 1000:g} mm" for s in p.spheres] + [f"clump {cl.name}" for cl in p.clumps]
    conv: list[str] = []
    inexact: list[str] = []
    props: list[str] = []
    hertz = material.effect("hertz_mindlin")
    zn, zt = c.damping_ratio_normal, c.damping_ratio_shear
    pairs = [(i, j) for i in range(1, n + 1) for j in range(i, n + 1)]

    def meff(i: int, j: int) -> float:
        if i == wall and j == wall:  # never used: walls do not touch walls
            return masses[0]
        if j == wall:
            return cv.effective_mass_kg(masses[i - 1])
        return cv.effective_mass_kg(masses[i - 1], masses[j - 1])

    if hertz is None:
        kpp = cv.series_stiffness_n_per_m(c.particle_stiffness_n_per_m, c.particle_stiffness_n_per_m)
        kpw = cv.series_stiffness_n_per_m(c.particle_stiffness_n_per_m, c.wall_stiffness_n_per_m)
        kn = {(i, j): (kpw if wall in (i, j) else kpp) for i, j in pairs}
        kt = {k: cv.stiffness_ratio_tangential_n_per_m(v, c.shear_to_normal_stiffness_ratio) for k, v in kn.items()}
        gn = {(i, j): cv.hooke_gamma_per_unit_mass_1_s(zn, kn[(i, j)], meff(i, j)) for i, j in pairs}
        gt = {(i, j): (cv.hooke_gamma_per_unit_mass_1_s(zt, kt[(i, j)], meff(i, j)) if kt[(i, j)] > 0 else 0.0)
              for i, j in pairs}
        props += [f"fix demcal_kn all property/global kn peratomtypepair {n} {_pair_table(kn, n)}",
                  f"fix demcal_kt all property/global kt peratomtypepair {n} {_pair_table(kt, n)}",
                  f"fix demcal_gn all property/global gamman peratomtypepair {n} {_pair_table(gn, n)}",
                  f"fix demcal_gt all property/global gammat peratomtypepair {n} {_pair_table(gt, n)}"]
        conv += [
            f"kn = kp kp/(kp+kp) = {_fmt(kpp)} N/m particle-particle, kp kw/(kp+kw) = {_fmt(kpw)} N/m "
            f"particle-wall (PFC springs in series; kp = {_fmt(c.particle_stiffness_n_per_m)}, "
            f"kw = {_fmt(c.wall_stiffness_n_per_m)} N/m)",
            f"kt = {_fmt(c.shear_to_normal_stiffness_ratio)} kn (demcal's shear/normal stiffness ratio)",
            f"gamman = 2 zeta_n sqrt(kn/m*), gammat = 2 zeta_t sqrt(kt/m*) per type pair (1/s; hooke/stiffness "
            f"with absolute_damping off multiplies by m*): zeta_n = {_fmt(zn)}, zeta_t = {_fmt(zt)} exact for "
            "every pair; m* = m_i m_j/(m_i+m_j) of the bodies (clump mass for a clump), m_i for a wall",
        ]
        model = "model hooke/stiffness tangential history"
        settings = f"tangential_damping {'on' if zt > 0 else 'off'} absolute_damping off limitForce off"
    else:
        e_wall = hertz.wall_young_modulus_pa or hertz.young_modulus_pa
        nu_wall = hertz.wall_poisson_ratio if hertz.wall_poisson_ratio is not None else hertz.poisson_ratio
        young = " ".join([_fmt(hertz.young_modulus_pa)] * n_part + [_fmt(e_wall)])
        poisson = " ".join([_fmt(hertz.poisson_ratio)] * n_part + [_fmt(nu_wall)])
        zeta_max = cv.hertz_damping_ratio_of_restitution(cv.LIGGGHTS_SMALLEST_RESTITUTION)
        if zn < zeta_max:
            e_rest = cv.hertz_restitution_for_damping_ratio(zn)
        else:
            e_rest = cv.LIGGGHTS_SMALLEST_RESTITUTION
            inexact.append(
                f"Hertz damping ratio {zn:g}: LIGGGHTS' hertz takes coefficientRestitution > "
                f"{cv.LIGGGHTS_MIN_RESTITUTION:g} only, i.e. a damping ratio of at most {zeta_max:.3f}. Nearest: "
                f"restitution {e_rest:g} (damping ratio {zeta_max:.3f} normal and tangential); expected difference: "
                "less dissipation per collision (faster, bouncier settling, possibly a slightly denser fill); the "
                "quasi-static stiffness is unchanged. Alternatively use demcal's damping ratio <= "
                f"{zeta_max:.3f} in the calibration.")
        rest = {k: e_rest for k in pairs}
        props += [f"fix demcal_E all property/global youngsModulus peratomtype {young}",
                  f"fix demcal_nu all property/global poissonsRatio peratomtype {poisson}",
                  f"fix demcal_e all property/global coefficientRestitution peratomtypepair {n} {_pair_table(rest, n)}"]
        y_pp, g_pp = cv.hertz_effective_moduli_pa(hertz.young_modulus_pa, hertz.poisson_ratio,
                                                  hertz.young_modulus_pa, hertz.poisson_ratio)
        conv += [
            f"Hertz-Mindlin: youngsModulus {_fmt(hertz.young_modulus_pa)} Pa, poissonsRatio {_fmt(hertz.poisson_ratio)} "
            f"(wall type: {_fmt(e_wall)} Pa, {_fmt(nu_wall)}); both codes combine them to Y* = {_fmt(y_pp)} Pa, "
            f"G* = {_fmt(g_pp)} Pa particle-particle. demcal's kp/kw are not used by a Hertz contact",
            f"coefficientRestitution {_fmt(e_rest)} = exp(-pi b/sqrt(1-b^2)), b = zeta_n sqrt(6/5): LIGGGHTS' "
            f"hertz dashpot -2 sqrt(5/6) beta sqrt(Sn m*) then equals demcal's 2 zeta sqrt(Sn m*) at zeta = "
            f"{_fmt(cv.hertz_damping_ratio_of_restitution(e_rest))} (demcal: {_fmt(zn)})",
        ]
        model = "model hertz tangential history"
        if zt == 0.0:
            settings = "tangential_damping off limitForce off"
        else:
            settings = "tangential_damping on limitForce off"
            if abs(zt - zn) > 1e-12:
                inexact.append(
                    f"Shear damping ratio {zt:g} differs from the normal one {zn:g}: LIGGGHTS' hertz damps the "
                    f"tangential direction with the normal beta, so its shear damping ratio is "
                    f"{cv.hertz_damping_ratio_of_restitution(e_rest):.3g}. Nearest: "
                    "this include (tangential dashpot at the normal ratio); expected difference: the dissipation of "
                    "sliding contacts, small in quasi-static tests.")
    mu = {(i, j): (c.friction_pw if wall in (i, j) else c.friction_pp) for i, j in pairs}
    props.append(f"fix demcal_mu all property/global coefficientFriction peratomtypepair {n} {_pair_table(mu, n)}")
    conv.append(f"coefficientFriction {_fmt(c.friction_pp)} particle-particle, {_fmt(c.friction_pw)} particle-wall "
                "(the Coulomb limit is mu times the normal force with its dashpot part in both codes; where the "
                "dashpot makes that force tensile, at the end of a contact, demcal's limit is 0 and LIGGGHTS' "
                "mu |Fn|)")

    # rolling resistance
    rolling = None
    for name, keyword in (("rolling_epsd2", "epsd2"), ("rolling_epsd", "epsd"), ("rolling_constant_torque", "cdt")):
        params = material.effect(name)
        if params is None:
            continue
        if rolling is not None:
            raise ValueError(f"effects: {rolling} and {keyword} both set; LIGGGHTS takes one rolling model")
        rolling = keyword
        mu_r = {k: params.rolling_friction for k in pairs}
        props.append(f"fix demcal_mur all property/global coefficientRollingFriction peratomtypepair {n} "
                     f"{_pair_table(mu_r, n)}")
        if keyword == "epsd2":
            conv.append(f"rolling_friction epsd2, coefficientRollingFriction {_fmt(params.rolling_friction)}: "
                        "k_r = k_t R*^2 and the cap mu_r R* |Fn| are the same formula in both codes "
                        "(LIGGGHTS src/rolling_model_epsd2.h; engine/effects/rolling_epsd2.py)")
        elif keyword == "epsd":
            eta = {k: params.rolling_damping_ratio for k in pairs}
            props.append(f"fix demcal_etar all property/global coefficientRollingViscousDamping peratomtypepair {n} "
                         f"{_pair_table(eta, n)}")
            conv.append(f"rolling_friction epsd, coefficientRollingFriction {_fmt(params.rolling_friction)}, "
                        f"coefficientRollingViscousDamping {_fmt(params.rolling_damping_ratio)}: k_r = 2.25 k_n mu_r^2 "
                        "R*^2, dashpot eta_r 2 sqrt(I_r k_r) with I_r from 1.4 m r^2 of both bodies, off at full "
                        "mobilisation, in both codes (LIGGGHTS src/rolling_model_epsd.h)")
        else:
            conv.append(f"rolling_friction cdt, coefficientRollingFriction {_fmt(params.rolling_friction)}: a torque "
                        "mu_r R* |Fn| against the relative rolling velocity in both codes")
    # cohesion
    cohesion = None
    sjkr = material.effect("cohesion_sjkr")
    adhesive = material.effect("cohesion_adhesive")
    if sjkr is not None:
        cohesion = "sjkr"
        ced = {k: sjkr.cohesion_energy_density_j_m3 for k in pairs}
        props.append(f"fix demcal_ced all property/global cohesionEnergyDensity peratomtypepair {n} {_pair_table(ced, n)}")
        conv.append(f"cohesion sjkr, cohesionEnergyDensity {_fmt(sjkr.cohesion_energy_density_j_m3)} J/m3: "
                    "k_c times the area of the sphere-sphere intersection circle in both codes (wall contacts: "
                    "not compared)")
    nearest_lines: list[str] = []
    if adhesive is not None:
        gamma = adhesive.surface_energy_j_m2
        inexact.append(
            f"cohesion_adhesive (surface energy {gamma:g} J/m2, pull-off force 3/2 pi Gamma R*): demcal's adhesive "
            "branch holds grains in tension up to the pull-off force after they stop overlapping. LIGGGHTS-PUBLIC "
            "3.8.0 has no tensile-branch (JKR) model. Nearest: 'cohesion sjkr' (an attraction k_c x contact area "
            "that acts only while grains overlap); expected difference: no tensile strength, so the bulk "
            "cohesion intercept c falls to about 0 (demcal's own comparison: sjkr +2.4 +- 10 kPa) and the "
            "angle of repose and pull-out force drop. It is left commented out below; not emitted.")
        if cohesion is None:
            nearest_lines = [
                "# NEAREST (not equivalent, see above): add 'cohesion sjkr' to the pair_style and wall model and",
                f"# fix demcal_ced all property/global cohesionEnergyDensity peratomtypepair {n} <k_c J/m3 per pair>",
            ]
    if c.local_damping > 0:
        inexact.append(
            f"local_damping {c.local_damping:g} (Cundall non-viscous damping of each body's force and torque): "
            "LIGGGHTS-PUBLIC has none. Nearest: no damping fix (fix viscous is viscous, not Cundall); expected "
            "difference: slower settling and less dissipation in dynamic phases; quasi-static stiffness unchanged. "
            "Not emitted.")

    model_line = model
    if cohesion:
        model_line += f" cohesion {cohesion}"
    if rolling:
        model_line += f" rolling_friction {rolling}"
    pair_line = f"{model_line} {settings}"
    conv.append(f"pair_style gran {pair_line}")
    conv.append("tangential history: an incremental spring capped at the Coulomb limit in both codes; demcal "
                "rotates the stored spring into the new tangent plane keeping its length, as LIGGGHTS does. The "
                "cap differs where a tangential dashpot acts: demcal caps spring + dashpot at mu Fn, LIGGGHTS the "
                "spring alone, adding the dashpot only while the contact sticks (measured: no effect on E', "
                "docs/export.md)")

    dt = demcal_timestep_s(material) if timestep_s is None else float(timestep_s)
    conv.append(f"time step {_fmt(dt)} s: demcal's rule, {DEMCAL_SAFETY_FACTOR} x the critical step of the normal and "
                "rotation-coupled tangential modes (engine/timestep.py); LIGGGHTS went unstable with a tangential "
                "dashpot at zeta 0.8 and dt = 0.2 sqrt(m/kn) (docs/engine.md), so keep at most this step")
    if p.clumps and timestep_s is None:
        dt *= MULTISPHERE_STEP_FACTOR
        conv.append(f"  clumps: {MULTISPHERE_STEP_FACTOR:g} x that step ({_fmt(dt)} s) for fix multisphere: at demcal's "
                    "own step the lid force on a clump packing jumped 4.6 % of its peak from one 20 um sample to the "
                    "next, at half of it 0.40 %, as with single spheres (docs/export.md)")

    # particle templates and the distribution the user's insertion fix takes
    seeds = _primes_above(15485863, n_part + 1)
    rho = p.solid_density_kg_m3
    templates: list[str] = []
    fractions: list[str] = []
    type_id = 0
    for k, s in enumerate(p.spheres):
        type_id += 1
        templates.append(f"fix demcal_pt{type_id} all particletemplate/sphere {seeds[k]} atom_type {type_id} "
                         f"density constant {_fmt(rho)} radius constant {_fmt(s.radius_m)}")
        fractions.append(f"demcal_pt{type_id} {_fmt(s.volume_fraction)}")
    for k, cl in enumerate(p.clumps):
        type_id += 1
        t = cl.template()
        spheres = " ".join(f"{_fmt(x)} {_fmt(y)} {_fmt(z)} {_fmt(r)}"
                           for (x, y, z), r in zip(t.sphere_offsets_m, t.sphere_radii_m))
        ixx, iyy, izz = (float(v) for v in t.principal_inertia_kg_m2(rho))
        templates.append(f"fix demcal_pt{type_id} all particletemplate/multisphere {seeds[len(p.spheres) + k]} "
                         f"atom_type {type_id} density constant {_fmt(rho)} nspheres {t.n_spheres} ntry 1000000 "
                         f"spheres {spheres} type {k + 1} mass {_fmt(t.mass_kg(rho))} use_density "
                         f"inertia_tensor {_fmt(ixx)} 0 0 {_fmt(iyy)} 0 {_fmt(izz)}")
        fractions.append(f"demcal_pt{type_id} {_fmt(cl.volume_fraction)}")
    if p.clumps:
        conv.append("clumps: one multisphere template per clump (spheres in demcal's principal frame, CoM at the "
                    "origin) with demcal's exact mass and principal inertia of the union (overlaps counted once) given "
                    "by 'mass ... use_density inertia_tensor', so LIGGGHTS' Monte Carlo estimate is not used; "
                    "fix multisphere integrates the bodies and sets their spheres itself, so 'fix integ all "
                    "nve/sphere' stays for the single spheres (checked in LIGGGHTS 3.8.0: a clump's sphere "
                    "distances stay exact and single spheres need it to move); m* is the body mass in both codes")
        for cl in p.clumps:
            t = cl.template()
            conv.append(f"  {cl.name}: {t.n_spheres} spheres, solid volume {_fmt(t.volume_m3)} m3 (overlaps "
                        f"counted once), mass {_fmt(t.mass_kg(rho))} kg")
    distribution = (f"fix demcal_pdd all particledistribution/discrete {seeds[-1]} {n_part} " + " ".join(fractions))
    conv.append("particledistribution/discrete takes mass fractions = demcal's solid-volume fractions (one density)")

    header = [
        f"# demcal material export for {LIGGGHTS_VERSION}: {material.name}",
        "# Generated by calibration/export/liggghts.py. Read it after 'create_box N' with",
        f"#   create_box {n} <region>     ({n_part} particle type(s) + 1 wall type)",
        "# and 'atom_style granular', 'units si', 'communicate single vel yes', 'newton off'.",
        "# Atom types:",
    ]
    header += [f"#   {i + 1}: {names[i]} ({kinds[i]}, body mass {_fmt(masses[i])} kg)" for i in range(n_part)]
    header += [f"#   {wall}: walls (fix wall/gran ${{demcal_wall_model}} primitive type "
               "${demcal_wall_type} <shape> ${demcal_wall_settings}, or ... mesh n_meshes 1 meshes <id> "
               "${demcal_wall_settings})",
               "# Conversions made:"]
    header += [f"#   - {line}" for line in conv]
    if material.notes:
        header.append("# Particles as given to the export:")
        header += [f"#   - {line}" for line in material.notes]
    if inexact:
        header.append("# NOT EXACTLY EXPRESSIBLE IN LIGGGHTS-PUBLIC (read before use):")
        header += [f"#   ! {line}" for line in inexact]
    else:
        header.append("# Every demcal effect of this material has an exact LIGGGHTS counterpart.")
    law = "hertz" if hertz is not None else "hooke/stiffness"
    header.append(f"# Expected differences from demcal at these parameters (measured, {law}):")
    header += [f"#   ~ {line}" for line in MEASURED_DIFFERENCES[law]]
    if p.clumps:
        header.append(f"#   ~ {CLUMP_DIFFERENCE}")
    body = [
        "",
        f"variable demcal_wall_type equal {wall}",
        f"variable demcal_dt equal {_fmt(dt)}",
        f'variable demcal_wall_model string "{model_line}"',
        f'variable demcal_wall_settings string "{settings}"',
        "",
        *props,
        "",
        f"pair_style gran {pair_line}",
        "pair_coeff * *",
        "",
        *templates,
        distribution,
    ]
    if p.clumps:
        body.append("fix demcal_ms all multisphere")
    body += nearest_lines
    text = "\n".join(header + body) + "\n"
    return LiggghtsExport(text=text, n_atom_types=n, wall_type=wall, particle_types=list(range(1, n_part + 1)),
                          distribution_id="demcal_pdd", timestep_s=dt, conversions=conv, inexact=inexact,
                          has_clumps=bool(p.clumps))
