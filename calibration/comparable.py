"""Which measurements a loop's runs can be compared with, and why the others are left out.

A measurement carries the apparatus it was made in and the material's particles; a loop simulates a set-up
(a preset, or those particles, as measured or coarse-grained, in that rig). A value the apparatus sets (a
bulk mass) measured in another rig, or one that scales with the particles' size (a particle count) at a
resolution that changes them, has no simulated counterpart (``engine.lab.resolution.incomparable``). Such
targets are left out with the reason, never compared silently; the machine puts them in every report. So is a
quantity the laboratory computes from others that are targets (``once_each``: a porosity from the bulk density),
and a packing height that is the rig's level: one measurement enters the statistics once.
One function for both drivers: the service's campaigns (the material's rig and particles from the database)
and the notebook loop (``CalibrationLoop(..., measured_rig=, measured_particles=)``).
"""
from __future__ import annotations

from typing import Any, Sequence

from .records import Measured


def split(targets: Sequence[Measured], measured_rig, measured_particles,
          settings) -> tuple[list[Measured], list[dict[str, Any]]]:
    """(the targets the runs can be compared with, those left out as {test, quantity, condition, reason, kind}).
    ``measured_rig``/``measured_particles``: the rig the measurements were made in and the material's particles
    (``engine.lab.rigs.Rig``, ``engine.particles.description.Particles``; None where unknown: compared, as before
    rigs were data). ``settings``: the loop's (``LoopSettings`` or a campaign's configuration)."""
    from engine.lab.registry import get as get_test

    if measured_rig is None and measured_particles is None:
        return once_each(list(targets), get_test)
    from engine.lab.resolution import incomparable, rig_value

    setup = simulated_setup(settings)
    kept, left_out = [], []
    for target in targets:
        quantity = get_test(target.key.test).quantity(target.key.quantity)
        fixed = rig_value(quantity, setup)  # the rig's own number: the same measurement, not a missing one
        why = fixed or incomparable(quantity, measured_rig, measured_particles, setup)
        if why is None:
            kept.append(target)
        else:
            left_out.append(_left(target, why, "counted_once" if fixed else "incomparable"))
    kept, derived = once_each(kept, get_test, lambda test, name: rig_value(get_test(test).quantity(name), setup))
    return kept, left_out + derived


def once_each(targets: list[Measured], get_test, known=None) -> tuple[list[Measured], list[dict[str, Any]]]:
    """``targets`` with each measurement counted once: a quantity the laboratory computes from others of the same
    test and condition (``Quantity.derived_from``: a porosity from the bulk density, a bulk mass from the bulk
    density and the height) is left out where each of its sources is a target or the rig's own number
    (``known(test, quantity)`` truthy: the height of a packing struck off at a level). Counted as targets of their
    own, one weighing would enter the chi2, the lack of fit and the attribution as three to five independent
    measurements (the founding case's fill did, docs/diagnosis.md)."""
    present = {(t.key.test, t.key.quantity, t.key.condition) for t in targets}
    kept, left_out = [], []
    for target in targets:
        test, condition = target.key.test, target.key.condition
        quantity = get_test(test).quantity(target.key.quantity)
        sources = quantity.derived_from
        if sources and all((test, name, condition) in present or (known is not None and known(test, name))
                           for name in sources):
            left_out.append(_left(target, (
                f"{quantity.name} is computed from {' and '.join(sources)} ({quantity.relation}): the same "
                "measurement as those targets, counted once through them"), "counted_once"))
        else:
            kept.append(target)
    return kept, left_out


def _left(target: Measured, why: str, kind: str) -> dict[str, Any]:
    """One left-out target; ``kind`` "incomparable" (no counterpart in the runs' rig or resolution) or
    "counted_once" (the same measurement as targets kept: computed from them, or the rig's own number)."""
    return {"test": target.key.test, "quantity": target.key.quantity, "condition": target.key.condition_dict,
            "reason": why, "kind": kind}


def simulated_setup(settings):
    """The lab set-up the loop's runs are built in (at the centre of its factor box: the rig and particles are
    the same at every run but for a varied screening radius). A set-up the lab refuses raises its
    ``engine.lab.errors.SpecFieldError`` (the field named)."""
    from engine.lab.resolution import setup_for

    from .conditions import run_spec

    return setup_for(run_spec(settings, {f.name: 0.5 * (f.low + f.high) for f in settings.factors}, 0))


def in_world(settings, measured_rig, measured_particles):
    """``settings`` (``LoopSettings``) at a material resolution ("as_measured", "coarse") run in the rig the
    measurements were made in with the material's particles, where the settings do not name their own (as a
    campaign copies its material's, ``service.campaigns.store.with_material_world``); otherwise as they are."""
    from engine.lab.resolution import is_preset

    if is_preset(settings.resolution) or (settings.rig is not None and settings.particles is not None):
        return settings
    fill = {}
    if settings.rig is None and measured_rig is not None:
        fill["rig"] = measured_rig.model_dump(mode="json")
    if settings.particles is None and measured_particles is not None:
        fill["particles"] = measured_particles.model_dump(mode="json", exclude_none=True)
    return type(settings).model_validate({**settings.model_dump(mode="json"), **fill}) if fill else settings
