"""The case use cases: submit (validate -> triage -> store -> respond), read, list.

These are plain synchronous functions; the routers run them in a worker
thread so that the engine's CPU work never blocks the event loop.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import json
import logging
import time
import uuid
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from sqlalchemy.exc import IntegrityError

from models.pulse import PulseError
from models.triage import EngineModels, Method, UnknownVehicleModel, triage
from service.auth import Caller
from service.context import ServiceContext
from service.conversion import to_case_result
from service.db import repository
from service.db.tables import Case, CaseOccupant, IdempotencyRecord
from service.problems import (
    EngineFailure,
    FieldError,
    IdempotencyConflict,
    NotFound,
    UnprocessableNotification,
)
from service.schemas import CaseList, CaseResult, CaseSummary, CrashNotificationIn, StoredCase

log = logging.getLogger("aacn_triage")

__all__ = [
    "InvalidCursor",
    "SubmitOutcome",
    "canonical_sha256",
    "decode_cursor",
    "encode_cursor",
    "evaluate",
    "get_case",
    "list_cases",
    "submit",
]


@dataclass(frozen=True)
class SubmitOutcome:
    """A submitted case and whether it was a replay of an earlier one."""

    result: CaseResult
    replayed: bool


class InvalidCursor(UnprocessableNotification):
    title = "Invalid cursor"


def canonical_sha256(document: Any) -> str:
    """SHA-256 of the canonical JSON form (sorted keys, no spaces) of a document."""
    text = json.dumps(document, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def evaluate(
    notification: CrashNotificationIn,
    models: EngineModels,
    *,
    case_id: str | None,
    received_at: datetime,
) -> CaseResult:
    """Run the engine on a validated notification (no database).

    Raises
    ------
    UnprocessableNotification
        When the content is well-formed but the engine cannot use it (an
        unknown vehicle model, a pulse the engine cannot process).
    EngineFailure
        When the engine itself fails: a 500-class problem carrying the case
        reference, logged with it (and never with the notification's contents).
    """
    engine_input, notes = notification.to_engine()
    try:
        result = triage(engine_input, models)
    except UnknownVehicleModel as exc:
        raise UnprocessableNotification(
            str(exc),
            errors=[FieldError(field="vehicle.model", reason=str(exc), type="unknown_model")],
        ) from exc
    except PulseError as exc:
        raise UnprocessableNotification(
            f"The crash pulse cannot be processed: {exc}",
            errors=[FieldError(field="crash.pulse", reason=str(exc), type="pulse_unusable")],
        ) from exc
    except Exception as exc:
        reference = case_id or str(uuid.uuid4())
        log.exception("engine failure, case reference %s (%s)", reference, type(exc).__name__)
        raise EngineFailure(
            f"The engine failed on this notification; nothing was stored. Case reference "
            f"{reference} (give it to the operator: the failure is logged under it).",
            reference=reference,
        ) from exc
    return to_case_result(result, case_id=case_id, received_at=received_at, extra_assumptions=notes)


def _replay_or_conflict(
    record: IdempotencyRecord, request_sha256: str, ctx: ServiceContext
) -> SubmitOutcome:
    if record.request_sha256 != request_sha256:
        raise IdempotencyConflict(
            f"event_id {record.event_id!r} was already submitted by this client with a "
            f"different body (case {record.case_id}); send a new event_id for a new event."
        )
    with ctx.sessions() as session:
        case = repository.get_case(session, record.case_id)
        if case is None:  # pragma: no cover - the foreign key forbids it
            raise NotFound(f"case {record.case_id} is missing")
        ctx.metrics.replays.inc()
        return SubmitOutcome(result=CaseResult.model_validate(case.result), replayed=True)


def submit(
    ctx: ServiceContext,
    notification: CrashNotificationIn,
    document: Any,
    caller: Caller,
    received_at: datetime,
) -> SubmitOutcome:
    """Triage a notification and store it, or replay the stored case of its event_id.

    Parameters
    ----------
    ctx : ServiceContext
    notification : CrashNotificationIn
        The validated notification.
    document : Any
        The notification as received (parsed JSON), stored verbatim for audit.
    caller : Caller
    received_at : datetime
        When the request arrived (UTC).
    """
    if ctx.models is None:
        raise RuntimeError("models are not loaded")
    request_sha256 = canonical_sha256(document)
    with ctx.sessions() as session:
        record = repository.get_idempotency_record(session, caller.name, notification.event_id)
    if record is not None:
        return _replay_or_conflict(record, request_sha256, ctx)

    case_id = str(uuid.uuid4())
    start = time.perf_counter()
    result = evaluate(notification, ctx.models, case_id=case_id, received_at=received_at)
    ctx.metrics.engine_seconds.observe(time.perf_counter() - start)

    stored_at = datetime.now(UTC)
    payload = result.model_dump(mode="json")
    case = Case(
        id=case_id,
        event_id=notification.event_id,
        client_name=caller.name,
        received_at=received_at,
        stored_at=stored_at,
        request_sha256=request_sha256,
        notification=document,
        result=payload,
        models=payload["models"],
        engine_version=result.engine_version,
        iss15_plus=result.triage.iss15_plus,
        probability=result.triage.probability,
        occupants=[
            CaseOccupant(
                position=i,
                seat=o.seat.value,
                impact_mode=o.impact_mode,
                method=o.method,
                iss15_plus=o.triage.iss15_plus,
                probability=o.triage.probability,
            )
            for i, o in enumerate(result.occupants)
        ],
    )
    record = IdempotencyRecord(
        client_name=caller.name,
        event_id=notification.event_id,
        request_sha256=request_sha256,
        case_id=case_id,
        created_at=stored_at,
    )
    try:
        with ctx.sessions.begin() as session:
            repository.add_case(session, case, record)
    except IntegrityError:
        # A concurrent request with the same (client, event_id) committed first.
        with ctx.sessions() as session:
            existing = repository.get_idempotency_record(
                session, caller.name, notification.event_id
            )
        if existing is None:
            raise
        return _replay_or_conflict(existing, request_sha256, ctx)
    decision = "iss15_plus" if result.triage.iss15_plus else "not_iss15_plus"
    methods = {o.method for o in result.occupants}
    method = Method.LPM if Method.LPM in methods else Method.FIELD
    ctx.metrics.decisions.labels(decision, method.value).inc()
    return SubmitOutcome(result=result, replayed=False)


def _stored(case: Case) -> StoredCase:
    return StoredCase(
        case_id=case.id,
        event_id=case.event_id,
        client_name=case.client_name,
        received_at=case.received_at,
        stored_at=case.stored_at,
        request_sha256=case.request_sha256,
        notification=case.notification,
        result=CaseResult.model_validate(case.result),
        models=case.models,
    )


def get_case(ctx: ServiceContext, case_id: str) -> StoredCase:
    """The stored case, or NotFound."""
    with ctx.sessions() as session:
        case = repository.get_case(session, case_id)
        if case is None:
            raise NotFound(f"No case with id {case_id!r}.")
        return _stored(case)


def encode_cursor(received_at: datetime, case_id: str) -> str:
    raw = json.dumps([received_at.isoformat(), case_id]).encode()
    return base64.urlsafe_b64encode(raw).decode().rstrip("=")


def decode_cursor(cursor: str) -> tuple[datetime, str]:
    """Inverse of `encode_cursor`; InvalidCursor names the field on failure."""
    try:
        raw = base64.urlsafe_b64decode(cursor + "=" * (-len(cursor) % 4))
        at_text, case_id = json.loads(raw)
        at = datetime.fromisoformat(at_text)
        if at.tzinfo is None or not isinstance(case_id, str):
            raise ValueError("malformed")
        return at, case_id
    except (ValueError, TypeError, binascii.Error, UnicodeDecodeError) as exc:
        raise InvalidCursor(
            "The cursor is not one this service issued.",
            errors=[FieldError(field="cursor", reason="not a valid cursor", type="cursor")],
        ) from exc


def list_cases(
    ctx: ServiceContext,
    filters: repository.CaseFilters,
    *,
    limit: int,
    cursor: str | None,
) -> CaseList:
    """A page of cases, newest first."""
    after = decode_cursor(cursor) if cursor else None
    with ctx.sessions() as session:
        rows = repository.list_cases(session, filters, limit=limit + 1, after=after)
        items = [
            CaseSummary(
                case_id=c.id,
                event_id=c.event_id,
                client_name=c.client_name,
                received_at=c.received_at,
                iss15_plus=c.iss15_plus,
                probability=c.probability,
                impact_modes=[o.impact_mode for o in c.occupants],
            )
            for c in rows[:limit]
        ]
    next_cursor = None
    if len(rows) > limit:
        last = items[-1]
        next_cursor = encode_cursor(last.received_at, last.case_id)
    return CaseList(items=items, next_cursor=next_cursor)
