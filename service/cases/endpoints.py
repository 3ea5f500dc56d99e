"""POST /v1/cases, GET /v1/cases/{case_id}, GET /v1/cases."""

from __future__ import annotations

from datetime import UTC, datetime
from enum import StrEnum
from typing import TYPE_CHECKING, Annotated, Any

from fastapi import APIRouter, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError

from models.impact_mode import ImpactMode
from models.tiers import Tier
from service.auth import require_auditor, require_submitter
from service.cases import service as cases_service
from service.cases.notification import CrashNotificationIn, ReceivedSource, Rfc3339Text
from service.cases.result import CaseList, CaseResult, StoredCase
from service.cases.veds import VEDS_MEDIA_TYPE, is_veds_media_type, read_veds
from service.db.repository import CaseFilters
from service.deps import ContextDep
from service.jsonbody import MalformedJson
from service.problems import (
    PROBLEM_MEDIA_TYPE,
    MalformedBody,
    Problem,
    UnsupportedMediaType,
)

__all__ = ["router"]

router = APIRouter(prefix="/v1/cases", tags=["cases"])


def _problems(*statuses: int) -> dict[int | str, dict[str, Any]]:
    return {
        s: {"model": Problem, "content": {PROBLEM_MEDIA_TYPE: {}}, "description": "Problem"}
        for s in statuses
    }


if TYPE_CHECKING:
    ImpactModeFilter = ImpactMode
else:
    #: The `impact_mode` query parameter's type: the values of
    #: `models.impact_mode.ImpactMode` (the one spelling of the modes), under the name
    #: the OpenAPI document gives it (its schema `ImpactModeFilter`).
    ImpactModeFilter = StrEnum("ImpactModeFilter", {m.value: m.value for m in ImpactMode})
    ImpactModeFilter.__doc__ = "Impact mode of at least one occupant of the case."


CaseId = Annotated[str, Path(description="Case id (UUID).", max_length=64)]

QueryTime = Rfc3339Text

#: Longest accepted `cursor`: an issued one is about 110 characters (base64 of an
#: RFC 3339 time and a UUID); a bound keeps crafted ones (1,100 nested brackets
#: overflowed the JSON parser's recursion, a fuzzing finding) out of the parser.
MAX_CURSOR_CHARS = 256


def _json_media_type(request: Request) -> bool:
    media = request.headers.get("content-type", "").split(";", 1)[0].strip().lower()
    return media == "application/json" or (
        media.startswith("application/") and media.endswith("+json")
    )


@router.post(
    "",
    status_code=201,
    summary="Triage a crash notification",
    response_model=CaseResult,
    responses={
        200: {"model": CaseResult, "description": "Replay of the event's case."},
        202: {
            "model": CaseResult,
            "description": "Triaged, and recorded in the local spool because the audit "
            "store is unavailable (`stored: false`, `spooled: true`); stored later under the "
            "same case id.",
        },
        **_problems(400, 401, 403, 409, 413, 415, 422, 503),
    },
)
async def create_case(
    request: Request,
    caller: require_submitter,
    ctx: ContextDep,
) -> JSONResponse:
    """Triage every occupant, store the case, and answer with the case result.

    The key is checked before the body is read. The body must be
    `application/json` (else 415), one JSON document without repeated keys (else
    400), with strict types: numbers as JSON numbers, booleans as `true`/`false`,
    times as RFC 3339 text (else 422).

    Or a VEDS document, `application/EmergencyCallData.VEDS+xml` (RFC 8148, VEDS 3.1
    or 1.0): read safely (no DTD or entities, bounded depth; else 400), mapped to
    the same notification (a missing delta-V, an unknown unit or seat code: 422
    naming the element) and answered the same way. Its incident id (else the
    document's SHA-256) is the `event_id`; the XML is kept with the case.

    Re-sending an `event_id` with a notification of the same meaning (`56` and
    `56.0` alike, defaults written out or not) answers the case with status 200 and
    `Idempotent-Replayed: true`; with another, 409. When the audit store is
    unavailable, the case is recorded in the local spool and answered with 202.
    """
    received_at = datetime.now(UTC)
    source: ReceivedSource | None = None
    if is_veds_media_type(request.headers.get("content-type", "")):
        raw = await request.body()
        veds = await run_in_threadpool(read_veds, raw, received_at=received_at)
        notification, document, source = veds.notification, veds.document, veds.source
    elif _json_media_type(request):
        notification, document = _read_json(await request.body())
    else:
        raise UnsupportedMediaType(
            "Send the notification as `Content-Type: application/json`, or a VEDS document "
            f"as `Content-Type: {VEDS_MEDIA_TYPE}`."
        )
    outcome = await run_in_threadpool(
        cases_service.submit, ctx, notification, document, caller, received_at, source
    )
    case_id = outcome.result.case_id
    status = 200 if outcome.replayed else 202 if outcome.spooled else 201
    return JSONResponse(
        outcome.wire(),
        status_code=status,
        headers={
            "Location": f"/v1/cases/{case_id}",
            "Idempotent-Replayed": "true" if outcome.replayed else "false",
        },
    )


def _read_json(raw: bytes) -> tuple[CrashNotificationIn, Any]:
    """The JSON notification, strictly validated, and the parsed document."""
    try:
        return CrashNotificationIn.from_json(raw)
    except MalformedJson as exc:
        raise MalformedBody(f"The request body is not valid JSON: {exc}") from exc
    except ValidationError as exc:
        raise RequestValidationError(
            [{**e, "loc": ("body", *e["loc"])} for e in exc.errors()]
        ) from exc


@router.get(
    "/{case_id}",
    summary="Read a stored case",
    response_model=StoredCase,
    responses=_problems(401, 403, 404, 422),
)
def read_case(case_id: CaseId, caller: require_auditor, ctx: ContextDep) -> StoredCase:
    """The notification as received, the result, the client, timestamps and model versions."""
    return cases_service.get_case(ctx, case_id)


@router.get(
    "",
    summary="List stored cases, newest first",
    response_model=CaseList,
    responses=_problems(401, 403, 422),
)
def list_cases(
    caller: require_auditor,
    ctx: ContextDep,
    limit: Annotated[
        int | None, Query(ge=1, description="Page size; capped at the configured maximum.")
    ] = None,
    cursor: Annotated[
        str | None,
        Query(max_length=MAX_CURSOR_CHARS, description="`next_cursor` of the previous page."),
    ] = None,
    received_from: Annotated[
        QueryTime | None,
        Query(description="Only cases received at or after this time (RFC 3339, with offset)."),
    ] = None,
    received_before: Annotated[
        QueryTime | None,
        Query(description="Only cases received before this time (RFC 3339, with offset)."),
    ] = None,
    iss15_plus: Annotated[bool | None, Query(description="Only this case-level decision.")] = None,
    tier: Annotated[
        Tier | None,
        Query(
            description="Only this case-level risk tier (`high`, `moderate`, `none`; derived "
            "for cases stored before tiers, with the high-risk threshold at its default)."
        ),
    ] = None,
    impact_mode: Annotated[
        ImpactModeFilter | None, Query(description="Only cases with an occupant in this mode.")
    ] = None,
) -> CaseList:
    """Keyset-paginated list of cases with filters."""
    settings = ctx.settings
    page = min(limit or settings.page_default_limit, settings.page_max_limit)
    filters = CaseFilters(
        received_from=received_from,
        received_before=received_before,
        iss15_plus=iss15_plus,
        impact_mode=impact_mode.value if impact_mode is not None else None,
        tier=tier,
    )
    return cases_service.list_cases(ctx, filters, limit=page, cursor=cursor)
