"""Campaign service layer: creation, legal state changes, and JSON views for the API.

State machine (status): draft -start-> running -pause-> paused -resume-> running
-> completed | failed. Anything else is a 409. Inside 'running', the current
iteration's ``phase`` says what the runner does next (see ``runner``).
"""
from __future__ import annotations

from typing import Any

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from calibration.adding import effect_hints, with_effect_factor, with_proposed_design
from calibration.analysis import active_effects
from calibration.automatic import may_continue
from calibration.errors import SettingsError
from calibration.keys import ResponseKey
from calibration.keys import select as select_targets
from calibration.records import Measured
from calibration.vocabulary import AGAINST_ADDING, Phase
from engine.lab.plausibility import settings_warnings
from engine.lab.resolution import is_preset, label
from engine.lab.rigs import rig_json
from service.campaigns.schemas import CampaignCreate, IterationIn
from service.config import Settings, get_settings
from service.errors import Conflict, Invalid, NotFound, from_settings_error
from service.limits import check_campaign_limits
from service.materials.store import get_material
from service.models.base import utcnow
from service.models.campaign import Campaign, CampaignIteration
from service.pagination import paged
from service.vocabulary import CampaignStatus, RunStatus

TRANSITIONS = {"start": ({CampaignStatus.DRAFT}, CampaignStatus.RUNNING),
               "pause": ({CampaignStatus.RUNNING}, CampaignStatus.PAUSED),
               "resume": ({CampaignStatus.PAUSED}, CampaignStatus.RUNNING)}


def _settings(session: Session) -> Settings:
    return session.info.get("settings") or get_settings()


def campaign_targets(session: Session, config: CampaignCreate) -> list[Measured]:
    """The measurements a campaign calibrates against: its material's, those ``config.targets`` names
    (all when None), as the loop's records, less those its runs cannot be compared with (``split_targets``)."""
    return split_targets(session, config)[0]


def split_targets(session: Session, config: CampaignCreate) -> tuple[list[Measured], list[dict[str, Any]]]:
    """The campaign's targets, and those left out with the reason (``calibration.comparable.split``: a quantity
    the apparatus sets measured in another rig than the runs simulate, or one that scales with the particles'
    size at a resolution that changes them). Never compared silently: the campaign's summary and every report
    name them."""
    from calibration.comparable import split
    from engine.lab.errors import SpecFieldError

    material = get_material(session, config.material_id)
    wanted = [t.model_dump() for t in config.targets] if config.targets is not None else None
    chosen = [Measured.from_record(m) for m in select_targets(material.measurements if material else [], wanted)]
    measured_rig, measured_particles = material_world(material)
    if measured_rig is None and measured_particles is None:
        return chosen, []
    try:
        return split(chosen, measured_rig, measured_particles, config)
    except SpecFieldError as exc:  # e.g. a coarse factor that makes the particles larger than the lab takes
        raise Invalid(exc.message, exc.field) from None


def material_world(material) -> tuple[Any, Any]:
    """The rig the material's measurements were made in and its particles (either None when not given)."""
    from engine.particles.description import Particles
    from service.rigs.store import record_of

    if material is None:
        return None, None
    rig = record_of(material.rig) if material.rig is not None else None
    particles = Particles.model_validate(material.particles) if material.particles is not None else None
    return rig, particles


def simulated_setup(config: CampaignCreate):
    """The lab set-up the campaign's runs are built in (``calibration.comparable.simulated_setup``), a refusal
    as a 422 naming the field."""
    from calibration.comparable import simulated_setup as setup
    from engine.lab.errors import SpecFieldError

    try:
        return setup(config)
    except SpecFieldError as exc:
        raise Invalid(exc.message, exc.field) from None


