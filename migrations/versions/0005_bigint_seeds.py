"""bigint seeds: a job's and a campaign run's seed hold every 32-bit seed on PostgreSQL

Revision ID: 0005_bigint_seeds
Revises: 0004_ownership
Create Date: 2026-11-26

Seeds run to 2^32 - 1 (engine.lab.bounds.MAX_SEED), past PostgreSQL's INTEGER (2^31 - 1): there a seed of
3,000,000,000 answered 500 ("integer out of range") where SQLite, whose integers are 64-bit, stored it.
SQLite keeps the same values (its INTEGER and BIGINT are one storage class); the table is rebuilt only so
that the declared type matches the models. Downgrading on PostgreSQL fails while a seed past 2^31 - 1 is stored.
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0005_bigint_seeds"
down_revision = "0004_ownership"
branch_labels = None
depends_on = None

SEEDED = ("jobs", "campaign_runs")


def upgrade() -> None:
    for table in SEEDED:
        with op.batch_alter_table(table) as batch:
            batch.alter_column("seed", existing_type=sa.Integer(), type_=sa.BigInteger(), existing_nullable=False)


def downgrade() -> None:
    for table in reversed(SEEDED):
        with op.batch_alter_table(table) as batch:
            batch.alter_column("seed", existing_type=sa.BigInteger(), type_=sa.Integer(), existing_nullable=False)
