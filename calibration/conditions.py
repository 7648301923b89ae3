"""Which conditions a battery computes, decided by the measurements it is compared with.

Why: a target is matched to a simulated value by an equal condition, so the DST must shear at
exactly the user's normal stresses and the CCT report E' at exactly the user's stress levels;
otherwise measured values are silently left out (or, worse, compared with another stress).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any, Iterable, Mapping

from .keys import ResponseKey

if TYPE_CHECKING:
    from engine.lab.spec import JobSpec

    from .settings import LoopSettings

STRESS = "normal_stress_pa"


def battery_options(keys: Iterable[ResponseKey], base: dict[str, Any] | None = None) -> dict[str, Any]:
    """TestOptions fields (a dict) that make the battery report every key's condition.

    Options the user set explicitly in ``base`` win; the derived ones fill what is unset. The angle of
    repose and the anchor pull-out are separate, costly set-ups: they run when ``base`` asks for them
    (``include_aor``, ``include_anchor``), never because a material happens to list such a measurement.
    """
    from engine.lab import registry

    out = dict(base or {})
    stresses: dict[str, set[float]] = {}
    for k in keys:
        if k.stress_pa() is None:
            continue
        option = registry.quantity(k.test, k.quantity).stress_option
        if option is not None:  # each quantity's stresses go to the option that makes the battery report it there
            stresses.setdefault(option, set()).add(k.stress_pa())
    for option, values in stresses.items():
        if out.get(option) is None:
            out[option] = sorted(values)
    return out


def job_spec(test: str, fidelity: str, seed: int, parameters: Mapping[str, Any], options: Mapping[str, Any],
             lab: Mapping[str, Any] | None = None) -> "JobSpec":
    """The job one battery is: the one place a run's ``JobSpec`` is built (a queued job, a notebook's
    batch, the cost check), so all three run and cost the same thing. ``lab``: where it runs beyond the
    fidelity (``LoopSettings.lab``: a resolution with its rig and particles)."""
    from engine.lab.spec import JobSpec, MicroParameters, TestOptions

    where = {k: v for k, v in (lab or {}).items() if k != "fidelity"}
    return JobSpec(test=test, fidelity=fidelity, seed=int(seed), parameters=MicroParameters.model_validate(dict(parameters)),
                   options=TestOptions.model_validate(dict(options)), **where)


def run_spec(settings: "LoopSettings", natural: Mapping[str, float], seed: int, keys: Iterable[ResponseKey] = ()) -> "JobSpec":
    """The job of one run of the loop: the settings' fixed parameters with the run's factor values
    (dotted effect paths applied), and options that make the battery compute every target's condition
    (``keys``: the targets')."""
    from . import parameters as factor_paths

    return job_spec(settings.test, settings.fidelity, seed, factor_paths.apply(settings.fixed_parameters, dict(natural)),
                    battery_options(keys, settings.options), settings.lab())


def standin_conditions(options: dict[str, Any], cct_max_stress_pa: float = 65.6e3):
    """The stand-in's Conditions for TestOptions fields (defaults: the thesis's loads)."""
    from .standin import Conditions

    defaults = Conditions()
    return Conditions(
        dst_normal_stresses_pa=tuple(options.get("dst_normal_stresses_pa") or defaults.dst_normal_stresses_pa),
        cct_window_stresses_pa=tuple(options.get("cct_window_stresses_pa") or ()),
        cct_unload_reload_stresses_pa=tuple(options.get("cct_unload_reload_stresses_pa") or ()),
        cct_max_stress_pa=float(options.get("cct_max_stress_pa") or cct_max_stress_pa),
        include_aor=bool(options.get("include_aor", False)),
        include_anchor=bool(options.get("include_anchor", False)),
    )
