"""Which measurements a loop's runs can be compared with, and why the others are left out.

A measurement carries the apparatus it was made in and the material's particles; a loop simulates a set-up
(a preset, or those particles, as measured or coarse-grained, in that rig). A value the apparatus sets (a
bulk mass) measured in another rig, or one that scales with the particles' size (a particle count) at a
resolution that changes them, has no simulated counterpart (``engine.lab.resolution.incomparable``). Such
targets are left out with the reason, never compared silently; the machine puts them in every report.
One function for both drivers: the service's campaigns (the material's rig and particles from the database)
and the notebook loop (``CalibrationLoop(..., measured_rig=, measured_particles=)``).
"""
from __future__ import annotations

from typing import Any, Sequence

from .records import Measured


def split(targets: Sequence[Measured], measured_rig, measured_particles,
          settings) -> tuple[list[Measured], list[dict[str, Any]]]:
    """(the targets the runs can be compared with, those left out as {test, quantity, condition, reason}).
    ``measured_rig``/``measured_particles``: the rig the measurements were made in and the material's particles
    (``engine.lab.rigs.Rig``, ``engine.particles.description.Particles``; None where unknown: compared, as before
    rigs were data). ``settings``: the loop's (``LoopSettings`` or a campaign's configuration)."""
    if measured_rig is None and measured_particles is None:
        return list(targets), []
    from engine.lab.registry import get as get_test
    from engine.lab.resolution import incomparable

    setup = simulated_setup(settings)
    kept, left_out = [], []
    for target in targets:
        why = incomparable(get_test(target.key.test).quantity(target.key.quantity), measured_rig,
                           measured_particles, setup)
        if why is None:
            kept.append(target)
        else:
            left_out.append({"test": target.key.test, "quantity": target.key.quantity,
                             "condition": target.key.condition_dict, "reason": why})
    return kept, left_out


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
