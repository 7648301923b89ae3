"""The service's status words as enums: one spelling per state, checked by the interpreter.

Why: the states of a job and of a campaign were string literals written in the queue, the workers,
the routers, the CLI and the models; a typo was a state nobody handles. Each enum mixes in ``str``,
so a member *is* its stored string: it compares equal to what the database holds, binds as that
string, and serialises to it in JSON, and the tables, the API and the page stay as they were.

``str()`` and f-strings give the value too (``calibration.vocabulary.Word``, the base of the loop's
words as well), so a member can go into a message or a log line as it is.
"""
from __future__ import annotations

from calibration.vocabulary import Word


class JobStatus(Word):
    """A queued job's state (``service.queue`` moves it; only the owner of the lease ends it)."""

    QUEUED = "queued"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @classmethod
    def unfinished(cls) -> tuple[JobStatus, ...]:
        """States a worker may still change (they count against a client's queue limit)."""
        return (cls.QUEUED, cls.RUNNING)

    @classmethod
    def finished(cls) -> tuple[JobStatus, ...]:
        return (cls.SUCCEEDED, cls.FAILED, cls.CANCELLED)

    @classmethod
    def unsuccessful(cls) -> tuple[JobStatus, ...]:
        """The ends without a result: what a worker gives up with, and what ``retry`` queues again."""
        return (cls.FAILED, cls.CANCELLED)


class JobOrigin(Word):
    """Which jobs a list shows by where they came from: submitted directly (no campaign), queued by a
    campaign (its batteries), or both. The page lists direct jobs by default: two campaigns queue
    well over a hundred batteries, which buried the jobs a user submitted."""

    DIRECT = "direct"
    CAMPAIGN = "campaign"
    ALL = "all"


class CampaignStatus(Word):
    """A campaign's state: draft until started, running or paused, then completed or failed."""

    DRAFT = "draft"
    RUNNING = "running"
    PAUSED = "paused"
    COMPLETED = "completed"
    FAILED = "failed"


class RunStatus(Word):
    """A campaign run's state: pending until its job is queued, then its job's status."""

    PENDING = "pending"
    QUEUED = "queued"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"