def with_material_world(session: Session, body: CampaignCreate, field_prefix: str = "") -> CampaignCreate:
    """A campaign at a material resolution ("as_measured", "coarse") runs in its material's rig with its
    particles, copied into the configuration (the runs replay as queued if the material changes later); a 422
    naming ``resolution`` when the material has neither and the request did not send them."""
    if is_preset(body.resolution) or (body.rig is not None and body.particles is not None):
        return body
    material = get_material(session, body.material_id)
    rig, particles = material_world(material)
    missing = [name for name, value in (("rig", body.rig or rig), ("particles", body.particles or particles))
               if value is None]
    if missing:
        raise Invalid(f"resolution {body.resolution if isinstance(body.resolution, str) else body.resolution.mode!r} "
                      f"builds the material's particles in the rig its measurements were made in, and material "
                      f"{material.id} ({material.name!r}) has no {' and no '.join(missing)}: give the material "
                      f"{' and '.join(missing)} (PUT /api/v1/materials/{material.id}), send them with the campaign, "
                      "or choose a preset resolution ('thesis', 'screening')", f"{field_prefix}resolution")
    return CampaignCreate.model_validate({**body.model_dump(mode="json"),
                                          "rig": rig_json(body.rig or rig),
                                          "particles": (body.particles or particles).model_dump(mode="json", exclude_none=True)})


def check_limits_with_targets(session: Session, config: CampaignCreate, field_prefix: str = "",
                              settings: Settings | None = None) -> None:
    """``check_campaign_limits`` with the options the material's measurements derive, as queued later (in the
    material's rig, with its particles, at a material resolution)."""
    config = with_material_world(session, config, field_prefix)
    check_campaign_limits(config, settings or _settings(session), field_prefix,
                          [t.key for t in campaign_targets(session, config)])


def checked_next_settings(session: Session, raw: dict, settings: Settings | None = None) -> dict:
    """The next iteration's configuration as the automatic mode proposes it (or a continued loop decides it
    again), checked as a new campaign's is: the schema, then the cost limits of every run it would queue.
    One check for the runner and for ``continue_campaign``, so a continued loop cannot configure an
    iteration the runner would refuse."""
    validated = CampaignCreate.model_validate(raw)
    check_limits_with_targets(session, validated, settings=settings)
    return validated.model_dump(mode="json")


def check_targets_simulated(session: Session, body: CampaignCreate) -> None:
    """A 422 before anything runs when the campaign could not compare a single simulated value with a
    measurement: its material has none (``material_id``), or none of the targets is a measurement of the
    material that the campaign's ``test`` reports (``targets``). Accepted, such a campaign ran its whole
    design (on DEM, a quarter of an hour of both cores) to fail with "no target could be modelled"."""
    from engine.lab.registry import ALWAYS, NEVER, reported_by
    from engine.lab.registry import get as get_test
    from engine.lab.spec import TestOptions

    material = get_material(session, body.material_id)
    if not material.measurements:
        raise Invalid(f"material {material.id} ({material.name!r}) has no measurements, so a campaign has nothing "
                      f"to calibrate against: add them first (POST /api/v1/materials/{material.id}/measurements)",
                      "material_id")
    chosen, left_out = split_targets(session, body)
    if not chosen and left_out:
        raise Invalid("every target is left out, none can be compared with the runs: "
                      + "; ".join(f"{t['test']}/{t['quantity']}: {t['reason']}" for t in left_out), "resolution")
    if not chosen:
        raise Invalid(f"no target is a measurement of material {material.id}; it has "
                      f"{sorted({ResponseKey.from_record(m).label for m in material.measurements})}", "targets")
    tests = reported_by(body.test, TestOptions.model_validate(body.options))
    simulated = {(t.name, q.name) for t in tests for q in t.quantities}
    if not any((m.key.test, m.key.quantity) in simulated for m in chosen):
        wanted = sorted({m.key.test for m in chosen})
        # how each wanted test would run: its battery switch, else alone (the registry says which)
        ways = [f"options.{get_test(name).battery}=true" if get_test(name).battery not in (ALWAYS, NEVER)
                else f"test={name!r}" for name in wanted]
        raise Invalid(f"no target is simulated: test {body.test!r} reports {[t.name for t in tests]} and the "
                      f"targets are {sorted({m.key.label for m in chosen})}; run their tests ({', '.join(ways)}) "
                      "or choose targets among the reported quantities", "targets")


