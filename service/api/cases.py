"""POST /v1/cases, GET /v1/cases/{case_id}, GET /v1/cases."""

from __future__ import annotations

import json
import re
from datetime import UTC, datetime
from enum import StrEnum
from typing import Annotated, Any

from fastapi import APIRouter, Body, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import JSONResponse
from pydantic import AwareDatetime, BeforeValidator

from service import cases_service
from service.api.deps import ContextDep
from service.auth import require_auditor, require_submitter
from service.db.repository import CaseFilters
from service.problems import PROBLEM_MEDIA_TYPE, Problem
from service.schemas import (
    EXAMPLE_NOTIFICATIONS,
    CaseList,
    CaseResult,
    CrashNotificationIn,
    StoredCase,
)

__all__ = ["router"]

router = APIRouter(prefix="/v1/cases", tags=["cases"])


def _problems(*statuses: int) -> dict[int | str, dict[str, Any]]:
    return {
        s: {"model": Problem, "content": {PROBLEM_MEDIA_TYPE: {}}, "description": "Problem"}
        for s in statuses
    }


class ImpactModeFilter(StrEnum):
    """Impact mode of at least one occupant of the case."""

    frontal = "frontal"
    rear = "rear"
    near_side = "near_side"
    far_side = "far_side"


CaseId = Annotated[str, Path(description="Case id (UUID).", max_length=64)]

#: An RFC 3339 date-time with its offset ("2026-11-23T08:15:30Z"); pydantic alone
#: would also take a bare number as a Unix time (found by a schemathesis run:
#: ``received_from=0.5`` listed every case).
_RFC3339 = re.compile(r"^\d{4}-\d{2}-\d{2}[Tt ]\d{2}:\d{2}")


def _rfc3339_text(value: object) -> object:
    if not (isinstance(value, str) and _RFC3339.match(value)):
        raise ValueError(
            "must be an RFC 3339 date-time with a UTC offset, e.g. 2026-11-23T08:15:30Z"
        )
    return value


QueryTime = Annotated[AwareDatetime, BeforeValidator(_rfc3339_text)]


@router.post(
    "",
    status_code=201,
    summary="Triage a crash notification",
    response_model=CaseResult,
    responses={
        200: {"model": CaseResult, "description": "Replay of the event's stored case."},
        **_problems(400, 401, 403, 409, 413, 422),
    },
)
async def create_case(
    request: Request,
    notification: Annotated[CrashNotificationIn, Body(openapi_examples=EXAMPLE_NOTIFICATIONS)],
    caller: require_submitter,
    ctx: ContextDep,
) -> JSONResponse:
    """Triage every occupant, store the case, and answer with the case result.

    Re-sending an `event_id` with the same body answers the stored case with
    status 200 and `Idempotent-Replayed: true`; with another body, 409.
    """
    received_at = datetime.now(UTC)
    document = json.loads(await request.body())
    outcome = await run_in_threadpool(
        cases_service.submit, ctx, notification, document, caller, received_at
    )
    case_id = outcome.result.case_id
    return JSONResponse(
        outcome.result.model_dump(mode="json"),
        status_code=200 if outcome.replayed else 201,
        headers={
            "Location": f"/v1/cases/{case_id}",
            "Idempotent-Replayed": "true" if outcome.replayed else "false",
        },
    )


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
    cursor: Annotated[str | None, Query(description="`next_cursor` of the previous page.")] = None,
    received_from: Annotated[
        QueryTime | None,
        Query(description="Only cases received at or after this time (RFC 3339, with offset)."),
    ] = None,
    received_before: Annotated[
        QueryTime | None,
        Query(description="Only cases received before this time (RFC 3339, with offset)."),
    ] = None,
    iss15_plus: Annotated[bool | None, Query(description="Only this case-level decision.")] = None,
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
    )
    return cases_service.list_cases(ctx, filters, limit=page, cursor=cursor)
