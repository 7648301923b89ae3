"""All ORM modules, imported so ``Base.metadata`` knows every table (Alembic, tests)."""
from service.models.base import Base, utcnow
from service.models.job import FINISHED_STATUSES, JOB_STATUSES, Job
from service.models import rig, material, campaign, schedule  # noqa: F401  (S2's tables)

__all__ = ["Base", "Job", "JOB_STATUSES", "FINISHED_STATUSES", "utcnow", "rig", "material", "campaign", "schedule"]