def create_campaign(session: Session, body: CampaignCreate, *, client_id: str = "anonymous",
                    schedule_id: int | None = None, commit: bool = True, owner: str | None = None) -> Campaign:
    """A draft campaign; ``commit=False`` leaves the commit to the caller (the API builds its response first:
    ``service.db.built_then_committed``)."""
    if get_material(session, body.material_id) is None:
        raise NotFound(f"material {body.material_id} not found", "material_id")
    body = with_material_world(session, body)
    check_targets_simulated(session, body)
    # the design doe/ builds and the limits of every run: a 422 now, not a failure on start
    check_limits_with_targets(session, body)
    campaign = Campaign(name=body.name, material_id=body.material_id, status=CampaignStatus.DRAFT, evaluator=body.evaluator,
                        fidelity=label(body.resolution, body.fidelity), config=body.model_dump(mode="json"),
                        current_iteration=0,
                        schedule_id=schedule_id, client_id=client_id, owner=owner)
    session.add(campaign)
    if commit:
        session.commit()
    return campaign


def get_campaign(session: Session, campaign_id: int) -> Campaign:
    campaign = session.get(Campaign, campaign_id, populate_existing=True)
    if campaign is None:
        raise NotFound(f"campaign {campaign_id} not found", ["path", "campaign_id"])
    return campaign


def list_campaigns(session: Session, status: str | None = None, *, limit: int = 100,
                   offset: int = 0) -> tuple[list[Campaign], int]:
    """A page of campaigns, newest (highest id) first, and the total."""
    return paged(session, Campaign, where=[Campaign.status == status] if status else [],
                 order=(Campaign.id.desc(),), limit=limit, offset=offset)


def transition(session: Session, campaign_id: int, action: str) -> Campaign:
    """Apply start/pause/resume with a conditional UPDATE, so racing clients get one winner."""
    allowed, target = TRANSITIONS[action]
    campaign = get_campaign(session, campaign_id)
    if campaign.status not in allowed:
        raise Conflict(f"cannot {action} campaign {campaign_id}: it is {campaign.status} "
                       f"(allowed from {', '.join(sorted(allowed))})", ["path", "campaign_id"])
    values: dict[str, Any] = {"status": target, "updated_at": utcnow()}
    if action == "start":
        values["started_at"] = utcnow()
    won = session.execute(update(Campaign).where(Campaign.id == campaign_id, Campaign.status == campaign.status)
                          .values(**values).execution_options(synchronize_session=False)).rowcount
    session.commit()
    if not won:
        raise Conflict(f"campaign {campaign_id} changed state meanwhile; try again", ["path", "campaign_id"])
    return get_campaign(session, campaign_id)


