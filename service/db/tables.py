"""Typed SQLAlchemy 2 tables of the audit store."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

from sqlalchemy import (
    JSON,
    Boolean,
    DateTime,
    Dialect,
    Float,
    ForeignKey,
    Index,
    Integer,
    MetaData,
    String,
    Text,
    TypeDecorator,
    UniqueConstraint,
    text,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship

__all__ = [
    "ApiKey",
    "Base",
    "Case",
    "CaseOccupant",
    "EndedSession",
    "HealthProbe",
    "IdempotencyRecord",
    "OccupantOutcome",
    "UTCDateTime",
]

#: Constraint names that migrations can rely on (fastapi-best-practices, polar).
NAMING_CONVENTION = {
    "ix": "ix_%(column_0_label)s",
    "uq": "%(table_name)s_%(column_0_N_name)s_key",
    "ck": "%(table_name)s_%(constraint_name)s_check",
    "fk": "%(table_name)s_%(column_0_N_name)s_fkey",
    "pk": "%(table_name)s_pkey",
}


class UTCDateTime(TypeDecorator[datetime]):
    """A timezone-aware UTC timestamp on every backend (SQLite stores naive UTC)."""

    impl = DateTime(timezone=True)
    cache_ok = True

    def process_bind_param(self, value: datetime | None, dialect: Dialect) -> datetime | None:
        if value is None:
            return None
        if value.tzinfo is None:
            raise ValueError("naive datetimes are not stored; pass a timezone-aware value")
        value = value.astimezone(UTC)
        return value.replace(tzinfo=None) if dialect.name == "sqlite" else value

    def process_result_value(self, value: datetime | None, dialect: Dialect) -> datetime | None:
        if value is None:
            return None
        return value.replace(tzinfo=UTC) if value.tzinfo is None else value.astimezone(UTC)


class Base(DeclarativeBase):
    metadata = MetaData(naming_convention=NAMING_CONVENTION)
    type_annotation_map = {datetime: UTCDateTime, dict[str, Any]: JSON}


class ApiKey(Base):
    """A client's API key; only its SHA-256 is stored."""

    __tablename__ = "api_keys"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    name: Mapped[str] = mapped_column(String(100), unique=True)
    role: Mapped[str] = mapped_column(String(20))
    key_prefix: Mapped[str] = mapped_column(String(16))
    key_sha256: Mapped[str] = mapped_column(String(64), unique=True)
    created_at: Mapped[datetime]
    revoked_at: Mapped[datetime | None]


class Case(Base):
    """One triaged notification: what came in, what went out, and with which models."""

    __tablename__ = "cases"

    id: Mapped[str] = mapped_column(String(36), primary_key=True)
    event_id: Mapped[str] = mapped_column(String(128))
    client_name: Mapped[str] = mapped_column(String(100))
    received_at: Mapped[datetime]
    stored_at: Mapped[datetime]
    #: When the case was recorded in the local spool because the store failed (None:
    #: stored directly); `stored_at` is then when the spool was replayed into the store.
    spooled_at: Mapped[datetime | None]
    request_sha256: Mapped[str] = mapped_column(String(64))
    notification: Mapped[dict[str, Any]]
    result: Mapped[dict[str, Any]]
    models: Mapped[dict[str, Any]]
    #: How the notification came in: ``json`` (this contract) or ``veds`` (RFC 8148 XML).
    source_format: Mapped[str] = mapped_column(String(16), server_default=text("'json'"))
    #: A VEDS document exactly as received (None for JSON: `notification` is the body).
    source_document: Mapped[str | None] = mapped_column(Text)
    #: For VEDS: which elements became which fields, what was assumed, what was unused.
    source_mapping: Mapped[dict[str, Any] | None] = mapped_column(JSON(none_as_null=True))
    engine_version: Mapped[str] = mapped_column(String(32))
    iss15_plus: Mapped[bool] = mapped_column(Boolean)
    probability: Mapped[float] = mapped_column(Float)
    #: The case's risk tier (``high``, ``moderate``, ``none``) and the high-risk
    #: threshold it was set with; None for cases stored before tiers, whose tier is
    #: derived when read (``repository.tier_expression``), the rows left as stored.
    tier: Mapped[str | None] = mapped_column(String(16))
    high_threshold: Mapped[float | None] = mapped_column(Float)

    occupants: Mapped[list[CaseOccupant]] = relationship(
        back_populates="case", cascade="all, delete-orphan", order_by="CaseOccupant.position"
    )

    __table_args__ = (Index("ix_cases_received_at_id", "received_at", "id"),)


