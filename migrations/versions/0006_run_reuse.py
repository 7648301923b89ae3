"""run reuse: a campaign run may be a battery an earlier iteration ran (calibration.reuse)

Revision ID: 0006_run_reuse
Revises: 0005_bigint_seeds
Create Date: 2026-11-26

An iteration that adds an effect reuses the batteries of the iteration it builds on (its design's low face,
and the confirmation, polishing and diagnosis batteries as further points of the fit) instead of running
them again. Such a run keeps the original job id and says which battery it is in ``reused_from``
("iteration 1 design run 5"); runs stored before this revision were all run for their own iteration (null).
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0006_run_reuse"
down_revision = "0005_bigint_seeds"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("campaign_runs") as batch:
        batch.add_column(sa.Column("reused_from", sa.String(length=100), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("campaign_runs") as batch:
        batch.drop_column("reused_from")