def next_iteration(session: Session, campaign_id: int, changes: IterationIn) -> Campaign:
    """Completed campaign -> running again with a new iteration using the changed configuration."""
    campaign = get_campaign(session, campaign_id)
    if campaign.status != CampaignStatus.COMPLETED:
        raise Conflict(f"campaign {campaign_id} is {campaign.status}; a next iteration starts only after "
                       "the current one completed", ["path", "campaign_id"])
    config = dict(campaign.config)
    changed = changes.model_dump(mode="json", exclude_none=True)
    add_effect, strength_range = changed.pop("add_effect", None), changed.pop("strength_range", None)
    override = changed.pop("override", False)
    if changed.pop("proposed_design", False):
        try:
            config = with_proposed_design(config, max(campaign.iterations, key=lambda it: it.number, default=None))
        except SettingsError as exc:
            raise from_settings_error(exc) from exc
    if "resolution" in changed:
        # the rig and particles follow the resolution: a preset brings its own, a material resolution copies the
        # material's again (with_material_world below), so a campaign never runs one resolution in another's rig
        config.pop("rig", None)
        config.pop("particles", None)
    for key, value in changed.items():
        config[key] = value
    if add_effect is not None:
        # the range the automatic mode would give, from the last iteration's report
        last = max(campaign.iterations, key=lambda it: it.number, default=None)
        _refuse_against_diagnosis(last, add_effect, override)
        try:
            config = with_effect_factor(config, add_effect, strength_range,
                                        **effect_hints((last.report or {}) if last is not None else {}, add_effect))
        except SettingsError as exc:
            raise from_settings_error(exc) from exc
    validated = CampaignCreate.model_validate(config)  # 422 naming the field if inconsistent
    validated = with_material_world(session, validated)
    check_targets_simulated(session, validated)  # new targets or test: still something to compare
    check_limits_with_targets(session, validated)
    config = validated.model_dump(mode="json")
    won = session.execute(update(Campaign).where(Campaign.id == campaign_id, Campaign.status == CampaignStatus.COMPLETED)
                          .values(config=config, status=CampaignStatus.RUNNING, finished_at=None, updated_at=utcnow(),
                                  fidelity=label(validated.resolution, validated.fidelity))
                          .execution_options(synchronize_session=False)).rowcount
    session.commit()
    if not won:
        raise Conflict(f"campaign {campaign_id} changed state meanwhile; try again", ["path", "campaign_id"])
    return get_campaign(session, campaign_id)


def continue_campaign(session: Session, campaign_id: int, more_iterations: int) -> Campaign:
    """Completed automatic campaign -> running again, its limit raised by ``more_iterations``: the last
    iteration's next step is decided again (``calibration.machine.extended``, the database-free loop's
    ``extend`` too) and stored with what it had stopped for; the runner then starts the iteration it configures.
    409 when the campaign is not completed or stopped for a reason more iterations do not change."""
    from calibration import machine

    campaign = get_campaign(session, campaign_id)
    if campaign.status != CampaignStatus.COMPLETED:
        raise Conflict(f"campaign {campaign_id} is {campaign.status}; only a completed campaign continues",
                       ["path", "campaign_id"])
    config = CampaignCreate.model_validate(campaign.config)
    targets, left_out = split_targets(session, config)

    def validate(raw: dict) -> dict:
        return checked_next_settings(session, raw)

    last = max(campaign.iterations, key=lambda it: it.number)
    try:
        step = machine.extended(machine.Context(config, dict(campaign.config), targets, campaign.iterations, validate,
                                                left_out), last, more_iterations)
    except SettingsError as exc:
        raise from_settings_error(exc) from exc
    # the record and the campaign's state change together, and only from "completed" (a racing request loses)
    won = session.execute(update(Campaign).where(Campaign.id == campaign_id, Campaign.status == CampaignStatus.COMPLETED)
                          .values(config=step.next_settings, status=CampaignStatus.RUNNING, finished_at=None,
                                  updated_at=utcnow()).execution_options(synchronize_session=False)).rowcount
    if not won:
        session.rollback()
        raise Conflict(f"campaign {campaign_id} changed state meanwhile; try again", ["path", "campaign_id"])
    session.execute(update(CampaignIteration).where(CampaignIteration.id == last.id)
                    .values(**step.values).execution_options(synchronize_session=False))
    session.commit()
    session.expire_all()
    return get_campaign(session, campaign_id)


