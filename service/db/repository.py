"""Every query of the service. Services call these; routers never touch SQL."""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from sqlalchemy import (
    ColumnElement,
    Table,
    and_,
    case,
    delete,
    exists,
    func,
    insert,
    or_,
    select,
    text,
    update,
)
from sqlalchemy.orm import Session, selectinload

from models.tiers import HIGH_RISK_THRESHOLD, Tier
from service.db.tables import (
    ApiKey,
    Base,
    Case,
    CaseOccupant,
    EndedSession,
    HealthProbe,
    IdempotencyRecord,
    OccupantOutcome,
)

__all__ = [
    "CaseFilters",
    "CaseRecord",
    "add_api_key",
    "add_case",
    "add_outcome",
    "case_record",
    "case_tier",
    "count_cases",
    "current_outcome",
    "current_outcomes",
    "find_case_by_event",
    "outcome_history",
    "quality_rows",
    "end_browser_session",
    "find_active_key",
    "get_active_key_by_id",
    "get_api_key",
    "get_api_key_by_name",
    "get_case",
    "get_idempotency_record",
    "is_browser_session_ended",
    "list_api_keys",
    "list_cases",
    "ping",
    "probe_write",
    "revoke_api_key",
    "rotate_api_key",
    "tier_expression",
]


def ping(session: Session) -> None:
    """Round trip to the database (readiness)."""
    session.execute(text("SELECT 1"))


def probe_write(session: Session, at: datetime) -> None:
    """Rewrite the health probe row (readiness: the caller commits it)."""
    done = session.execute(update(HealthProbe).where(HealthProbe.id == 1).values(checked_at=at))
    if getattr(done, "rowcount", 0) == 0:
        session.add(HealthProbe(id=1, checked_at=at))
    session.flush()


# ------------------------------------------------------------------ API keys


def add_api_key(session: Session, key: ApiKey) -> ApiKey:
    session.add(key)
    session.flush()
    return key


def find_active_key(session: Session, key_sha256: str) -> ApiKey | None:
    return session.scalar(
        select(ApiKey).where(ApiKey.key_sha256 == key_sha256, ApiKey.revoked_at.is_(None))
    )


def get_active_key_by_id(session: Session, key_id: int) -> ApiKey | None:
    return session.scalar(select(ApiKey).where(ApiKey.id == key_id, ApiKey.revoked_at.is_(None)))


def get_api_key_by_name(session: Session, name: str) -> ApiKey | None:
    return session.scalar(select(ApiKey).where(ApiKey.name == name))


def list_api_keys(session: Session) -> Sequence[ApiKey]:
    return session.scalars(select(ApiKey).order_by(ApiKey.id)).all()


def get_api_key(session: Session, name_or_id: str) -> ApiKey | None:
    """A key by its name, or by its numeric id (ASCII digits: ``str.isdigit`` takes ``²``)."""
    key = get_api_key_by_name(session, name_or_id)
    if key is None and re.fullmatch(r"[0-9]{1,9}", name_or_id):
        key = session.get(ApiKey, int(name_or_id))
    return key


def revoke_api_key(session: Session, key: ApiKey, at: datetime) -> None:
    key.revoked_at = at
    session.flush()


def rotate_api_key(session: Session, key: ApiKey, *, key_prefix: str, key_sha256: str) -> None:
    """Replace a key's secret in place (same name and role; the old secret stops at once)."""
    key.key_prefix = key_prefix
    key.key_sha256 = key_sha256
    session.flush()


# --------------------------------------------------------------------- cases


def _table(entity: type[Base]) -> Table:
    return Base.metadata.tables[entity.__tablename__]


def add_case(
    session: Session,
    case: Mapping[str, Any],
    occupants: Sequence[Mapping[str, Any]],
    record: Mapping[str, Any],
) -> None:
    """Insert a case, its occupants and its idempotency record (the caller commits).

    Column values by name. Three INSERT statements on the session's connection (the
    occupants as one executemany), in the order the foreign keys ask for, without the
    ORM's unit of work: nothing is read back, so no object needs to be tracked. A
    second case of the same (client, event_id) raises ``IntegrityError`` at the record.
    """
    session.execute(insert(_table(Case)), dict(case))
    if occupants:
        session.execute(insert(_table(CaseOccupant)), [dict(o) for o in occupants])
    session.execute(insert(_table(IdempotencyRecord)), dict(record))


def get_case(session: Session, case_id: str) -> Case | None:
    return session.get(Case, case_id)


def count_cases(session: Session, *, received_from: datetime | None = None) -> int:
    """Cases received at or after `received_from` (all: None), for a progress bar."""
    stmt = select(func.count()).select_from(Case)
    if received_from is not None:
        stmt = stmt.where(Case.received_at >= received_from)
    return int(session.scalar(stmt) or 0)


