"""Occupant outcomes: append-only rows, one per revision, linked to a stored occupant.

Revision ID: 0006
Revises: 0005
Create Date: 2026-12-08
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

from service.db.tables import UTCDateTime

revision: str = "0006"
down_revision: str | None = "0005"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "occupant_outcomes",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("case_id", sa.String(length=36), nullable=False),
        sa.Column("position", sa.Integer(), nullable=False),
        sa.Column("seat", sa.String(length=32), nullable=False),
        sa.Column("revision", sa.Integer(), nullable=False),
        sa.Column("iss", sa.Integer(), nullable=True),
        sa.Column("mais", sa.Integer(), nullable=True),
        sa.Column("died", sa.Boolean(), nullable=True),
        sa.Column("disposition", sa.String(length=32), nullable=True),
        sa.Column("source", sa.String(length=32), nullable=False),
        sa.Column("recorded_at", UTCDateTime(), nullable=False),
        sa.Column("weight", sa.Float(), nullable=False),
        sa.Column("written_by", sa.String(length=200), nullable=False),
        sa.Column("written_at", UTCDateTime(), nullable=False),
        sa.Column("channel", sa.String(length=16), nullable=False),
        sa.Column("content_sha256", sa.String(length=64), nullable=False),
        sa.ForeignKeyConstraint(
            ["case_id"], ["cases.id"], name="occupant_outcomes_case_id_fkey", ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("id", name="occupant_outcomes_pkey"),
        sa.UniqueConstraint(
            "case_id",
            "position",
            "revision",
            name="occupant_outcomes_case_id_position_revision_key",
        ),
    )
    op.create_index("ix_occupant_outcomes_case_id", "occupant_outcomes", ["case_id"])


def downgrade() -> None:
    op.drop_index("ix_occupant_outcomes_case_id", table_name="occupant_outcomes")
    op.drop_table("occupant_outcomes")
