"""``GET /v1/cases/{case_id}/nemsis``: a case as a NEMSIS v3.5.1 EMSDataSet (XML).

Authenticated by an API key (``Authorization: Bearer``) or by the case pages'
signed-in session cookie, so that the case page can link to the record; who may
read which record is :mod:`service.nemsis.service`'s.
"""

from __future__ import annotations

import time
from typing import Annotated, Any, Final

from fastapi import APIRouter, Depends, Path, Query, Request
from fastapi.responses import Response
from fastapi.security import HTTPAuthorizationCredentials

from service.auth import Caller, authenticate, bearer_scheme, caller_for_key_id
from service.browser_session import SESSION_COOKIE, read_session
from service.browser_session_end import session_has_ended
from service.deps import ContextDep
from service.nemsis.mapping import NemsisRecord
from service.nemsis.service import record_for
from service.problems import PROBLEM_MEDIA_TYPE, Problem

__all__ = ["LEFT_OUT_HEADER", "NEMSIS_MEDIA_TYPE", "PLACEHOLDERS_HEADER", "router"]

router = APIRouter(prefix="/v1/cases", tags=["cases"])

#: The media type of the answer (NEMSIS defines none of its own).
NEMSIS_MEDIA_TYPE: Final = "application/xml"
#: Header listing the elements left out of some report of the record (unknown to the case).
LEFT_OUT_HEADER: Final = "NEMSIS-Left-Out"
#: Header listing the elements that carry placeholders (NEMSIS allows them no not-value).
PLACEHOLDERS_HEADER: Final = "NEMSIS-Placeholders"

#: An abridged record, for the OpenAPI document.
EXAMPLE_XML: Final = """<?xml version='1.0' encoding='UTF-8'?>
<EMSDataSet xmlns="http://www.nemsis.org" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">
  <Header>
    <DemographicGroup>
      <dAgency.01>C034</dAgency.01><dAgency.02>351-C034P2</dAgency.02><dAgency.04>09</dAgency.04>
    </DemographicGroup>
    <PatientCareReport UUID="4c1f3b9e-8a57-5c0e-9d62-1b7f0e2a9c44">
      <!-- aacn-triage 0.1.0: case ..., occupant 1 of 1 (seat driver). Filled from the case: ...
       Left out (not known, never guessed): ... Placeholders: ... -->
      <!-- eRecord, eResponse, eDispatch, eTimes, ePatient, ePayment, eScene, eSituation -->
      <eInjury>
        <eInjury.01 NV="7701003" xsi:nil="true"/>
        <eInjury.03 NV="7701003" xsi:nil="true"/>
        <eInjury.04>2904013</eInjury.04>
        <eInjury.08>2908001</eInjury.08>
        <eInjury.CollisionGroup>
          <eInjury.12>tsp-7d1c2a90-0001</eInjury.12>
          <eInjury.14>2026-11-23T08:15:30+00:00</eInjury.14>
          <eInjury.21>9923001</eInjury.21>
          <eInjury.22 VelocityUnit="9921001" DeltaVelocityOrdinal="1">56</eInjury.22>
          <eInjury.23>9923003</eInjury.23>
          <eInjury.24>12</eInjury.24>
          <eInjury.25>N</eInjury.25>
          <eInjury.SeatGroup>
            <eInjury.26>2926001</eInjury.26><eInjury.27>Y</eInjury.27>
            <eInjury.28>Y</eInjury.28><eInjury.29>Y</eInjury.29>
          </eInjury.SeatGroup>
        </eInjury.CollisionGroup>
      </eInjury>
      <!-- eArrest ... eOutcome: NV 7701003 (Not Recorded) -->
    </PatientCareReport>
  </Header>
</EMSDataSet>
"""

CaseId = Annotated[str, Path(description="Case id (UUID).", max_length=64)]
_AGENCY_TEXT = r"^[\x20-\x7e]+$"


def _caller(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(bearer_scheme)],
) -> Caller:
    """An API key's caller, or the signed-in case pages' (their session cookie).

    The cookie is taken as the pages take it: signed, not expired, not signed out
    (``service.browser_session_end``), its key active and not rotated since; else the
    Bearer key is asked for.
    """
    if credentials is None and SESSION_COOKIE in request.cookies:
        ctx = request.app.state.ctx
        session = read_session(
            ctx.session_secret, request.cookies.get(SESSION_COOKIE), now=time.time()
        )
        if session is not None and not session_has_ended(ctx.sessions, session):
            caller = caller_for_key_id(ctx.sessions, session.key_id, session.key_tag)
            if caller is not None:
                return caller
    return authenticate(request, credentials)


