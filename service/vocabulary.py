"""The service's status words, each spelt once: jobs, campaigns and a campaign's runs.

``str`` enums so the stored strings and the JSON stay the plain words they were. The loop's own
words (phases, run kinds, verdicts, stop reasons) are ``calibration.vocabulary``'s.
"""
from __future__ import annotations

from enum import Enum


class JobStatus(str, Enum):
    QUEUED = "queued"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"

    def __str__(self) -> str:
        return self.value


FINISHED_JOB = frozenset({JobStatus.SUCCEEDED, JobStatus.FAILED, JobStatus.CANCELLED})


class CampaignStatus(str, Enum):
    """draft -start-> running -pause-> paused -resume-> running -> completed | failed."""

    DRAFT = "draft"
    RUNNING = "running"
    PAUSED = "paused"
    COMPLETED = "completed"
    FAILED = "failed"

    def __str__(self) -> str:
        return self.value


class RunStatus(str, Enum):
    """A campaign run: pending until its job is queued, then its job's status."""

    PENDING = "pending"
    QUEUED = "queued"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"

    def __str__(self) -> str:
        return self.value