def cases_oldest_first(
    session: Session, *, limit: int, after: tuple[datetime, str] | None = None
) -> Sequence[Case]:
    """Cases oldest first, keyset-paginated on (received_at, id) (recall reports).

    Parameters
    ----------
    after : (received_at, case_id) or None
        The last row of the previous page.
    """
    stmt = select(Case).order_by(Case.received_at, Case.id).limit(limit)
    if after is not None:
        at, case_id = after
        stmt = stmt.where(
            or_(Case.received_at > at, and_(Case.received_at == at, Case.id > case_id))
        )
    return session.scalars(stmt).all()


def get_idempotency_record(
    session: Session, client_name: str, event_id: str
) -> IdempotencyRecord | None:
    return session.scalar(
        select(IdempotencyRecord).where(
            IdempotencyRecord.client_name == client_name, IdempotencyRecord.event_id == event_id
        )
    )


@dataclass(frozen=True)
class CaseFilters:
    """Filters of the case list (all optional)."""

    received_from: datetime | None = None
    received_before: datetime | None = None
    iss15_plus: bool | None = None
    impact_mode: str | None = None
    tier: Tier | None = None


def tier_expression() -> ColumnElement[str]:
    """The case's tier in SQL: as stored, else derived for a case stored before tiers.

    Derived as :func:`models.tiers.tier_of` of the stored decision (``iss15_plus``
    is the probability at or above the operating threshold) with the high-risk
    threshold at its default; :func:`case_tier` is the same in Python.
    """
    derived = case(
        (Case.iss15_plus.is_(False), Tier.NONE.value),
        (
            Case.probability >= func.coalesce(Case.high_threshold, HIGH_RISK_THRESHOLD),
            Tier.HIGH.value,
        ),
        else_=Tier.MODERATE.value,
    )
    return func.coalesce(Case.tier, derived)


def case_tier(c: Case) -> Tier:
    """The tier of a case row (:func:`tier_expression` in Python)."""
    if c.tier is not None:
        return Tier(c.tier)
    if not c.iss15_plus:
        return Tier.NONE
    high = HIGH_RISK_THRESHOLD if c.high_threshold is None else c.high_threshold
    return Tier.HIGH if c.probability >= high else Tier.MODERATE


def list_cases(
    session: Session,
    filters: CaseFilters,
    *,
    limit: int,
    after: tuple[datetime, str] | None = None,
) -> Sequence[Case]:
    """Cases newest first, keyset-paginated on (received_at, id).

    Parameters
    ----------
    after : (received_at, case_id) or None
        The last row of the previous page.
    """
    stmt = select(Case).options(selectinload(Case.occupants))
    if filters.received_from is not None:
        stmt = stmt.where(Case.received_at >= filters.received_from)
    if filters.received_before is not None:
        stmt = stmt.where(Case.received_at < filters.received_before)
    if filters.iss15_plus is not None:
        stmt = stmt.where(Case.iss15_plus.is_(filters.iss15_plus))
    if filters.tier is not None:
        stmt = stmt.where(tier_expression() == filters.tier.value)
    if filters.impact_mode is not None:
        stmt = stmt.where(
            exists().where(
                and_(
                    CaseOccupant.case_id == Case.id,
                    CaseOccupant.impact_mode == filters.impact_mode,
                )
            )
        )
    if after is not None:
        at, case_id = after
        stmt = stmt.where(
            or_(Case.received_at < at, and_(Case.received_at == at, Case.id < case_id))
        )
    stmt = stmt.order_by(Case.received_at.desc(), Case.id.desc()).limit(limit)
    return session.scalars(stmt).all()


@dataclass(frozen=True)
class CaseRecord:
    """A stored case as read from the audit store (plain JSON documents)."""

    case_id: str
    event_id: str
    client_name: str
    received_at: datetime
    stored_at: datetime
    request_sha256: str
    engine_version: str
    notification: Mapping[str, Any]
    result: Mapping[str, Any]
    models: Mapping[str, Any]
    #: ``json`` or ``veds``: how the notification came in
    source_format: str = "json"
    #: for VEDS: the mapping record (version, vehicle, mapped, assumed, ignored)
    source_mapping: Mapping[str, Any] | None = None


def case_record(session: Session, case_id: str) -> CaseRecord | None:
    """The stored case as plain documents, or None (one read)."""
    case = get_case(session, case_id)
    if case is None:
        return None
    return CaseRecord(
        case_id=case.id,
        event_id=case.event_id,
        client_name=case.client_name,
        received_at=case.received_at,
        stored_at=case.stored_at,
        request_sha256=case.request_sha256,
        engine_version=case.engine_version,
        notification=case.notification,
        result=case.result,
        models=case.models,
        source_format=case.source_format,
        source_mapping=case.source_mapping,
    )


# ------------------------------------------------------------------ outcomes


def find_case_by_event(session: Session, client_name: str, event_id: str) -> Case | None:
    """The case a client stored for an event id (an event id is unique per client)."""
    record = get_idempotency_record(session, client_name, event_id)
    return None if record is None else session.get(Case, record.case_id)


