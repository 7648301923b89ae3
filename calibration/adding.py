"""The next iteration's settings when the model or the design changes: an effect added (its strength
becomes one more design factor) or the design the surface check proposed.

One place for the manual "add this effect" (``POST .../iterations``) and the automatic mode
(``calibration.automatic``): the range the strength is given, from the diagnosis's estimate or the
user's, and the larger design that carries it.
"""
from __future__ import annotations

from calibration import parameters as factor_paths
from calibration.calibrate import generators_for
from calibration.decisions import effect_range
from calibration.errors import SettingsError
from doe.constraints import parse_constraint
from engine.candidates import get as get_candidate
from engine.lab.spec import MicroParameters


def effect_hints(report: dict, name: str) -> dict:
    """What an iteration's report says about adding ``name``: the diagnosis's estimate of its
    strength and the optimum a switch-type effect is matched at (``with_effect_factor``'s keywords);
    one place for the manual add-effect and the automatic mode."""
    ranked = next((r for r in (report.get("diagnosis") or {}).get("ranking", []) if r.get("effect") == name), {})
    return {"strength": ranked.get("strength"), "at": report.get("optimum") or None}


def with_effect_factor(config: dict, name: str, strength_range=None, *, strength: float | None = None,
                       at: dict | None = None) -> dict:
    """The configuration with candidate ``name``'s strength as one more factor and a half fraction of
    highest resolution for the larger design.

    The range is the user's ``strength_range``, else ``calibration.decisions.effect_range``: from
    the effect's "off" value over its plausible range (or twice the diagnosis's ``strength``
    estimate if larger), or for a switch-type effect a log range about its strength matched at ``at`` (the
    optimum's factor values; default the centre of the box)."""
    c = get_candidate(name)
    if not c.applies_to(config.get("fidelity")):
        raise SettingsError(f"{name} cannot be built at the {config.get('fidelity')} fidelity "
                      f"(only {', '.join(c.fidelities or ())})", "add_effect")
    if any(f["name"] == c.factor for f in config["factors"]):
        raise SettingsError(f"{name} is already a factor ({c.factor})", "add_effect", conflict=True)
    if strength_range is not None:
        low, high = strength_range
        log = c.is_switch
    else:
        reference = None
        if c.is_switch:
            point = at or {f["name"]: 0.5 * (f["low"] + f["high"]) for f in config["factors"]}
            optimum = factor_paths.apply(config.get("fixed_parameters") or {}, point)
            reference = float(c.reference(MicroParameters.model_validate(optimum)))
        low, high, log = effect_range(c, strength, reference)
    config = without_superseded(config, c, at)
    factors = list(config["factors"]) + [{"name": c.factor, "low": low, "high": high, "unit": c.unit, "log": log}]
    design = dict(config.get("design") or {})
    if c.off_value is not None and low == c.off_value and config.get("reuse", True):
        # the strength's low level is the model without the effect: the previous design, with the same
        # generators and the new factor crossed with it, has that design as its low face, so the next
        # iteration runs only the high face (calibration.reuse). 2^(4-1) IV x 2 is a 2^(5-1) with I = ABCD:
        # the new factor and its interactions are clear; two-factor interactions of the others stay
        # aliased in pairs, as they were in the previous iteration
        design.update(_crossed(design))
    else:
        generators = generators_for(len(factors))
        design.update({"type": "fractional", "generators": generators} if generators else {"type": "full",
                                                                                           "generators": None})
    return {**config, "factors": factors, "design": design}


def without_superseded(config: dict, candidate, at: dict | None) -> dict:
    """``config`` with the factors ``candidate``'s law supersedes (``Candidate.supersedes``) fixed at ``at``
    (the optimum the effect is added at; else their range's centre), and their priors and constraints gone.

    Why: with Hertz-Mindlin on, no force reads the linear spring's kp. Left a factor, it was calibrated on
    scatter alone: on tier B's hertz_strong (session 36) its slope in the surfaces was noise, the polish's
    Gauss-Newton step put 0.78 of its coded range into kp and failed at every length (24 batteries, no step),
    its 95 % interval was the whole range, and the design was a 2^(5-1) instead of a 2^(4-1). Fixed at the
    optimum, the time step it still bounds is the one the effect's reference modulus was matched at."""
    gone = {f["name"] for f in config["factors"] if f["name"] in candidate.supersedes}
    if not gone:
        return config
    point = at or {}
    values = {f["name"]: float(point[f["name"]]) if f["name"] in point else 0.5 * (f["low"] + f["high"])
              for f in config["factors"] if f["name"] in gone}
    return {**config, "factors": [f for f in config["factors"] if f["name"] not in gone],
            "fixed_parameters": {**(config.get("fixed_parameters") or {}), **values},
            "priors": [p for p in config.get("priors") or [] if p["parameter"] not in gone],
            "constraints": [t for t in config.get("constraints") or []
                            if not gone & set(parse_constraint(t).parameters)]}


def _crossed(design: dict) -> dict:
    """The design settings whose design is the previous one crossed with one more two-level factor: the
    same generators (they name only the previous factors' letters), or a full factorial again."""
    if design.get("type") == "fractional":
        return {"type": "fractional", "generators": list(design["generators"])}
    return {"type": "full", "generators": None}


def with_proposed_design(config: dict, last) -> dict:
    """The settings running the design the ``last`` iteration's surface check proposed: its factors
    narrowed about the optimum (``narrowed_factorial``), or the same two-level design with face-centred
    axial runs (``augment_ccd``), whose fit has squared terms."""
    check = ((last.report or {}).get("surrogate_check") or {}) if last is not None else {}
    kind, proposal = check.get("next_design_kind"), check.get("next_design")
    if kind == "narrowed_factorial" and proposal:
        levels = {f["name"]: (f["low"], f["high"]) for f in proposal["factors"]}
        factors = [{**f, "low": levels[f["name"]][0], "high": levels[f["name"]][1]} if f["name"] in levels else f
                   for f in config["factors"]]
        return {**config, "factors": factors}
    if kind == "augment_ccd":
        return {**config, "design": {**(config.get("design") or {}), "axial": "face"}}
    number = last.number if last is not None else 0
    raise SettingsError(f"iteration {number} proposes no design (its surface check: "
                        f"{check.get('verdict', 'not made')})", "proposed_design", conflict=True)
