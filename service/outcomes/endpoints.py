"""Outcomes of stored occupants, and the triage quality they measure.

- ``POST /v1/cases/{case_id}/occupants/{seat}/outcome``: the first outcome (registry, admin);
- ``PUT`` the same: the current outcome, a correction kept beside the old (registry, admin);
- ``GET`` the same: the current outcome and its history (auditor, admin);
- ``GET /v1/quality``: triage quality by month, operating point and tier (auditor, admin).
"""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Path, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError

from models.notification import Seat
from service.auth import Caller, require_auditor, require_registry
from service.cases.notification import Rfc3339Text
from service.deps import ContextDep
from service.jsonbody import MalformedJson
from service.outcomes import quality as quality_service
from service.outcomes import service as outcomes_service
from service.outcomes.quality import AGE_GROUPS, CRASH_MODES, QualityFilters, QualityReport
from service.outcomes.schemas import OutcomeIn, OutcomeOut, OutcomeRecord
from service.outcomes.service import WriteMode
from service.problems import PROBLEM_MEDIA_TYPE, MalformedBody, Problem, UnsupportedMediaType

__all__ = ["router"]

router = APIRouter(tags=["outcomes"])

CaseId = Annotated[str, Path(description="Case id (UUID).", max_length=64)]
SeatPath = Annotated[Seat, Path(description="Seat of the occupant in the case.")]

_BODY = {
    "requestBody": {
        "required": True,
        "content": {
            "application/json": {
                "schema": OutcomeIn.model_json_schema(),
                "example": OutcomeIn.model_config["json_schema_extra"]["examples"][0],  # type: ignore[index]
            }
        },
    }
}


def _problems(*statuses: int) -> dict[int | str, dict[str, Any]]:
    return {
        s: {"model": Problem, "content": {PROBLEM_MEDIA_TYPE: {}}, "description": "Problem"}
        for s in statuses
    }


async def _outcome_body(request: Request) -> OutcomeIn:
    media = request.headers.get("content-type", "").split(";", 1)[0].strip().lower()
    if media != "application/json":
        raise UnsupportedMediaType("Send the outcome as `Content-Type: application/json`.")
    raw = await request.body()
    try:
        return OutcomeIn.from_json(raw)
    except MalformedJson as exc:
        raise MalformedBody(f"The request body is not valid JSON: {exc}") from exc
    except ValidationError as exc:
        raise RequestValidationError(
            [{**e, "loc": ("body", *e["loc"])} for e in exc.errors()]
        ) from exc


async def _write(
    request: Request, case_id: str, seat: Seat, caller: Caller, ctx: Any, mode: WriteMode
) -> JSONResponse:
    outcome = await _outcome_body(request)
    written = await run_in_threadpool(
        outcomes_service.write_outcome,
        ctx.sessions,
        case_id,
        seat,
        outcome,
        written_by=caller.name,
        mode=mode,
    )
    status = 201 if written.stored and written.corrected is None else 200
    return JSONResponse(
        written.outcome.model_dump(mode="json"),
        status_code=status,
        headers={
            "Location": f"/v1/cases/{case_id}/occupants/{seat.value}/outcome",
            "Idempotent-Replayed": "false" if written.stored else "true",
        },
    )


_WRITE_RESPONSES: dict[int | str, dict[str, Any]] = {
    200: {"model": OutcomeOut, "description": "Replay (same content) or a correction stored."},
    201: {"model": OutcomeOut, "description": "The occupant's first outcome, stored."},
    **_problems(400, 401, 403, 404, 409, 415, 422, 503),
}


@router.post(
    "/v1/cases/{case_id}/occupants/{seat}/outcome",
    status_code=201,
    summary="Link an occupant's outcome",
    response_model=OutcomeOut,
    responses=_WRITE_RESPONSES,
    openapi_extra=_BODY,
)
async def create_outcome(
    request: Request, case_id: CaseId, seat: SeatPath, caller: require_registry, ctx: ContextDep
) -> JSONResponse:
    """The first outcome of a stored occupant (registry or admin key).

    The same content again is a replay (200, `Idempotent-Replayed: true`, nothing
    stored); other content where an outcome is stored is 409: a correction is a PUT.
    An unknown case is 404, a seat the case had no occupant in 422, an ISS out of
    0-75 or one that cannot occur 422, each naming its field.
    """
    return await _write(request, case_id, seat, caller, ctx, "create")


@router.put(
    "/v1/cases/{case_id}/occupants/{seat}/outcome",
    summary="Write or correct an occupant's outcome",
    response_model=OutcomeOut,
    responses=_WRITE_RESPONSES,
    openapi_extra=_BODY,
)
async def put_outcome(
    request: Request, case_id: CaseId, seat: SeatPath, caller: require_registry, ctx: ContextDep
) -> JSONResponse:
    """The occupant's current outcome (registry or admin key): 201 when it is the first,
    200 when it corrects the current one (a new revision; the old one stays in the
    history) or repeats it (nothing stored)."""
    return await _write(request, case_id, seat, caller, ctx, "put")


@router.get(
    "/v1/cases/{case_id}/occupants/{seat}/outcome",
    summary="Read an occupant's outcome and its history",
    response_model=OutcomeRecord,
    responses=_problems(401, 403, 404, 422),
)
def read_outcome(
    case_id: CaseId, seat: SeatPath, caller: require_auditor, ctx: ContextDep
) -> OutcomeRecord:
    """The current outcome and every revision, with who wrote each and when."""
    return outcomes_service.read_outcome(ctx.sessions, case_id, seat)


@router.get(
    "/v1/quality",
    summary="Triage quality against linked outcomes",
    response_model=QualityReport,
    responses=_problems(401, 403, 422),
)
def read_quality(
    caller: require_auditor,
    ctx: ContextDep,
    received_from: Annotated[
        Rfc3339Text | None, Query(description="Only cases received at or after this time.")
    ] = None,
    received_before: Annotated[
        Rfc3339Text | None, Query(description="Only cases received before this time.")
    ] = None,
    crash_mode: Annotated[
        str | None,
        Query(
            pattern="^(" + "|".join(CRASH_MODES) + ")$",
            description="Only occupants in this crash mode (the field model's: "
            + ", ".join(CRASH_MODES)
            + ").",
        ),
    ] = None,
    age_group: Annotated[
        str | None,
        Query(
            pattern="^(" + "|".join(AGE_GROUPS) + ")$",
            description="Only occupants of this age group (children apart: "
            + ", ".join(AGE_GROUPS)
            + "; `child` is every child under 16).",
        ),
    ] = None,
    seat_row: Annotated[int | None, Query(ge=1, le=3, description="Only this seat row.")] = None,
) -> QualityReport:
    """Under-triage and both over-triage definitions with Wilson intervals and counts,
    calibration by decile, per month, operating point and tier, over linked occupants
    only; and the drift alarm."""
    filters = QualityFilters(
        received_from=received_from,
        received_before=received_before,
        crash_mode=crash_mode,
        age_group=age_group,
        seat_row=seat_row,
    )
    return quality_service.quality_report(
        ctx.sessions, filters, drift=quality_service.drift_settings_of(ctx.settings)
    )
