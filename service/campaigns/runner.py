"""Drives running campaigns one step at a time from the database alone: persistence and queueing.

``CampaignRunner(session_factory, settings).tick()`` is called every second or so by the service's
background thread. Every step of the loop is ``calibration.machine``'s: for each running campaign the
runner asks the machine which runs the iteration's phase waits for, queues those not queued (one job
per run, under an idempotency key, so a step repeated after a crash finds the job it already queued
instead of queuing a twin), records the results of finished jobs, and once all have succeeded applies
the machine's transition in one transaction: the new runs, the iteration's new values and a
compare-and-swap of the phase, so a second runner sharing the database (or a restart) loses the race
and rolls back. Nothing lives in memory. Paused campaigns are skipped; their queued batteries keep
running in the queue and are picked up on resume.
"""
from __future__ import annotations

import logging
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from calibration import machine
from calibration.conditions import run_spec
from calibration.errors import LoopFailed
from calibration.keys import responses_of
from calibration.records import Measured
from calibration.vocabulary import Phase
from service.campaigns.schemas import CampaignCreate
from service.errors import ApiError, TooMany
from service.vocabulary import CampaignStatus, JobStatus, RunStatus
from service.models.base import utcnow
from service.models.campaign import Campaign, CampaignIteration, CampaignRun
from service.models.job import Job

log = logging.getLogger(__name__)

MAX_STEPS_PER_TICK = 8


