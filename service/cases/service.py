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
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from sqlalchemy.exc import DBAPIError, IntegrityError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError
from sqlalchemy.orm import Session, sessionmaker

from models.assumptions import Assumption
from models.pulse import PulseError
from models.triage import EngineModels, Method, UnknownVehicleModel, triage
from service.auth import Caller
from service.cases.notification import CrashNotificationIn, ReceivedSource
from service.cases.result import CaseList, CaseResult, CaseSummary, StoredCase, to_case_result
from service.context import ServiceContext
from service.db import repository
from service.db.repository import CaseRecord
from service.db.spool import SpoolEntry, SpoolError
from service.db.tables import Case, IdempotencyRecord
from service.problems import (
    EngineFailure,
    FieldError,
    IdempotencyConflict,
    NotFound,
    StoreUnavailable,
    UnprocessableNotification,
)

__all__ = [
    "load_case_record",
    "STORE_ERRORS",
    "InvalidCursor",
    "SubmitOutcome",
    "canonical_sha256",
    "decode_cursor",
    "encode_cursor",
    "evaluate",
    "get_case",
    "list_cases",
    "notification_sha256",
    "store_spooled",
    "submit",
]

log = logging.getLogger("aacn_triage.cases")

#: Errors that mean "the store is unavailable" (down, read-only, full, pool
#: exhausted), as opposed to an IntegrityError, which is the idempotency race.
STORE_ERRORS = (DBAPIError, PoolTimeoutError)


@dataclass(frozen=True)
class SubmitOutcome:
    """A submitted case, whether it replays an earlier one, whether it is spooled."""

    result: CaseResult
    replayed: bool
    spooled: bool = False
    #: ``result.model_dump(mode="json")`` when it was built already (a newly stored
    #: case: its stored payload and the two flags), else None.
    document: dict[str, Any] | None = None

    def wire(self) -> dict[str, Any]:
        """The answer as a JSON document (``result`` in the wire's field order)."""
        return self.document if self.document is not None else self.result.model_dump(mode="json")


class InvalidCursor(UnprocessableNotification):
    title = "Invalid cursor"


