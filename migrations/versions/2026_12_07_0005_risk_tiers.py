"""Risk tiers: the tier of each case and occupant, and the high-risk threshold of a case.

Cases stored before keep NULL in these columns (stored records are never altered);
their tier is derived when read, from the stored probability and decision with the
high-risk threshold at its default (``service.db.repository.tier_expression``).

Revision ID: 0005
Revises: 0004
Create Date: 2026-12-07
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0005"
down_revision: str | None = "0004"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("cases") as batch:
        batch.add_column(sa.Column("tier", sa.String(length=16), nullable=True))
        batch.add_column(sa.Column("high_threshold", sa.Float(), nullable=True))
    with op.batch_alter_table("case_occupants") as batch:
        batch.add_column(sa.Column("tier", sa.String(length=16), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("case_occupants") as batch:
        batch.drop_column("tier")
    with op.batch_alter_table("cases") as batch:
        batch.drop_column("high_threshold")
        batch.drop_column("tier")