def current_outcome(session: Session, case_id: str, position: int) -> OccupantOutcome | None:
    """The occupant's outcome as last written (highest revision), or None."""
    return session.scalar(
        select(OccupantOutcome)
        .where(OccupantOutcome.case_id == case_id, OccupantOutcome.position == position)
        .order_by(OccupantOutcome.revision.desc())
        .limit(1)
    )


def outcome_history(session: Session, case_id: str, position: int) -> Sequence[OccupantOutcome]:
    """Every revision of the occupant's outcome, first written first."""
    return session.scalars(
        select(OccupantOutcome)
        .where(OccupantOutcome.case_id == case_id, OccupantOutcome.position == position)
        .order_by(OccupantOutcome.revision)
    ).all()


def add_outcome(session: Session, outcome: OccupantOutcome) -> OccupantOutcome:
    """Stage a revision (the unique (case, position, revision) refuses a concurrent twin)."""
    session.add(outcome)
    session.flush()
    return outcome


def current_outcomes(
    session: Session, case_ids: Sequence[str]
) -> dict[tuple[str, int], OccupantOutcome]:
    """The current outcome of every occupant of these cases that has one."""
    out: dict[tuple[str, int], OccupantOutcome] = {}
    for start in range(0, len(case_ids), _IN_CHUNK):
        chunk = case_ids[start : start + _IN_CHUNK]
        latest = (
            select(
                OccupantOutcome.case_id,
                OccupantOutcome.position,
                func.max(OccupantOutcome.revision).label("revision"),
            )
            .where(OccupantOutcome.case_id.in_(chunk))
            .group_by(OccupantOutcome.case_id, OccupantOutcome.position)
            .subquery()
        )
        rows = session.scalars(
            select(OccupantOutcome).join(
                latest,
                and_(
                    OccupantOutcome.case_id == latest.c.case_id,
                    OccupantOutcome.position == latest.c.position,
                    OccupantOutcome.revision == latest.c.revision,
                ),
            )
        ).all()
        out.update({(o.case_id, o.position): o for o in rows})
    return out


#: Case ids per ``IN (...)`` list: well under SQLite's 32,766 bound variables.
_IN_CHUNK = 500


@dataclass(frozen=True)
class LinkedDecision:
    """One stored occupant's decision with its current outcome (the recalibration's row)."""

    case_id: str
    seat: str
    models: dict[str, Any]
    probability: float
    iss: int | None
    weight: float


def linked_decisions(session: Session, chunk: int = 1000) -> Iterator[LinkedDecision]:
    """Every stored occupant with an outcome, its decision and its current outcome (the
    latest revision), cases oldest first and occupants in seat order.

    Streamed (``yield_per``): only linked occupants' columns and their case's model record
    are read, never a case's notification or answer, so a year of cases is not held in
    memory.
    """
    latest = (
        select(
            OccupantOutcome.case_id,
            OccupantOutcome.position,
            func.max(OccupantOutcome.revision).label("revision"),
        )
        .group_by(OccupantOutcome.case_id, OccupantOutcome.position)
        .subquery()
    )
    stmt = (
        select(
            Case.id,
            CaseOccupant.seat,
            Case.models,
            CaseOccupant.probability,
            OccupantOutcome.iss,
            OccupantOutcome.weight,
        )
        .join(CaseOccupant, CaseOccupant.case_id == Case.id)
        .join(
            latest,
            and_(
                latest.c.case_id == CaseOccupant.case_id,
                latest.c.position == CaseOccupant.position,
            ),
        )
        .join(
            OccupantOutcome,
            and_(
                OccupantOutcome.case_id == latest.c.case_id,
                OccupantOutcome.position == latest.c.position,
                OccupantOutcome.revision == latest.c.revision,
            ),
        )
        .order_by(Case.received_at, Case.id, CaseOccupant.position)
        .execution_options(yield_per=chunk)
    )
    for row in session.execute(stmt):
        yield LinkedDecision(*row)


def quality_rows(
    session: Session,
    *,
    received_from: datetime | None = None,
    received_before: datetime | None = None,
) -> Sequence[Case]:
    """Cases (with their occupants) received in a window, oldest first: the quality figures'
    population, linked or not."""
    stmt = select(Case).options(selectinload(Case.occupants))
    if received_from is not None:
        stmt = stmt.where(Case.received_at >= received_from)
    if received_before is not None:
        stmt = stmt.where(Case.received_at < received_before)
    return session.scalars(stmt.order_by(Case.received_at, Case.id)).all()


# ---------------------------------------------------------- browser sessions


def end_browser_session(
    session: Session, session_sha256: str, expires_at: datetime, now: datetime
) -> None:
    """Record a signed-out session (idempotent) and drop those past their expiry."""
    session.execute(delete(EndedSession).where(EndedSession.expires_at <= now))
    if session.get(EndedSession, session_sha256) is None:
        session.add(EndedSession(session_sha256=session_sha256, expires_at=expires_at))
    session.flush()


def is_browser_session_ended(session: Session, session_sha256: str) -> bool:
    return session.get(EndedSession, session_sha256) is not None
