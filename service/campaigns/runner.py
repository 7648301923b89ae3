"""Drives running campaigns one step at a time from the database alone.

``CampaignRunner(session_factory, settings).tick()`` is called every second or so by
the service's background thread. Each call reads where every running campaign
is, does the next step(s) and commits after each one, so a restart (or a crash
between two steps) resumes where the database says: nothing lives in memory.
Job submission uses an idempotency key per run, so a step repeated after a
crash finds the job it already queued instead of queuing a twin.

Phases of an iteration: design -> batteries -> analysis -> confirmation (``confirmation_seeds`` batteries
at the optimum) -> polish (Gauss-Newton on the batteries, service.campaigns.polish, at the same seeds) ->
report -> done, and when the report finds misfit (lack of fit, or a target out of reach) or a conflict
(a parameter pinned at a bound, a prior pulled off; ``suspect``): report ->
diagnosis (a baseline at the optimum and each candidate effect, at as many seeds as the confirmation but
seeds of their own) -> diagnosed -> done, the ranking stored in the report and its verdict judged again on the
omnibus and the candidates' directed test together. In automatic mode
(service.campaigns.automatic) a done iteration either configures the next one, with the indicated
effect as a factor, or records why the loop stopped.
Paused campaigns are skipped; their queued batteries keep running in the queue
and are picked up on resume.
"""
from __future__ import annotations

import logging
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from engine.lab.spec import JobSpec, MicroParameters, TestOptions
from service.campaigns import analysis, automatic, polish
from service.campaigns.design import build_design, design_view
from service.campaigns.report import build_report
from calibration.keys import responses_of
from service.campaigns.schemas import CampaignCreate
from service.errors import ApiError, TooMany
from service.models.base import utcnow
from service.models.campaign import Campaign, CampaignIteration, CampaignRun
from service.models.job import Job

log = logging.getLogger(__name__)

MAX_STEPS_PER_TICK = 8
_SEED_MAX = 2**31 - 1


def _records(runs) -> list[list[dict]]:
    """Each stored run's response records (one list per battery)."""
    return [list((r.responses or {}).values()) for r in runs]


class CampaignFailed(Exception):
    """A step cannot succeed (a battery failed, no target can be modelled): the campaign fails."""