def canonical_sha256(document: Any) -> str:
    """SHA-256 of the canonical JSON form (sorted keys, no spaces) of a document."""
    text = json.dumps(document, sort_keys=True, separators=(",", ":"), ensure_ascii=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _no_negative_zero(value: Any) -> Any:
    if isinstance(value, float):
        return 0.0 if value == 0.0 else value
    if isinstance(value, dict):
        return {k: _no_negative_zero(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_no_negative_zero(v) for v in value]
    return value


def notification_sha256(notification: CrashNotificationIn, *, with_time: bool = True) -> str:
    """Fingerprint of what a notification means, for idempotency.

    The canonical JSON of the validated notification: every default written out,
    numbers as the floats they are (``56`` and ``56.0`` alike, ``-0.0`` as ``0.0``),
    the crash time in UTC. Two bodies that validate to the same notification are the
    same body (a replay, not a 409 conflict). A VEDS document maps to a
    notification and is fingerprinted as that notification, so a re-sent document,
    or the JSON of the same meaning, replays.

    Parameters
    ----------
    with_time : bool
        False when the crash time is not the sender's (a VEDS document without one
        takes the time it was received): it is then left out, so that the same
        document sent again replays instead of conflicting.
    """
    document = _no_negative_zero(notification.model_dump(mode="json"))
    document["occurred_at"] = (
        notification.occurred_at.astimezone(UTC).isoformat() if with_time else None
    )
    return canonical_sha256(document)


def evaluate(
    notification: CrashNotificationIn,
    models: EngineModels,
    *,
    case_id: str | None,
    received_at: datetime,
    extra_assumptions: Sequence[Assumption] = (),
    occupant_models: bool = True,
) -> CaseResult:
    """Run the engine on a validated notification (no database).

    `extra_assumptions` (what mapping a VEDS document assumed) come first in the
    answer's assumptions, before the engine's own. Without `occupant_models` the
    answer is the decision only (``models.triage.triage``'s decision-only run).

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
        result = triage(engine_input, models, occupant_models=occupant_models)
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
    return to_case_result(
        result,
        case_id=case_id,
        received_at=received_at,
        extra_assumptions=[*extra_assumptions, *notes],
    )


def _conflict(event_id: str, case_id: str) -> IdempotencyConflict:
    return IdempotencyConflict(
        f"event_id {event_id!r} was already submitted by this client with a "
        f"different body (case {case_id}); send a new event_id for a new event."
    )


def _replay_or_conflict(
    record: IdempotencyRecord, fingerprints: tuple[str, str], ctx: ServiceContext
) -> SubmitOutcome:
    if record.request_sha256 not in fingerprints:
        raise _conflict(record.event_id, record.case_id)
    with ctx.sessions() as session:
        case = repository.get_case(session, record.case_id)
        if case is None:  # pragma: no cover - the foreign key forbids it
            raise NotFound(f"case {record.case_id} is missing")
        ctx.metrics.replays.inc()
        return SubmitOutcome(result=CaseResult.model_validate(case.result), replayed=True)


def _replay_spooled(entry: SpoolEntry, fingerprint: str, ctx: ServiceContext) -> SubmitOutcome:
    if entry.request_sha256 != fingerprint:
        raise _conflict(entry.event_id, entry.case_id)
    ctx.metrics.replays.inc()
    result = CaseResult.model_validate({**entry.result, "stored": False, "spooled": True})
    return SubmitOutcome(result=result, replayed=True, spooled=True)


@dataclass(frozen=True)
class CaseRows:
    """The rows of one case as column values: the case, its occupants, its idempotency
    record (``repository.add_case`` inserts them in one transaction)."""

    case: dict[str, Any]
    occupants: list[dict[str, Any]]
    record: dict[str, Any]


def _case_rows(
    *,
    case_id: str,
    event_id: str,
    client_name: str,
    received_at: datetime,
    stored_at: datetime,
    spooled_at: datetime | None,
    request_sha256: str,
    document: Any,
    payload: dict[str, Any],
    source: dict[str, Any] | None,
) -> CaseRows:
    """The rows of one case, from its result payload (stored directly or spooled).

    `source` is `ReceivedSource.record()` of a notification that came in as another
    format than JSON (the document as received and its mapping), else None.
    """
    case = {
        "id": case_id,
        "event_id": event_id,
        "client_name": client_name,
        "received_at": received_at,
        "stored_at": stored_at,
        "spooled_at": spooled_at,
        "request_sha256": request_sha256,
        "notification": document,
        "result": payload,
        "models": payload["models"],
        "source_format": source["format"] if source else "json",
        "source_document": source["document"] if source else None,
        "source_mapping": source["mapping"] if source else None,
        "engine_version": payload["engine_version"],
        "iss15_plus": payload["triage"]["iss15_plus"],
        "probability": payload["triage"]["probability"],
        # None for a result spooled before tiers (the list derives those)
        "tier": payload["triage"].get("tier"),
        "high_threshold": payload["triage"].get("high_threshold"),
    }
    occupants = [
        {
            "case_id": case_id,
            "position": i,
            "seat": o["seat"],
            "impact_mode": o["impact_mode"],
            "method": o["method"],
            "iss15_plus": o["triage"]["iss15_plus"],
            "probability": o["triage"]["probability"],
            "tier": o["triage"].get("tier"),
        }
        for i, o in enumerate(payload["occupants"])
    ]
    record = {
        "client_name": client_name,
        "event_id": event_id,
        "request_sha256": request_sha256,
        "case_id": case_id,
        "created_at": stored_at,
    }
    return CaseRows(case=case, occupants=occupants, record=record)


def _add_case(ctx: ServiceContext, rows: CaseRows) -> IntegrityError | None:
    """Store a case and its idempotency record in one transaction.

    Returns None when stored, or the ``IntegrityError`` of a case whose (client,
    event_id) may have been committed first (:func:`_committed_first` finds it). The
    store's own errors (:data:`STORE_ERRORS`) are raised: each caller has its answer.
    """
    try:
        with ctx.sessions.begin() as session:
            repository.add_case(session, rows.case, rows.occupants, rows.record)
    except IntegrityError as exc:
        return exc
    return None


def _committed_first(
    ctx: ServiceContext, conflict: IntegrityError, client_name: str, event_id: str
) -> IdempotencyRecord:
    """The idempotency record committed first for (client, event_id); raises `conflict`
    when there is none (the store refused the case for another reason)."""
    with ctx.sessions() as session:
        existing = repository.get_idempotency_record(session, client_name, event_id)
    if existing is None:
        raise conflict
    return existing


def store_spooled(ctx: ServiceContext, entry: SpoolEntry) -> None:
    """Store one spooled case (the replayer's step); "already stored" counts as done.

    Raises
    ------
    sqlalchemy.exc.DBAPIError
        The store is still unavailable (the connection pool is reset).
    """
    rows = _case_rows(
        case_id=entry.case_id,
        event_id=entry.event_id,
        client_name=entry.client_name,
        received_at=entry.received_at,
        stored_at=datetime.now(UTC),
        spooled_at=entry.spooled_at,
        request_sha256=entry.request_sha256,
        document=entry.notification,
        payload=entry.result,
        source=entry.source,
    )
    try:
        conflict = _add_case(ctx, rows)
    except STORE_ERRORS:
        ctx.reset_store_connections()
        raise
    if conflict is not None:
        existing = _committed_first(ctx, conflict, entry.client_name, entry.event_id)
        if existing.case_id != entry.case_id:
            # stored before the outage and re-sent while the store could not be read:
            # the store keeps its case, the spooled duplicate is dropped
            log.warning(
                "spooled case dropped: its event was stored already",
                extra={"case_id": entry.case_id, "stored_case_id": existing.case_id},
            )
        return
    ctx.metrics.spool_replayed.inc()


def _spool(
    ctx: ServiceContext, entry: SpoolEntry, fingerprint: str, result: CaseResult
) -> SubmitOutcome:
    try:
        recorded = ctx.spool.put(entry)
    except SpoolError as exc:
        log.error(
            "the spool failed too: the case is not recorded",
            extra={"case_id": entry.case_id, "error_type": type(exc.__cause__).__name__},
        )
        raise StoreUnavailable(
            "Neither the audit store nor the local spool can record the case, so it is not "
            "answered; re-send the same event_id."
        ) from exc
    if recorded is not entry:  # the same event was spooled first by a concurrent request
        return _replay_spooled(recorded, fingerprint, ctx)
    ctx.metrics.spooled.inc()
    answer = result.model_copy(update={"stored": False, "spooled": True})
    return SubmitOutcome(result=answer, replayed=False, spooled=True)


def submit(
    ctx: ServiceContext,
    notification: CrashNotificationIn,
    document: Any,
    caller: Caller,
    received_at: datetime,
    source: ReceivedSource | None = None,
) -> SubmitOutcome:
    """Triage a notification and store it, or replay the stored case of its event_id.

    The case is committed before it is answered: to the store (201), or, when the
    store is unavailable, to the local spool (202, `stored: false`, `spooled:
    true`), from which it is stored later under the same case id.

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
    source : ReceivedSource or None
        The document as received when it was not this contract's JSON (VEDS): kept
        with the case, its assumptions added to the answer's.

    Raises
    ------
    IdempotencyConflict
        The event_id was submitted with a notification of another meaning.
    StoreUnavailable
        Neither the store nor the spool can record the case.
    """
    if ctx.models is None:
        raise RuntimeError("models are not loaded")
    time_is_senders = source is None or not source.occurred_at_assumed
    fingerprint = notification_sha256(notification, with_time=time_is_senders)
    # a case may also carry the fingerprint of its document as received (the older rule)
    fingerprints = (fingerprint, canonical_sha256(document))
    store_up = True
    try:
        with ctx.sessions() as session:
            record = repository.get_idempotency_record(session, caller.name, notification.event_id)
        if record is not None:
            return _replay_or_conflict(record, fingerprints, ctx)
    except STORE_ERRORS:
        store_up = False
        ctx.reset_store_connections()
    try:
        waiting = ctx.spool.find(caller.name, notification.event_id)
    except SpoolError:
        waiting = None  # spooling fails too if it comes to that
    if waiting is not None:
        return _replay_spooled(waiting, fingerprint, ctx)

    case_id = str(uuid.uuid4())
    start = time.perf_counter()
    result = evaluate(
        notification,
        ctx.models,
        case_id=case_id,
        received_at=received_at,
        extra_assumptions=source.assumptions if source else (),
    )
    ctx.metrics.engine_seconds.observe(time.perf_counter() - start)

    stored_at = datetime.now(UTC)
    payload = result.model_dump(mode="json", exclude={"stored", "spooled"})
    entry = SpoolEntry(
        seq=None,
        client_name=caller.name,
        event_id=notification.event_id,
        request_sha256=fingerprint,
        case_id=case_id,
        received_at=received_at,
        spooled_at=stored_at,
        notification=document,
        result=payload,
        source=source.record() if source else None,
    )
    if not store_up:
        return _spool(ctx, entry, fingerprint, result)
    rows = _case_rows(
        case_id=case_id,
        event_id=notification.event_id,
        client_name=caller.name,
        received_at=received_at,
        stored_at=stored_at,
        spooled_at=None,
        request_sha256=fingerprint,
        document=document,
        payload=payload,
        source=entry.source,
    )
    try:
        conflict = _add_case(ctx, rows)
    except STORE_ERRORS as exc:
        log.warning(
            "the store failed; the case goes to the spool",
            extra={"case_id": case_id, "error_type": type(exc).__name__},
        )
        ctx.reset_store_connections()
        return _spool(ctx, entry, fingerprint, result)
    if conflict is not None:  # a concurrent request with the same event committed first
        existing = _committed_first(ctx, conflict, caller.name, notification.event_id)
        return _replay_or_conflict(existing, fingerprints, ctx)
    decision = "iss15_plus" if result.triage.iss15_plus else "not_iss15_plus"
    methods = {o.method for o in result.occupants}
    method = Method.LPM if Method.LPM in methods else Method.FIELD
    ctx.metrics.decisions.labels(decision, method.value).inc()
    # the payload is the answer without its two last fields: the answer's document
    # without a second dump
    document = {**payload, "stored": result.stored, "spooled": result.spooled}
    return SubmitOutcome(result=result, replayed=False, document=document)


def stored_case(case: Case) -> StoredCase:
    """The wire form of a stored case row (also the NEMSIS export's input)."""
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
        source_format="veds" if case.source_format == "veds" else "json",
        source_document=case.source_document,
        source_mapping=case.source_mapping,
        tiers_derived=not isinstance(case.result.get("triage"), dict)
        or "tier" not in case.result["triage"],
    )


def get_case(ctx: ServiceContext, case_id: str) -> StoredCase:
    """The stored case, or NotFound."""
    with ctx.sessions() as session:
        case = repository.get_case(session, case_id)
        if case is None:
            raise NotFound(f"No case with id {case_id!r}.")
        return stored_case(case)


def load_case_record(sessions: sessionmaker[Session], case_id: str) -> CaseRecord | None:
    """The stored case as plain documents, or None (one read, no engine): the pages' source."""
    with sessions() as session:
        return repository.case_record(session, case_id)


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
        return at.astimezone(UTC), case_id
    except (
        ValueError,
        TypeError,
        OverflowError,
        RecursionError,
        binascii.Error,
        UnicodeDecodeError,
    ) as exc:
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
                tier=repository.case_tier(c),
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
