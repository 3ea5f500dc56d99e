"""How a case came in: its source format, the VEDS document as received, its mapping.

Revision ID: 0003
Revises: 0002
Create Date: 2026-12-05
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0003"
down_revision: str | None = "0002"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("cases") as batch:
        batch.add_column(
            sa.Column(
                "source_format",
                sa.String(length=16),
                server_default=sa.text("'json'"),
                nullable=False,
            )
        )
        batch.add_column(sa.Column("source_document", sa.Text(), nullable=True))
        batch.add_column(sa.Column("source_mapping", sa.JSON(none_as_null=True), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("cases") as batch:
        batch.drop_column("source_mapping")
        batch.drop_column("source_document")
        batch.drop_column("source_format")