def _problems(*statuses: int) -> dict[int | str, dict[str, Any]]:
    return {
        s: {"model": Problem, "content": {PROBLEM_MEDIA_TYPE: {}}, "description": "Problem"}
        for s in statuses
    }


def _header_list(names: list[str] | tuple[str, ...]) -> str:
    return ", ".join(names) if names else "none"


@router.get(
    "/{case_id}/nemsis",
    summary="The case as a NEMSIS v3.5.1 EMS record (XML)",
    response_class=Response,
    responses={
        200: {
            "description": "An `EMSDataSet` (NEMSIS v3.5.1), valid against the official "
            "XSDs, one `PatientCareReport` per occupant.",
            "content": {NEMSIS_MEDIA_TYPE: {"schema": {"type": "string"}, "example": EXAMPLE_XML}},
            "headers": {
                LEFT_OUT_HEADER: {
                    "description": "Elements left out of some report because the case does "
                    "not know them (comma-separated; `none`); each report's XML comment says "
                    "why, occupant by occupant.",
                    "schema": {"type": "string"},
                },
                PLACEHOLDERS_HEADER: {
                    "description": "Elements NEMSIS makes mandatory without a not-value that "
                    "a crash notification cannot know (the EMS unit's own response): they hold "
                    "documented placeholders for the receiving agency's record to replace.",
                    "schema": {"type": "string"},
                },
            },
        },
        **_problems(401, 403, 404, 422, 503),
    },
)
def read_nemsis_record(
    case_id: CaseId,
    caller: Annotated[Caller, Depends(_caller)],
    ctx: ContextDep,
    agency_state_id: Annotated[
        str | None,
        Query(
            min_length=1,
            max_length=50,
            pattern=_AGENCY_TEXT,
            description="dAgency.01, the receiving EMS agency's unique state ID (default "
            "`AACN_NEMSIS_AGENCY_STATE_ID`).",
        ),
    ] = None,
    agency_number: Annotated[
        str | None,
        Query(
            min_length=1,
            max_length=15,
            pattern=_AGENCY_TEXT,
            description="dAgency.02 and eResponse.01, the receiving EMS agency's number "
            "(default `AACN_NEMSIS_AGENCY_NUMBER`).",
        ),
    ] = None,
    agency_state: Annotated[
        str | None,
        Query(
            pattern=r"^[0-9]{2}$",
            description="dAgency.04, the two-digit ANSI code of the state that assigned the "
            "agency number (default `AACN_NEMSIS_AGENCY_STATE`).",
        ),
    ] = None,
) -> Response:
    """The case handed to an EMS agency: a NEMSIS v3.5.1 `EMSDataSet` document.

    One `PatientCareReport` per occupant: the ACN elements eInjury.11-.29 from the
    crash (delta-V in km/h, `VelocityUnit` 9921001; PDOF as a clock hour; seats
    2926xxx with belt and airbag), eInjury.23 and eInjury.04 (2904013, "vehicle
    telemetry data consistent with severe injury") from the occupant's decision;
    every other required element NV 7701003 "Not Recorded", except the few NEMSIS
    allows no not-value (the EMS unit's own response), which hold documented
    placeholders (`NEMSIS-Placeholders`). A fact the case does not hold is left out,
    never guessed (`NEMSIS-Left-Out`; each report's XML comment says why). The
    document is validated against the shipped NEMSIS XSDs before it is answered.

    Auditors and admins read any case's record; a submitter the records of its own
    cases (another client's case is 404). The receiving agency (mandatory in
    NEMSIS) comes from the query, else the `AACN_NEMSIS_AGENCY_*` settings; missing,
    422 naming the parameter.
    """
    record = record_for(
        ctx,
        case_id,
        caller,
        agency_state_id=agency_state_id,
        agency_number=agency_number,
        agency_state=agency_state,
    )
    return xml_response(record)


def xml_response(record: NemsisRecord) -> Response:
    """The record as the HTTP answer, with its report headers."""
    return Response(
        record.document,
        media_type=NEMSIS_MEDIA_TYPE,
        headers={
            LEFT_OUT_HEADER: _header_list(record.report.left_out_elements()),
            PLACEHOLDERS_HEADER: _header_list(record.report.placeholders),
            "Content-Disposition": f'inline; filename="nemsis-{record.case_id}.xml"',
        },
    )
