"""The NEMSIS record use case: who may read a case's record; build it; validate it.

Access (``docs/api.md``):

- auditors and admins: the record of any case (as they read any case);
- submitters: the records of the cases their own key submitted (the call center
  hands its own cases to EMS; it received their answers when it posted them). Another
  client's case is 404, word for word as an unknown one, so that ids are not probed;
- metrics keys: 403.

Every record is validated against the shipped XSDs before it is answered or written;
one that fails is never handed out: :class:`NemsisRecordInvalid` is a 422 problem
naming each element and the schema's reason (and is logged: it is a defect of the
mapping, which the tests exclude for every kind of case they know).
"""

from __future__ import annotations

import logging
from typing import Final

from lxml import etree

from service.auth import Caller, Role
from service.cases import service as cases_service
from service.cases.result import StoredCase
from service.context import ServiceContext
from service.nemsis.mapping import Agency, NemsisRecord, build_record
from service.nemsis.validate import validate
from service.problems import DomainError, FieldError, Forbidden, NotFound
from service.settings import Settings

__all__ = [
    "READERS",
    "AgencyMissing",
    "NemsisRecordInvalid",
    "NemsisSchemaUnavailable",
    "agency_from",
    "checked_record",
    "record_for",
]

log = logging.getLogger("aacn_triage.nemsis")

#: Roles that may read NEMSIS records (submitters: their own cases only).
READERS: Final = frozenset({Role.AUDITOR, Role.ADMIN, Role.SUBMITTER})


class AgencyMissing(DomainError):
    """The receiving agency's identity is missing or not what NEMSIS takes."""

    status, slug, title = 422, "validation", "Invalid request"


class NemsisSchemaUnavailable(DomainError):
    """The shipped NEMSIS schemas cannot be read (an install without its package data)."""

    status, slug, title = 503, "nemsis-schema-unavailable", "NEMSIS schemas unavailable"


class NemsisRecordInvalid(DomainError):
    """The case's record would not validate against the NEMSIS schema: not handed out."""

    status, slug, title = 422, "nemsis-invalid", "The NEMSIS record would not be valid"


#: Query parameter and setting of each agency field.
_AGENCY_FIELDS: Final = (
    ("state_id", "agency_state_id", "AACN_NEMSIS_AGENCY_STATE_ID"),
    ("number", "agency_number", "AACN_NEMSIS_AGENCY_NUMBER"),
    ("state", "agency_state", "AACN_NEMSIS_AGENCY_STATE"),
)


def agency_from(
    settings: Settings,
    *,
    state_id: str | None = None,
    number: str | None = None,
    state: str | None = None,
) -> Agency:
    """The receiving agency: each field as given, else the setting.

    Raises
    ------
    AgencyMissing
        A field neither given nor set, or one NEMSIS would refuse (422 naming the
        query parameter).
    """
    given = {
        "state_id": state_id or settings.nemsis_agency_state_id,
        "number": number or settings.nemsis_agency_number,
        "state": state or settings.nemsis_agency_state,
    }
    errors = [
        FieldError(
            field=param,
            reason=f"the receiving EMS agency's {attr.replace('_', ' ')} is mandatory in NEMSIS "
            f"(dAgency); give it, or set {env}",
            type="missing",
        )
        for attr, param, env in _AGENCY_FIELDS
        if not given[attr]
    ]
    if not errors:
        agency = Agency(**{k: str(v) for k, v in given.items()})
        params = {attr: param for attr, param, _ in _AGENCY_FIELDS}
        errors = [
            FieldError(field=params[attr], reason=reason, type="value_error")
            for attr, reason in agency.problems()
        ]
        if not errors:
            return agency
    raise AgencyMissing(
        "NEMSIS makes the receiving EMS agency's identity mandatory: "
        + ", ".join(e.field for e in errors)
        + ".",
        errors=errors,
    )


def checked_record(case: StoredCase, agency: Agency) -> NemsisRecord:
    """The case's record, validated against the shipped XSDs.

    Raises
    ------
    NemsisRecordInvalid
        It does not validate (each violation named; nothing is handed out).
    NemsisSchemaUnavailable
        The shipped schemas cannot be read (503).
    """
    record = build_record(case, agency)
    try:
        errors = validate(record.document)
    except (OSError, etree.XMLSchemaParseError) as exc:
        log.error("the NEMSIS schemas cannot be read: %s", exc)
        raise NemsisSchemaUnavailable(
            "The NEMSIS schemas shipped with the service cannot be read, so no record is "
            "handed out unvalidated; the operator must reinstall the service."
        ) from exc
    if errors:
        log.error(
            "NEMSIS record of case %s fails the schema: %s",
            case.case_id,
            "; ".join(f"{e.element}: {e.message}" for e in errors),
        )
        raise NemsisRecordInvalid(
            f"The NEMSIS record of case {case.case_id} does not validate against the "
            "NEMSIS v3.5.1 schema, so it is not handed out; the failure is logged.",
            errors=[
                FieldError(field=e.element or f"line {e.line}", reason=e.message, type="xsd")
                for e in errors
            ],
        )
    return record


def record_for(
    ctx: ServiceContext,
    case_id: str,
    caller: Caller,
    *,
    agency_state_id: str | None = None,
    agency_number: str | None = None,
    agency_state: str | None = None,
) -> NemsisRecord:
    """The NEMSIS record of a case the caller may read (module docstring).

    The caller's role is checked first, then the receiving agency (given, else the
    settings: :func:`agency_from`), then the case.

    Raises
    ------
    Forbidden
        The caller's role reads no records.
    AgencyMissing
    NotFound
        No such case, or (a submitter) another client's case.
    NemsisRecordInvalid
    """
    if caller.role not in READERS:
        raise Forbidden(
            f"The key {caller.name!r} has role {caller.role.value!r}; NEMSIS records need "
            "auditor or admin, or the submitter of the case."
        )
    agency = agency_from(
        ctx.settings, state_id=agency_state_id, number=agency_number, state=agency_state
    )
    case = cases_service.get_case(ctx, case_id)
    if caller.role is Role.SUBMITTER and case.client_name != caller.name:
        raise NotFound(f"No case with id {case_id!r}.")
    return checked_record(case, agency)
