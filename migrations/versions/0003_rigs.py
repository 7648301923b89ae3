"""rigs: the apparatus a material's measurements were made in; materials name their rig and carry particles

Revision ID: 0003_rigs
Revises: 0002_campaigns
Create Date: 2026-11-26
"""
from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0003_rigs"
down_revision = "0002_campaigns"
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table(
        "rigs",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("bundled", sa.Boolean(), nullable=False),
        sa.Column("record", sa.JSON(), nullable=False),
        sa.Column("created_at", sa.DateTime(), nullable=False),
        sa.Column("updated_at", sa.DateTime(), nullable=False),
        sa.PrimaryKeyConstraint("id", name="pk_rigs"),
        sa.UniqueConstraint("name", name="uq_rigs_name"),
    )
    # existing materials keep no rig (NULL) until one is named; the bundled one gets the thesis rig at start-up
    with op.batch_alter_table("materials") as batch:
        batch.add_column(sa.Column("rig_id", sa.Integer(), nullable=True))
        batch.add_column(sa.Column("particles", sa.JSON(), nullable=True))
        batch.create_foreign_key("fk_materials_rig_id_rigs", "rigs", ["rig_id"], ["id"], ondelete="RESTRICT")
        batch.create_index("ix_materials_rig_id", ["rig_id"])


def downgrade() -> None:
    with op.batch_alter_table("materials") as batch:
        batch.drop_index("ix_materials_rig_id")
        batch.drop_constraint("fk_materials_rig_id_rigs", type_="foreignkey")
        batch.drop_column("particles")
        batch.drop_column("rig_id")
    op.drop_table("rigs")