class CampaignRunner:
    def __init__(self, session_factory, settings=None):
        self.session_factory = session_factory
        self.settings = settings

    def tick(self) -> int:
        """Advance every running campaign; returns how many steps were taken."""
        with self.session_factory() as session:
            ids = list(session.scalars(select(Campaign.id).where(Campaign.status == "running").order_by(Campaign.id)))
        steps = 0
        for campaign_id in ids:
            try:
                steps += self.advance(campaign_id)
            except CampaignFailed as exc:
                self._fail(campaign_id, str(exc))
            except Exception as exc:  # a bug must not stop the other campaigns
                log.exception("campaign %s: step failed", campaign_id)
                self._fail(campaign_id, f"internal error: {type(exc).__name__}: {exc}")
        return steps

    def advance(self, campaign_id: int) -> int:
        steps = 0
        for _ in range(MAX_STEPS_PER_TICK):
            with self.session_factory() as session:  # fresh session: every step sees the database as it is
                campaign = session.get(Campaign, campaign_id)
                if campaign is None or campaign.status != "running":
                    break
                if not self._step(session, campaign):
                    break
            steps += 1
        return steps

    # -- one step --------------------------------------------------------------------------
    def _step(self, session: Session, campaign: Campaign) -> bool:
        """Do the next thing for this campaign; False when it must wait (for jobs)."""
        config = CampaignCreate.model_validate(campaign.config)
        it = next((i for i in campaign.iterations if i.number == campaign.current_iteration), None)
        if it is None:
            self._new_iteration(session, campaign, config)
            return True
        if it.phase == "design":
            return self._design(session, campaign, config, it)
        if it.phase == "batteries":
            return self._batteries(session, campaign, config, it, kind="design", next_phase="analysis")
        if it.phase == "analysis":
            return self._analysis(session, campaign, config, it)
        if it.phase == "confirmation":
            return self._batteries(session, campaign, config, it, kind="confirmation", next_phase="polish")
        if it.phase == "polish":
            return self._polish(session, campaign, config, it)
        if it.phase == "report":
            return self._report(session, campaign, config, it)
        if it.phase == "diagnosis":
            return self._batteries(session, campaign, config, it, kind="diagnosis", next_phase="diagnosed")
        if it.phase == "diagnosed":
            return self._diagnosed(session, campaign, config, it)
        if it.phase == "done":  # running again after POST .../iterations: the next iteration begins
            self._new_iteration(session, campaign, config)
            return True
        return False

    def _new_iteration(self, session: Session, campaign: Campaign, config: CampaignCreate) -> None:
        number = campaign.current_iteration + 1
        fixed = dict(config.fixed_parameters)
        session.add(CampaignIteration(
            campaign_id=campaign.id, number=number, phase="design",
            parameters={"factors": [f.model_dump() for f in config.factors],
                        "fixed": {k: v for k, v in fixed.items() if k != "effects"},
                        "effects": fixed.get("effects", {}), "options": dict(config.options),
                        "evaluator": config.evaluator, "fidelity": config.fidelity},
        ))
        campaign.current_iteration = number
        try:
            session.commit()
        except IntegrityError:  # another runner sharing the database created it first
            session.rollback()

    def _set_phase(self, session: Session, it: CampaignIteration, old: str, new: str, **values: Any) -> bool:
        """Conditional phase change: a second runner that raced us loses and rolls back."""
        won = session.execute(update(CampaignIteration).where(
            CampaignIteration.id == it.id, CampaignIteration.phase == old).values(phase=new, **values)
            .execution_options(synchronize_session=False)).rowcount
        if not won:
            session.rollback()
            return False
        session.commit()
        session.refresh(it)
        return True

    def _design(self, session, campaign, config, it) -> bool:
        seed = (config.seed + 7919 * (it.number - 1)) % _SEED_MAX
        try:
            design = build_design(config.factors, config.design, seed)
        except ApiError as exc:
            raise CampaignFailed(f"iteration {it.number}: the design cannot be built: {exc.message}") from exc
        view = design_view(design)
        for row in view["runs"]:
            session.add(CampaignRun(
                iteration_id=it.id, kind="design", std_order=row["std_order"], run_order=row["run_order"],
                is_centre=row["point_type"] == "center", coded=row["coded"], natural=row["natural"],
                seed=row["seed"], status="pending"))
        return self._set_phase(session, it, "design", "batteries", design=view)

    # -- batteries ---------------------------------------------------------------------------
    def _spec(self, config: CampaignCreate, run: CampaignRun, targets=()) -> JobSpec:
        """The run's job: fixed parameters with the run's factor values (dotted effect paths applied),
        and options that make the battery compute every target's condition (DST loads, E' stresses)."""
        from calibration import parameters as factor_paths
        from calibration.conditions import battery_options
        from calibration.keys import ResponseKey

        parameters = MicroParameters.model_validate(factor_paths.apply(config.fixed_parameters, run.natural))
        options = battery_options([ResponseKey.from_record(t) for t in targets], config.options)
        options = {k: v for k, v in options.items() if k in TestOptions.model_fields}
        return JobSpec(test=config.test, fidelity=config.fidelity, seed=run.seed, parameters=parameters,
                       options=TestOptions.model_validate(options))

    def _submit(self, session, campaign, config, run) -> bool:
        from service.queue import submit_job

        try:
            spec = self._spec(config, run, self._targets(session, campaign, config))
            job = submit_job(session, spec, evaluator=config.evaluator,
                             priority=config.priority, idempotency_key=f"campaign:{campaign.id}:run:{run.id}",
                             client_id=campaign.client_id, campaign_id=campaign.id)
        except TooMany:
            session.rollback()
            return False  # the client's queue is full: try again next tick
        except ApiError as exc:
            session.rollback()
            raise CampaignFailed(f"run {run.std_order} ({run.kind}) cannot be queued: {exc.message}") from exc
        run.job_id = job.id
        run.status = "queued"
        session.commit()
        return True

    def _batteries(self, session, campaign, config, it, *, kind: str, next_phase: str) -> bool:
        runs = [r for r in it.runs if r.kind == kind]
        progressed, done = self._run_all(session, campaign, config, runs, kind)
        if done:
            return self._set_phase(session, it, it.phase, next_phase)
        return progressed

    def _run_all(self, session, campaign, config, runs, kind: str) -> tuple[bool, bool]:
        """Queue what is not queued, record what finished: (progressed, all succeeded)."""
        # queued in the design's randomised run order, so drifts in the service do not alias with factors
        runs = sorted(runs, key=lambda r: (r.run_order, r.id))
        progressed = False
        for run in runs:
            if run.job_id is None:
                if not self._submit(session, campaign, config, run):
                    return progressed, False
                progressed = True
        pending = [r for r in runs if r.status not in ("succeeded",)]
        if pending:
            jobs = {j.id: j for j in session.scalars(
                select(Job).where(Job.id.in_([r.job_id for r in pending])).execution_options(populate_existing=True))}
            for run in pending:
                job = jobs.get(run.job_id)
                if job is None:
                    raise CampaignFailed(f"job {run.job_id} of run {run.std_order} ({kind}) vanished from the queue")
                if job.status == "succeeded":
                    run.responses = responses_of(job.result or {})
                    run.status = "succeeded"
                    progressed = True
                elif job.status in ("failed", "cancelled"):
                    run.status = job.status
                    run.error = job.error
                    session.commit()
                    raise CampaignFailed(f"{kind} run {run.std_order} (job {job.id}) {job.status}: {job.error}")
                elif run.status != job.status:
                    run.status = job.status
            session.commit()
        return progressed, all(r.status == "succeeded" for r in runs)

    # -- polishing on the batteries (service.campaigns.polish) ----------------------------------
    def _polish(self, session, campaign, config, it) -> bool:
        state = (it.optimum or {}).get("polish")
        if config.polish_steps == 0 or (state and state["stage"] == "done"):
            return self._set_phase(session, it, "polish", "report")
        targets = self._targets(session, campaign, config)
        design, models = analysis.fit(it.design["doe"], [r for r in it.runs if r.kind == "design"], targets)
        modelled = [m for m in models if m.fit is not None]
        if state is None:
            confirmations = polish.final_runs(it)
            if config.polish_when == "surrogate_misses":
                check = analysis.surrogate_check(config, modelled, it.optimum, _records(confirmations),
                                                 [r.seed for r in confirmations])
                if check.get("confirmed") is not False:  # confirmed, or nothing modelled to polish on
                    return self._set_phase(session, it, "polish", "report",
                                           optimum={**it.optimum, "polish": polish.skipped(check)})
            state, points = polish.start(config, design, modelled, dict(it.optimum["parameters"]),
                                         [r.id for r in confirmations], _records(confirmations),
                                         [r.seed for r in confirmations])
            self._add_polish_runs(session, it, state, points)
            return self._set_phase(session, it, "polish", "polish", optimum={**it.optimum, "polish": state})
        round_runs = sorted((r for r in it.runs if r.kind == "polish" and r.std_order // polish.ROUND == state["round"]),
                            key=lambda r: r.std_order)
        progressed, done = self._run_all(session, campaign, config, round_runs, "polish")
        if not done:
            return progressed
        state, points = polish.advance(config, design, modelled, state, round_runs, config.polish_steps)
        if points:
            self._add_polish_runs(session, it, state, points)
            return self._set_phase(session, it, "polish", "polish", optimum={**it.optimum, "polish": state})
        theta = state["theta"]
        optimum = {**it.optimum, "polish": state, "surrogate_parameters": it.optimum["parameters"],
                   "parameters": theta, "coded": {f.name: float(f.to_coded(theta[f.name])) for f in design.factors}}
        return self._set_phase(session, it, "polish", "report", optimum=optimum)

    @staticmethod
    def _add_polish_runs(session, it, state: dict, points) -> None:
        for k, (natural, coded) in enumerate(points):
            for j, seed in enumerate(polish.seeds_of(state)):
                order = polish.std_order(state, k, j)
                session.add(CampaignRun(iteration_id=it.id, kind="polish", std_order=order, run_order=order,
                                        is_centre=False, coded=coded, natural=natural, seed=seed,
                                        status="pending"))

    # -- analysis and report -----------------------------------------------------------------
    def _targets(self, session, campaign, config):
        from calibration.keys import select
        from service.materials.store import get_material

        material = get_material(session, campaign.material_id)
        wanted = [t.model_dump() for t in config.targets] if config.targets is not None else None
        return select(material.measurements if material else [], wanted)

    def _analysis(self, session, campaign, config, it) -> bool:
        runs = [r for r in it.runs if r.kind == "design"]
        targets = self._targets(session, campaign, config)
        try:
            result = analysis.analyse(config, it.design["doe"], runs, targets)
        except analysis.AnalysisError as exc:
            raise CampaignFailed(f"iteration {it.number}: {exc}") from exc
        opt = result["optimum"]
        taken = {r.seed for r in it.runs}
        seed = (config.seed + 1_000_003 * it.number) % _SEED_MAX
        for k in range(config.confirmation_seeds):
            while seed in taken:
                seed = (seed + 1) % _SEED_MAX
            taken.add(seed)
            session.add(CampaignRun(iteration_id=it.id, kind="confirmation", std_order=k, run_order=k,
                                    is_centre=False, coded=opt["coded"], natural=opt["parameters"],
                                    seed=seed, status="pending"))
        return self._set_phase(session, it, "analysis", "confirmation", models=result["models"], optimum=opt)

    def _report(self, session, campaign, config, it) -> bool:
        targets = self._targets(session, campaign, config)
        confirmations = polish.final_runs(it)
        seeds = [r.seed for r in confirmations]
        design_runs = [r for r in it.runs if r.kind == "design"]
        assessment = analysis.assess(config, it.design["doe"], design_runs, targets, it.optimum,
                                     _records(confirmations), seeds)
        polished = polish.summary((it.optimum or {}).get("polish"))
        assessment["polished"] = bool(polished and polished["steps"] > 0)
        report = build_report(config, it.models, it.optimum, confirmations, targets, assessment)
        report["polish"] = polished
        first = confirmations[0]
        stored = {"job_id": first.job_id, "seed": first.seed, "parameters": first.natural,
                  "responses": first.responses, "job_ids": [r.job_id for r in confirmations], "seeds": seeds}
        # a diagnosis needs misfit the parameters cannot absorb: more measured values than free parameters
        diagnosable = ((report.get("lack_of_fit") or {}).get("dof") or 0) > 0
        # in automatic mode an iteration the next one will not build on needs no diagnosis of its own
        rejected = config.automatic and not automatic.builds_on(config, campaign.iterations, it, report)
        # a diagnosis attributes misfit: it runs when the lack of fit fails or a target is out of reach, and
        # when a conflict (a parameter pinned at a bound, a prior pulled off) suggests a misfit the omnibus
        # test cannot see, which the diagnosis's directed test then judges (whatever the surfaces' check says);
        # with diagnose_always, after every report
        misfit = report["verdict"] in ("targets out of reach", "model misses the measurements") or report["suspect"]
        plan = analysis.diagnosis_plan(config, it.optimum, it.parameters, seeds) if (
            config.diagnose and diagnosable and (misfit or config.diagnose_always) and not rejected) else []
        if plan:
            for k, (name, natural, seed) in enumerate(plan):
                session.add(CampaignRun(iteration_id=it.id, kind="diagnosis", std_order=k + 1, run_order=k + 1,
                                        is_centre=False, coded={}, natural=natural, seed=seed, status="pending"))
            return self._set_phase(session, it, "report", "diagnosis", report=report, confirmation=stored)
        return self._finish(session, campaign, config, it, "report", report, confirmation=stored)

    def _diagnosed(self, session, campaign, config, it) -> bool:
        targets = self._targets(session, campaign, config)
        confirmations = polish.final_runs(it)
        seeds = [r.seed for r in confirmations]
        design_runs = [r for r in it.runs if r.kind == "design"]
        runs = sorted((r for r in it.runs if r.kind == "diagnosis"), key=lambda r: r.std_order)
        plan = analysis.diagnosis_plan(config, it.optimum, it.parameters, seeds)
        diagnosis = analysis.diagnose(config, it.design["doe"], design_runs, targets, it.optimum,
                                      _records(confirmations), seeds,
                                      [(name, seed, list((r.responses or {}).values()))
                                       for (name, _, seed), r in zip(plan, runs)])
        report = analysis.diagnosed_report(it.report or {}, diagnosis)
        return self._finish(session, campaign, config, it, "diagnosed", report)

    def _finish(self, session, campaign, config, it, phase: str, report: dict, **values: Any) -> bool:
        """The iteration is done. In automatic mode the next one is configured in the same
        transaction (phase "done" with the campaign still running makes ``_step`` start it);
        otherwise, or when automatic mode stops, the campaign completes."""
        if config.automatic:
            record = automatic.next_step(config, campaign.config, campaign.iterations, it, report, self.settings)
            following = record.pop("next_config", None)
            report = {**report, "automatic": record}
            if following is not None:
                campaign.config = following  # flushed and committed with the phase change, or rolled back
                return self._set_phase(session, it, phase, "done", report=report, finished_at=utcnow(), **values)
        if not self._set_phase(session, it, phase, "done", report=report, finished_at=utcnow(), **values):
            return False
        return self._complete(session, campaign)

    def _complete(self, session, campaign) -> bool:
        campaign.status = "completed"
        campaign.finished_at = utcnow()
        session.commit()
        return True

    def _fail(self, campaign_id: int, message: str) -> None:
        with self.session_factory() as session:
            session.execute(update(Campaign).where(Campaign.id == campaign_id, Campaign.status == "running")
                            .values(status="failed", error=message[:20000], finished_at=utcnow()))
            session.commit()