class CaseOccupant(Base):
    """Per-occupant facts of a case, kept as columns for audit queries and filters."""

    __tablename__ = "case_occupants"

    case_id: Mapped[str] = mapped_column(
        String(36), ForeignKey("cases.id", ondelete="CASCADE"), primary_key=True
    )
    position: Mapped[int] = mapped_column(Integer, primary_key=True)
    seat: Mapped[str] = mapped_column(String(32))
    impact_mode: Mapped[str] = mapped_column(String(16), index=True)
    method: Mapped[str] = mapped_column(String(16))
    iss15_plus: Mapped[bool] = mapped_column(Boolean)
    probability: Mapped[float] = mapped_column(Float)
    #: The occupant's risk tier; None for cases stored before tiers.
    tier: Mapped[str | None] = mapped_column(String(16))

    case: Mapped[Case] = relationship(back_populates="occupants")


class IdempotencyRecord(Base):
    """(client, event_id) -> the case it produced and the fingerprint of the body."""

    __tablename__ = "idempotency_records"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    client_name: Mapped[str] = mapped_column(String(100))
    event_id: Mapped[str] = mapped_column(String(128))
    request_sha256: Mapped[str] = mapped_column(String(64))
    case_id: Mapped[str] = mapped_column(String(36), ForeignKey("cases.id", ondelete="CASCADE"))
    created_at: Mapped[datetime]

    __table_args__ = (UniqueConstraint("client_name", "event_id"),)


class HealthProbe(Base):
    """One row that readiness rewrites: a committed write proves the store writable."""

    __tablename__ = "health_probe"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=False)
    checked_at: Mapped[datetime]


class EndedSession(Base):
    """A browser session ended by its sign-out (``service.browser_session_end``).

    Its cookie is refused until it would have expired; then the row may go.
    """

    __tablename__ = "ended_sessions"

    #: SHA-256 of the session's nonce (the cookie's "n").
    session_sha256: Mapped[str] = mapped_column(String(64), primary_key=True)
    expires_at: Mapped[datetime] = mapped_column(index=True)


class OccupantOutcome(Base):
    """One written outcome of a stored occupant: append-only, the highest revision current.

    A correction is a new row (revision + 1), never an update, so the history of every
    occupant's outcome, and who wrote each revision and when, stays in the store
    (``service.outcomes.service``).
    """

    __tablename__ = "occupant_outcomes"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    case_id: Mapped[str] = mapped_column(
        String(36), ForeignKey("cases.id", ondelete="CASCADE"), index=True
    )
    #: The occupant's position in the case (``case_occupants.position``) and its seat.
    position: Mapped[int] = mapped_column(Integer)
    seat: Mapped[str] = mapped_column(String(32))
    #: 1 for the first outcome of the occupant, +1 per correction.
    revision: Mapped[int] = mapped_column(Integer)
    #: Injury Severity Score 0-75 (None: an EMS outcome without one, "not transported").
    iss: Mapped[int | None] = mapped_column(Integer)
    #: Maximum AIS 0-6, where known.
    mais: Mapped[int | None] = mapped_column(Integer)
    died: Mapped[bool | None] = mapped_column(Boolean)
    disposition: Mapped[str | None] = mapped_column(String(32))
    source: Mapped[str] = mapped_column(String(32))
    #: When the source recorded the outcome.
    recorded_at: Mapped[datetime]
    #: Survey weight of the occupant in the figures (1 unless a registry extract says).
    weight: Mapped[float] = mapped_column(Float)
    #: Who wrote this revision: the API key's name, or the import command's account.
    written_by: Mapped[str] = mapped_column(String(200))
    written_at: Mapped[datetime]
    #: ``api`` or ``import``.
    channel: Mapped[str] = mapped_column(String(16))
    #: SHA-256 of the outcome's content, so that a write of the same content is a replay.
    content_sha256: Mapped[str] = mapped_column(String(64))

    __table_args__ = (UniqueConstraint("case_id", "position", "revision"),)
