"""The interface every contact effect implements.

Stages (the order the pair kernel runs them in, with the numba function's signature):

* ``"stiffness"``: ``apply(p, delta, r_eff, kn, ks) -> (fn_elastic, kn_tangent, ks)`` replaces the
  linear normal force and the stiffnesses (used for damping and the time step) of the contact.
* ``"normal_extra"``: ``apply(p, delta, r_i, r_j, dist, fn_elastic) -> f_normal`` adds a normal
  force (positive pushes apart) to the contact law's elastic force ``fn_elastic``; ``r_j < 0`` marks a
  wall. The Coulomb limit stays mu times the contact law's own (repulsive) force.
* ``"rolling"``: ``apply(p, hist, h0, n0, n1, n2, w0, w1, w2, fn, r_eff, kn, ks, i_roll, dt) ->
  (t0, t1, t2)`` returns the torque on particle i (particle j gets the opposite); ``w`` is the relative
  angular velocity omega_i - omega_j, ``kn``/``ks`` the contact's normal and tangential stiffness,
  ``i_roll`` its rolling inertia (Ai et al. 2011), ``hist[h0:h0 + n_hist]`` this effect's history
  slots.

History slots must hold quantities of i relative to j that change sign when i and j swap roles: the
engine renumbers particles for locality and stores each pair once with i < j, negating the history
of pairs whose order flips.

``p`` (length ``1 + n_props``) is this effect's slice of the pair-property row; ``p[0]`` is written by the framework (1 where the
effect is on for the pair) and the kernel skips the call where it is 0.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from pydantic import BaseModel

STAGES = ("stiffness", "normal_extra", "rolling")

# Tests and quantities of a fingerprint row (the signs a missing effect leaves on the residuals,
# measured - model, before the baseline parameters compensate). Keys are calibration's vocabulary.
FINGERPRINT_COLUMNS = ("bulk_density", "modulus_level", "modulus_slope", "cohesion", "friction_angle",
                       "dilatancy", "angle_of_repose", "pull_force")


# The physical terms of the closed-form stand-in (calibration.standin) an effect or candidate can feed:
# a rolling resistance coefficient, an adhesive surface energy (J/m2), a Hertzian modulus (Pa) and
# Poisson's ratio replacing the linear spring, and a grain elongation (aspect ratio - 1).
STANDIN_TERMS = ("rolling_friction", "surface_energy_j_m2", "hertz_young_modulus_pa", "hertz_poisson_ratio",
                 "elongation")


# a strength-type candidate is probed again at its plausible top only when the top lies this many secant steps
# out: nearer, a response curving between step and top changes its direction too little to matter
TOP_PROBE_RATIO = 2.0


@dataclass(frozen=True)
class Candidate:
    """What the missing-physics diagnosis (``calibration/``) needs to know of a physical effect.

    Declared by the module that implements the effect, so the list of candidates cannot drift from
    the list of effects. ``factor`` is the dotted path of the strength parameter in
    ``MicroParameters`` (``effects.rolling_epsd2.rolling_friction``, ``clump_aspect_ratio``): the
    diagnosis switches the effect on there, and a campaign varies it there as a design factor.

    ``off_value`` is the strength at which the effect vanishes (0 friction, aspect ratio 1). An effect
    that replaces a baseline law instead of adding to it (Hertz-Mindlin replaces the linear spring)
    has no such value: ``off_value`` is None and ``reference`` gives the strength that matches the
    baseline at the calibrated parameters, so switching it on changes the shape of the response, not
    its level.
    """

    name: str
    title: str
    factor: str
    unit: str
    plausible_range: tuple[float, float]
    step: float
    off_value: float | None = 0.0
    # fingerprint: FINGERPRINT_COLUMNS entry -> "+", "++", "-", "0", "+-" (sign of measured - model)
    fingerprint: dict[str, str] = field(default_factory=dict)
    physics: str = ""
    # (MicroParameters) -> strength matched to the baseline law; switch-type effects only
    reference: Callable[..., float] | None = None
    # further parameters the effect needs when switched on (e.g. Poisson's ratio), fixed values
    companions: dict[str, float] = field(default_factory=dict)
    # fidelities whose lab can build the effect (None: all); the thesis fidelity has its own clump mix
    fidelities: tuple[str, ...] | None = None
    # the closed-form stand-in's term this strength feeds (calibration.standin.TERMS), for a candidate
    # that is a micro parameter rather than a contact effect (an effect declares its own: Effect.standin)
    standin_term: str | None = None
    # (test, quantity, how) of the measurements that would show the effect where the measured ones cannot
    # (calibration.unseen): named to the user when a "no misfit" could not have seen it; validated against
    # the lab's registry (tests/calibration/test_unseen.py)
    revealed_by: tuple[tuple[str, str, str], ...] = ()
    # baseline micro parameters the effect's law replaces (Hertz-Mindlin's modulus takes the linear spring's
    # place): with the effect on they change no force, only at most the time step, so a campaign that adds the
    # effect fixes them instead of calibrating a parameter the physics no longer reads (calibration.adding)
    supersedes: tuple[str, ...] = ()

    def applies_to(self, fidelity: str | None) -> bool:
        return fidelity is None or self.fidelities is None or fidelity in self.fidelities

    @property
    def effect_name(self) -> str | None:
        """The contact effect whose parameter the strength is (``effects.<name>.<param>``), else None."""
        return self.factor.split(".")[1] if self.factor.startswith("effects.") else None

    def active_in(self, factors: list[dict], fixed: dict) -> bool:
        """Is this effect in a model with design ``factors`` ({name, ...}) and ``fixed`` micro parameters
        (``effects`` included)? An effect is in when its strength is a factor, when it is one of the fixed
        contact effects, or when its fixed strength differs from the value at which it vanishes."""
        effect = self.effect_name
        if effect is not None:
            return effect in (fixed.get("effects") or {}) or any(
                f["name"].startswith(f"effects.{effect}.") for f in factors)
        if any(f["name"] == self.factor for f in factors):
            return True
        return self.factor in fixed and (self.off_value is None or fixed[self.factor] != self.off_value)

    def __post_init__(self):
        low, high = self.plausible_range
        if not low < high:
            raise ValueError(f"candidate {self.name}: plausible range must have low < high")
        if not self.step > 0:
            raise ValueError(f"candidate {self.name}: step must be positive")
        unknown = set(self.fingerprint) - set(FINGERPRINT_COLUMNS)
        if unknown:
            raise ValueError(f"candidate {self.name}: unknown fingerprint columns {sorted(unknown)}")
        if self.off_value is None and self.reference is None:
            raise ValueError(f"candidate {self.name}: a switch-type effect needs a reference strength")
        if self.supersedes and self.off_value is not None:
            raise ValueError(f"candidate {self.name}: only an effect that replaces a baseline law (switch-type) "
                             "supersedes baseline parameters")

    @property
    def is_switch(self) -> bool:
        return self.off_value is None

    @property
    def top_step(self) -> float | None:
        """The strength change from "off" to the plausible range's top, where a second diagnosis probe runs
        (``calibration.analysis.top_probe_plan``) when the secant step saw the effect but could not explain
        the misfit; None for a switch-type effect (it is probed at its matched strength only) and where the
        top is not at least TOP_PROBE_RATIO steps out (a probe there says little the step's did not)."""
        if self.is_switch:
            return None
        top = self.plausible_range[1] - (self.off_value or 0.0)
        return top if top >= TOP_PROBE_RATIO * self.step else None


@dataclass(frozen=True)
class Effect:
    name: str
    stage: str
    params_model: type[BaseModel]
    n_props: int
    n_hist: int
    # (params, contact_type, material_i, material_other) -> n_props floats (p[1:], p[0] is the switch)
    pair_props: Callable[..., list[float]]
    module: str
    function: str = "apply"
    doc: str = ""
    # critical time step this effect imposes: (params, density_kg_m3, r_min_m) -> dt_s (None: none)
    timestep_limit: Callable[..., float] | None = None
    # a contact law replacing the linear springs: (params, contact_type, r_min_m) -> (kn, kt), its normal tangent
    # and tangential stiffness at the largest overlap it is meant for; the critical step judges them with the
    # damping and the rotation as it judges the linear springs (engine.timestep). None: no such law
    contact_stiffness: Callable[..., tuple[float, float]] | None = None
    # the missing-physics diagnosis's view of this effect; None: not a diagnosis candidate
    candidate: Candidate | None = None
    # how the closed-form stand-in (calibration.standin) represents it: (params) -> {term: value} over
    # calibration.standin.TERMS; None: the stand-in has no closed form for it
    standin: Callable[..., dict[str, float]] | None = None