def retry_campaign(session: Session, campaign_id: int) -> Campaign:
    """Failed campaign -> running again where it failed: its current iteration's failed or cancelled batteries
    are queued again (``queue.retry_job``: same job, fresh attempts) and the runner takes the phase up; every
    battery that succeeded stays. 409 unless the campaign failed.

    Why: one battery that fails (a worker's bug since fixed, a cancelled job) failed the whole campaign, and the
    only way on was a new campaign that runs every battery again (tier B's hertz_strong on DEM failed in its
    second iteration after 59 batteries, on an unload-reload hold the servo could not settle, session 32)."""
    from service.queue import retry_job

    campaign = get_campaign(session, campaign_id)
    if campaign.status != CampaignStatus.FAILED:
        raise Conflict(f"campaign {campaign_id} is {campaign.status}; only a failed campaign is retried",
                       ["path", "campaign_id"])
    current = next((it for it in campaign.iterations if it.number == campaign.current_iteration), None)
    record = ((current.report or {}).get("automatic") or {}) if current is not None else {}
    if current is not None and current.phase == Phase.DONE and (not record or record.get("stop_reason") is not None):
        # the loop had ended there (no next iteration configured): running it again would start one it never asked for
        raise Conflict(f"campaign {campaign_id}'s last iteration had completed the loop; nothing failed to retry",
                       ["path", "campaign_id"])
    won = session.execute(update(Campaign).where(Campaign.id == campaign_id, Campaign.status == CampaignStatus.FAILED)
                          .values(status=CampaignStatus.RUNNING, error=None, finished_at=None, updated_at=utcnow())
                          .execution_options(synchronize_session=False)).rowcount
    if not won:
        session.rollback()
        raise Conflict(f"campaign {campaign_id} changed state meanwhile; try again", ["path", "campaign_id"])
    for run in (current.runs if current is not None else []):
        if run.status not in (RunStatus.FAILED, RunStatus.CANCELLED):
            continue
        if run.job_id is not None:
            try:
                retry_job(session, run.job_id)
            except Conflict:  # the job finished meanwhile (a retry of its own): the runner reads it as it is
                pass
        run.status, run.error = RunStatus.QUEUED.value if run.job_id is not None else RunStatus.PENDING.value, None
    session.commit()
    session.expire_all()
    return get_campaign(session, campaign_id)


def _refuse_against_diagnosis(last, add_effect: str, override: bool) -> None:
    """409 for an effect added against the last diagnosis (no physical match, a suspect measurement)
    unless the request says ``override: true``: the page offers that only as a marked override."""
    diagnosis = ((last.report or {}).get("diagnosis") or {}) if last is not None else {}
    if diagnosis.get("verdict") in AGAINST_ADDING and not override:
        raise Conflict(f"iteration {last.number}'s diagnosis is {diagnosis['verdict']!r}: "
                       f"{diagnosis.get('message', '')}. Adding {add_effect} goes against it; send override: true "
                       "to add it anyway", ["body", "override"])


def iteration(session: Session, campaign: Campaign, number: int | None = None) -> CampaignIteration:
    number = number or campaign.current_iteration
    for it in campaign.iterations:
        if it.number == number:
            return it
    raise NotFound(f"campaign {campaign.id} has no iteration {number or 1} yet", ["path", "campaign_id"])


def campaign_summary(campaign: Campaign) -> dict[str, Any]:
    current = next((it for it in campaign.iterations if it.number == campaign.current_iteration), None)
    runs = current.runs if current else []
    done = sum(1 for r in runs if r.status == RunStatus.SUCCEEDED)
    return {
        "id": campaign.id, "name": campaign.name, "material_id": campaign.material_id, "status": campaign.status,
        "evaluator": campaign.evaluator, "fidelity": campaign.fidelity,
        "current_iteration": campaign.current_iteration, "phase": current.phase if current else None,
        "runs_total": len(runs), "runs_succeeded": done,
        "runs_failed": sum(1 for r in runs if r.status in (RunStatus.FAILED, RunStatus.CANCELLED)),
        "error": campaign.error, "schedule_id": campaign.schedule_id, "owner": campaign.owner,
        "created_at": _iso(campaign.created_at), "started_at": _iso(campaign.started_at),
        "finished_at": _iso(campaign.finished_at), "config": campaign.config,
        "stop_reason": (((current.report or {}).get("automatic") or {}).get("stop_reason") if current else None),
        "kept_iteration": (((current.report or {}).get("automatic") or {}).get("kept_iteration") if current else None),
        # stopped where more iterations could go on (POST .../continue): at the limit, or an alias left unfitted
        "continuable": bool(campaign.status == CampaignStatus.COMPLETED and current is not None and may_continue(
            (current.report or {}).get("automatic"), current.number)),
        "warnings": settings_warnings(campaign.config or {}) + resolution_warnings(campaign),
    }


