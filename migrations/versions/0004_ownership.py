"""ownership: who made each job, material, campaign and schedule; a schedule's client identity

Revision ID: 0004_ownership
Revises: 0003_rigs
Create Date: 2026-11-26

Existing rows get ``owner`` NULL: nobody's, which only an administrator may change once tokens are
configured (``service.ownership``); on a server without tokens nothing changes. Existing schedules get
``client_id`` NULL, and the campaigns they start keep counting as ``schedule:<id>`` until re-created.
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0004_ownership"
down_revision = "0003_rigs"
branch_labels = None
depends_on = None

OWNED = ("jobs", "materials", "campaigns", "schedules")
# rigs: altered in place, not through a batch copy: SQLite's batch mode recreates the table, and dropping
# the old one fails while materials.rig_id references it (SQLite 3.35+ adds and drops columns natively)
OWNED_IN_PLACE = ("rigs",)


def upgrade() -> None:
    for table in OWNED:
        with op.batch_alter_table(table) as batch:
            batch.add_column(sa.Column("owner", sa.String(100), nullable=True))
    with op.batch_alter_table("schedules") as batch:
        batch.add_column(sa.Column("client_id", sa.String(100), nullable=True))
    for table in OWNED_IN_PLACE:
        op.add_column(table, sa.Column("owner", sa.String(100), nullable=True))


def downgrade() -> None:
    for table in OWNED_IN_PLACE:
        op.drop_column(table, "owner")
    with op.batch_alter_table("schedules") as batch:
        batch.drop_column("client_id")
    for table in reversed(OWNED):
        with op.batch_alter_table(table) as batch:
            batch.drop_column("owner")
