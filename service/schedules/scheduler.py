"""Fires due schedules: each firing creates a campaign from the template and starts it.

Missed-run policy (stated, and tested): **coalesce**. If the service was down
while one or more due times passed, the first tick after restart fires *once*
(at most one catch-up run) and records how many due times it covered; the next
due time is computed from now, never from the past. Policy **skip** instead
drops due times older than ``SKIP_GRACE`` and just moves on.

Claiming a firing is a conditional UPDATE on ``next_run_at``, so two schedulers
sharing one database (or a tick repeated after a crash) fire a due time once.
"""
from __future__ import annotations

import logging
from datetime import datetime, timedelta, timezone

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from service.campaigns.schemas import CampaignCreate
from engine.lab.resolution import label
from service.campaigns.store import campaign_targets, with_material_world
from service.limits import check_campaign_limits
from service.errors import ApiError
from service.materials.store import get_material, latest_measurement_id
from service.models.base import utcnow
from service.models.campaign import Campaign
from service.models.schedule import Schedule, ScheduleFiring
from service.schedules.cron import parse_cron
from service.vocabulary import CampaignStatus

log = logging.getLogger(__name__)

MISSED_RUN_POLICIES = ("coalesce", "skip")
SKIP_GRACE = timedelta(minutes=5)
_MAX_COUNTED_MISSES = 10_000


def naive_utc(when: datetime | None) -> datetime:
    if when is None:
        return utcnow()
    if when.tzinfo is not None:
        when = when.astimezone(timezone.utc).replace(tzinfo=None)
    return when


class Scheduler:
    def __init__(self, session_factory, settings=None):
        self.session_factory = session_factory
        self.settings = settings

    def tick(self, now: datetime | None = None) -> list[int]:
        """Fire every due schedule once; returns the ids of campaigns started."""
        now = naive_utc(now)
        with self.session_factory() as session:
            due = list(session.scalars(select(Schedule.id).where(Schedule.enabled.is_(True),
                                                                 Schedule.next_run_at <= now)))
        started = []
        for schedule_id in due:
            try:
                campaign_id = self._fire(schedule_id, now)
            except Exception:  # one broken schedule must not stop the others
                log.exception("schedule %s: firing failed", schedule_id)
                continue
            if campaign_id is not None:
                started.append(campaign_id)
        return started

    def _fire(self, schedule_id: int, now: datetime) -> int | None:
        with self.session_factory() as session:
            schedule = session.get(Schedule, schedule_id)
            if schedule is None or not schedule.enabled or schedule.next_run_at > now:
                return None
            cron = parse_cron(schedule.cron)
            due, missed = schedule.next_run_at, 0
            while True:  # the latest due time <= now, and how many were passed over
                following = cron.next_after(due)
                if following > now or missed >= _MAX_COUNTED_MISSES:
                    break
                due, missed = following, missed + 1
            first_due = schedule.next_run_at
            new_next = cron.next_after(now)
            claimed = session.execute(update(Schedule).where(
                Schedule.id == schedule_id, Schedule.next_run_at == first_due).values(next_run_at=new_next)
                .execution_options(synchronize_session=False)).rowcount
            if not claimed:
                session.rollback()
                return None
            firing = ScheduleFiring(schedule_id=schedule_id, due_at=due, fired_at=now, missed_count=missed)
            session.add(firing)
            reason = self._skip_reason(session, schedule, due, now)
            campaign_id = None
            if reason is None:
                try:
                    campaign_id = self._start_campaign(session, schedule, due, now)
                except ApiError as exc:
                    reason = f"template cannot start a campaign: {exc.message}"
                except ValueError as exc:  # the stored template no longer validates
                    reason = f"template is invalid: {exc}"
            firing.campaign_id = campaign_id
            firing.skipped_reason = reason
            schedule.last_run_at = now
            if campaign_id is not None:
                schedule.last_campaign_id = campaign_id
            session.commit()
            return campaign_id

    def _skip_reason(self, session: Session, schedule: Schedule, due: datetime, now: datetime) -> str | None:
        if schedule.missed_run_policy == "skip" and now - due > SKIP_GRACE:
            return f"missed by {(now - due).total_seconds():.0f} s (policy skip)"
        material_id = (schedule.template or {}).get("material_id")
        if get_material(session, material_id) is None:
            return f"material {material_id} no longer exists"
        if schedule.only_if_new_measurements:
            latest = latest_measurement_id(session, material_id)
            if latest is None:
                return "the material has no measurements"
            if schedule.last_measurement_id is not None and latest <= schedule.last_measurement_id:
                return "no new measurements since the last run"
        return None

    def _start_campaign(self, session: Session, schedule: Schedule, due: datetime, now: datetime) -> int:
        body = dict(schedule.template)
        body["name"] = f"{body.get('name') or schedule.name} @ {due:%Y-%m-%d %H:%M}Z"[:200]
        # at a material resolution, the material's rig and particles as they are at this firing
        config = with_material_world(session, CampaignCreate.model_validate(body))
        # the limits in force now (they may have been lowered since the schedule was created): a firing
        # over them is skipped with the reason, not a campaign that fails on its first run
        check_campaign_limits(config, self.settings, target_keys=[t.key for t in campaign_targets(session, config)])
        campaign = create_campaign_nocommit(session, config, schedule)
        campaign.status = CampaignStatus.RUNNING
        campaign.started_at = now
        schedule.last_measurement_id = latest_measurement_id(session, config.material_id)
        session.flush()
        return campaign.id


def create_campaign_nocommit(session: Session, config: CampaignCreate, schedule: Schedule) -> Campaign:
    """Same row as the API creates, in the firing's transaction (firing and campaign commit together).

    The campaign is the schedule owner's, and queues under the owner's client identity: as its own client
    ("schedule:<id>", still used for schedules made before 0004_ownership) each schedule had a fresh
    per-client limit, and a client held at 3 queued 15 jobs through 4 schedules."""
    campaign = Campaign(name=config.name, material_id=config.material_id, status=CampaignStatus.DRAFT,
                        evaluator=config.evaluator, fidelity=label(config.resolution, config.fidelity),
                        config=config.model_dump(mode="json"),
                        current_iteration=0, schedule_id=schedule.id,
                        client_id=schedule.client_id or f"schedule:{schedule.id}", owner=schedule.owner)
    session.add(campaign)
    return campaign