def resolution_warnings(campaign: Campaign) -> list[str]:
    """What the campaign's rig and resolution say before and after it runs: the coarse factor chosen (or a
    particle target the direct-shear standards capped), a rig too small for the particles it runs (the
    standards' sizes), and the targets left out (``split_targets``)."""
    from sqlalchemy.orm import object_session

    from calibration.conditions import run_spec
    from engine.lab.resolution import setup_notes

    session = object_session(campaign)
    if session is None or not campaign.config:
        return []
    try:
        config = CampaignCreate.model_validate(campaign.config)
        setup = simulated_setup(config)
        notes = setup_notes(run_spec(config, {f.name: 0.5 * (f.low + f.high) for f in config.factors}, 0))
        rig = [f"rig {setup.rig_name!r}, {w}" for w in setup.rig_warnings()] if not is_preset(config.resolution) else []
        _, left_out = split_targets(session, config)
    except (ValueError, Invalid):  # a stored configuration this version no longer reads: the runner reports it
        return []
    return notes + rig + [f"{t['test']}/{t['quantity']} left out of the targets: {t['reason']}" for t in left_out]


def run_view(run) -> dict[str, Any]:
    return {"id": run.id, "kind": run.kind, "std_order": run.std_order, "run_order": run.run_order,
            "is_centre": run.is_centre, "coded": run.coded, "natural": run.natural, "seed": run.seed,
            "job_id": run.job_id, "status": run.status, "responses": run.responses, "error": run.error,
            "reused_from": run.reused_from}


def iteration_view(it: CampaignIteration, *, with_runs: bool = True) -> dict[str, Any]:
    out = {"number": it.number, "phase": it.phase, "parameters": it.parameters,
           "effects": sorted(active_effects(it.parameters)),
           "design": _design_summary(it.design), "created_at": _iso(it.created_at),
           "finished_at": _iso(it.finished_at), "report": it.report}
    if with_runs:
        out["runs"] = [run_view(r) for r in it.runs]
    return out


def _design_summary(design: dict | None) -> dict | None:
    if design is None:
        return None
    return {k: v for k, v in design.items() if k != "doe"}


def _iso(value) -> str | None:
    return value.isoformat() + "Z" if value is not None else None


def campaign_estimate(session: Session, campaign: Campaign) -> dict[str, Any] | None:
    """Each battery's cost in the campaign's rig and resolution (at the centre of its factor box, with the
    options its targets derive) and the batteries of its first design, shown when it is created and read."""
    from calibration.conditions import run_spec
    from engine.lab.cost import estimate_view
    from service.limits import design_runs
    from service.wall_estimate import wall_time_estimate

    try:
        config = CampaignCreate.model_validate(campaign.config)
        keys = [t.key for t in campaign_targets(session, config)]
        spec = run_spec(config, {f.name: 0.5 * (f.low + f.high) for f in config.factors}, 0, keys)
        view = estimate_view(spec)
    except (ValueError, Invalid):  # SpecFieldError is one: a stored configuration this version no longer reads
        return None
    design = config.design
    return {**view, **wall_time_estimate(session, spec.test, view, campaign.evaluator),
            "batteries": design_runs(len(config.factors), len(design.generators or ()),
                                                            design.replicates, design.centre_runs,
                                                            design.axial != "none")}