class CampaignRunner:
    def __init__(self, session_factory, settings=None):
        self.session_factory = session_factory
        self.settings = settings

    def tick(self) -> int:
        """Advance every running campaign; returns how many steps were taken."""
        with self.session_factory() as session:
            ids = list(session.scalars(select(Campaign.id).where(Campaign.status == CampaignStatus.RUNNING.value)
                                       .order_by(Campaign.id)))
        steps = 0
        for campaign_id in ids:
            try:
                steps += self.advance(campaign_id)
            except LoopFailed as exc:
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
                if campaign is None or campaign.status != CampaignStatus.RUNNING:
                    break
                if not self._step(session, campaign):
                    break
            steps += 1
        return steps

    # -- one step --------------------------------------------------------------------------
    def _step(self, session: Session, campaign: Campaign) -> bool:
        """Do the next thing for this campaign; False when it must wait (for jobs, or a lost race)."""
        config = CampaignCreate.model_validate(campaign.config)
        it = next((i for i in campaign.iterations if i.number == campaign.current_iteration), None)
        if it is None or it.phase == Phase.DONE:  # the first, or the next after POST .../iterations or automatic mode
            self._new_iteration(session, campaign, config)
            return True
        awaited = machine.awaited(it)
        if awaited:
            progressed, done = self._run_all(session, campaign, config, awaited)
            if not done:
                return progressed
        from service.campaigns.store import split_targets

        targets, left_out = split_targets(session, config)
        context = machine.Context(config, campaign.config, targets, campaign.iterations, self._validate, left_out)
        transition = machine.step(context, it)
        return transition is not None and self._apply(session, campaign, it, transition)

    def _validate(self, raw: dict) -> dict:
        """The next iteration's configuration as the automatic mode proposes it, checked as a campaign's
        (with the cost limits of every run)."""
        from service.campaigns.store import checked_next_settings

        with self.session_factory() as session:
            return checked_next_settings(session, raw, self.settings)

    def _new_iteration(self, session: Session, campaign: Campaign, config: CampaignCreate) -> None:
        number = campaign.current_iteration + 1
        session.add(CampaignIteration(campaign_id=campaign.id, number=number, phase=Phase.DESIGN.value,
                                      parameters=machine.iteration_parameters(config, config.evaluator)))
        campaign.current_iteration = number
        try:
            session.commit()
        except IntegrityError:  # another runner sharing the database created it first
            session.rollback()

    def _apply(self, session: Session, campaign: Campaign, it: CampaignIteration, t: machine.Transition) -> bool:
        """The machine's transition in one transaction: new runs, values, the phase changed only if it is
        still ``t.source`` (else a racing runner won and this one rolls back), then the campaign's next
        configuration (automatic mode) or its completion."""
        for new in t.runs:
            reused = new.responses is not None  # an earlier iteration's battery (calibration.reuse): not queued
            session.add(CampaignRun(iteration_id=it.id, kind=new.kind.value, std_order=new.std_order,
                                    run_order=new.run_order, is_centre=new.is_centre, coded=new.coded,
                                    natural=new.natural, seed=new.seed, responses=new.responses, job_id=new.job_id,
                                    reused_from=new.reused_from,
                                    status=(RunStatus.SUCCEEDED if reused else RunStatus.PENDING).value))
        values = dict(t.values)
        if t.finished:
            values["finished_at"] = utcnow()
        if t.next_settings is not None:
            campaign.config = t.next_settings  # flushed and committed with the phase change, or rolled back
        if not self._set_phase(session, it, t.source, t.to, **values):
            return False
        return self._complete(session, campaign) if t.complete else True

    def _set_phase(self, session: Session, it: CampaignIteration, old: Phase, new: Phase, **values: Any) -> bool:
        """Conditional phase change: a second runner that raced us loses and rolls back."""
        won = session.execute(update(CampaignIteration).where(
            CampaignIteration.id == it.id, CampaignIteration.phase == old.value).values(phase=new.value, **values)
            .execution_options(synchronize_session=False)).rowcount
        if not won:
            session.rollback()
            return False
        session.commit()
        session.refresh(it)
        return True

    # -- batteries ---------------------------------------------------------------------------
    def _submit(self, session, campaign, config, run, target_keys) -> bool:
        from service.queue import submit_job

        try:
            spec = run_spec(config, run.natural, run.seed, target_keys)
            job = submit_job(session, spec, evaluator=config.evaluator,
                             priority=config.priority, idempotency_key=f"campaign:{campaign.id}:run:{run.id}",
                             client_id=campaign.client_id, campaign_id=campaign.id, owner=campaign.owner)
        except TooMany:
            session.rollback()
            return False  # the client's queue is full: try again next tick
        except ApiError as exc:
            session.rollback()
            raise LoopFailed(f"run {run.std_order} ({run.kind}) cannot be queued: {exc.message}") from exc
        run.job_id = job.id
        run.status = RunStatus.QUEUED.value
        session.commit()
        return True

    def _run_all(self, session, campaign, config, runs) -> tuple[bool, bool]:
        """Queue what is not queued, record what finished: (progressed, all succeeded)."""
        # queued in the design's randomised run order, so drifts in the service do not alias with factors
        runs = sorted(runs, key=lambda r: (r.run_order, r.id))
        progressed = False
        unqueued = [run for run in runs if run.job_id is None]
        keys = [t.key for t in self._targets(session, campaign, config)] if unqueued else []
        for run in unqueued:
            if not self._submit(session, campaign, config, run, keys):
                return progressed, False
            progressed = True
        pending = [r for r in runs if r.status != RunStatus.SUCCEEDED]
        if pending:
            jobs = {j.id: j for j in session.scalars(
                select(Job).where(Job.id.in_([r.job_id for r in pending])).execution_options(populate_existing=True))}
            for run in pending:
                job = jobs.get(run.job_id)
                if job is None:
                    raise LoopFailed(f"job {run.job_id} of run {run.std_order} ({run.kind}) vanished from the queue")
                if job.status == JobStatus.SUCCEEDED:
                    run.responses = responses_of(job.result or {})
                    run.status = RunStatus.SUCCEEDED.value
                    progressed = True
                elif job.status in (JobStatus.FAILED, JobStatus.CANCELLED):
                    run.status = job.status
                    run.error = job.error
                    session.commit()
                    raise LoopFailed(f"{run.kind} run {run.std_order} (job {job.id}) {job.status}: {job.error}")
                elif run.status != job.status:
                    run.status = job.status
            session.commit()
        return progressed, all(r.status == RunStatus.SUCCEEDED for r in runs)

    def _targets(self, session, campaign, config) -> list[Measured]:
        from service.campaigns.store import campaign_targets

        return campaign_targets(session, config)

    def _complete(self, session, campaign) -> bool:
        campaign.status = CampaignStatus.COMPLETED.value
        campaign.finished_at = utcnow()
        session.commit()
        return True

    def _fail(self, campaign_id: int, message: str) -> None:
        with self.session_factory() as session:
            session.execute(update(Campaign).where(Campaign.id == campaign_id, Campaign.status == CampaignStatus.RUNNING.value)
                            .values(status=CampaignStatus.FAILED.value, error=message[:20000], finished_at=utcnow()))
            session.commit()
