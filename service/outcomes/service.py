"""The outcome use cases: write an occupant's outcome (idempotent, append-only), read it.

Rules (``docs/api.md``, outcomes):

- an outcome belongs to a stored occupant, named by its case and seat; an unknown
  case is 404, a seat the case had no occupant in is 422, both naming the field;
- a write whose content equals the current revision's is a replay: nothing is
  stored, the current revision is answered;
- ``create`` (POST) refuses to replace an outcome of other content (409: a correction
  is a PUT); ``put`` (PUT) writes a new revision, the old ones kept: the history is
  the audit trail, each revision with who wrote it and when;
- bad input changes nothing (every check runs before the row is staged).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Literal

from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session, sessionmaker

from models.notification import Seat
from service.cases.service import canonical_sha256
from service.db import repository
from service.db.tables import Case, CaseOccupant, OccupantOutcome
from service.outcomes.schemas import OutcomeIn, OutcomeOut, OutcomeRecord
from service.problems import DomainError, FieldError, NotFound, UnprocessableNotification

__all__ = [
    "OutcomeConflict",
    "WriteMode",
    "Written",
    "occupant_of",
    "outcome_out",
    "read_outcome",
    "stage_outcome",
    "write_outcome",
]

WriteMode = Literal["create", "put"]


class OutcomeConflict(DomainError):
    """POST of an outcome where one of other content is stored: a correction is a PUT."""

    status, slug, title = 409, "outcome-conflict", "An outcome of other content is stored"


class InvalidOutcome(UnprocessableNotification):
    title = "Invalid outcome"


@dataclass(frozen=True)
class Written:
    """The revision a write left current, and whether the write stored a new row."""

    outcome: OutcomeOut
    stored: bool
    #: The previous current revision, when the write corrected one.
    corrected: int | None = None


def outcome_out(row: OccupantOutcome, *, current: bool = True) -> OutcomeOut:
    return OutcomeOut(
        case_id=row.case_id,
        seat=Seat(row.seat),
        revision=row.revision,
        current=current,
        iss=row.iss,
        mais=row.mais,
        died=row.died,
        disposition=row.disposition,
        source=row.source,
        recorded_at=row.recorded_at,
        weight=row.weight,
        written_by=row.written_by,
        written_at=row.written_at,
        channel="import" if row.channel == "import" else "api",
    )


def _unknown_case(case_id: str, field: str = "case_id") -> NotFound:
    return NotFound(
        f"No case with id {case_id!r}.",
        errors=[FieldError(field=field, reason="no stored case has this id", type="unknown_case")],
    )


def occupant_of(case: Case, seat: Seat, field: str = "seat") -> CaseOccupant:
    """The case's occupant in `seat`, or InvalidOutcome naming `field`."""
    for occupant in case.occupants:
        if occupant.seat == seat.value:
            return occupant
    seats = ", ".join(o.seat for o in case.occupants)
    raise InvalidOutcome(
        f"Case {case.id} had no occupant in seat {seat.value!r}.",
        errors=[
            FieldError(
                field=field,
                reason=f"the case had no occupant in this seat (its occupants' seats: {seats})",
                type="no_occupant",
            )
        ],
    )


def stage_outcome(
    session: Session,
    case: Case,
    seat: Seat,
    outcome: OutcomeIn,
    *,
    written_by: str,
    channel: Literal["api", "import"],
    mode: WriteMode,
    now: datetime,
) -> Written:
    """Check one outcome against its stored occupant and stage its row (no commit).

    Raises
    ------
    InvalidOutcome
        The seat had no occupant, or the fields disagree (each named).
    OutcomeConflict
        `mode` is ``create`` and an outcome of other content is current.
    """
    occupant = occupant_of(case, seat)
    problems = outcome.problems()
    if problems:
        raise InvalidOutcome(
            f"{len(problems)} field{'s' if len(problems) != 1 else ''} refused.", errors=problems
        )
    fingerprint = canonical_sha256(outcome.content())
    current = repository.current_outcome(session, case.id, occupant.position)
    if current is not None and current.content_sha256 == fingerprint:
        return Written(outcome=outcome_out(current), stored=False)
    if current is not None and mode == "create":
        raise OutcomeConflict(
            f"The occupant in seat {seat.value!r} of case {case.id} has an outcome of other "
            f"content (revision {current.revision}); send a correction with PUT."
        )
    content = outcome.content()
    row = repository.add_outcome(
        session,
        OccupantOutcome(
            case_id=case.id,
            position=occupant.position,
            seat=occupant.seat,
            revision=1 if current is None else current.revision + 1,
            iss=content["iss"],
            mais=outcome.mais,
            died=outcome.died,
            disposition=outcome.disposition,
            source=outcome.source,
            recorded_at=outcome.recorded_at,
            weight=float(outcome.weight),
            written_by=written_by,
            written_at=now,
            channel=channel,
            content_sha256=fingerprint,
        ),
    )
    return Written(
        outcome=outcome_out(row),
        stored=True,
        corrected=None if current is None else current.revision,
    )


def write_outcome(
    sessions: sessionmaker[Session],
    case_id: str,
    seat: Seat,
    outcome: OutcomeIn,
    *,
    written_by: str,
    mode: WriteMode,
    clock: Callable[[], datetime] = lambda: datetime.now(UTC),
) -> Written:
    """Write one occupant's outcome over the API (one transaction).

    Two writers racing for the same revision: the unique (case, position, revision)
    refuses the second, which is then decided again against the first's row (a
    replay if it wrote the same content).

    Raises
    ------
    NotFound
        No such case (naming ``case_id``).
    InvalidOutcome
    OutcomeConflict
    """
    for attempt in range(2):
        try:
            with sessions.begin() as session:
                case = repository.get_case(session, case_id)
                if case is None:
                    raise _unknown_case(case_id)
                return stage_outcome(
                    session,
                    case,
                    seat,
                    outcome,
                    written_by=written_by,
                    channel="api",
                    mode=mode,
                    now=clock(),
                )
        except IntegrityError:
            if attempt:
                raise
    raise AssertionError("unreachable")  # pragma: no cover


def read_outcome(sessions: sessionmaker[Session], case_id: str, seat: Seat) -> OutcomeRecord:
    """The occupant's current outcome and its history.

    Raises
    ------
    NotFound
        No such case, or no outcome written for the occupant.
    InvalidOutcome
        The case had no occupant in the seat.
    """
    with sessions() as session:
        case = repository.get_case(session, case_id)
        if case is None:
            raise _unknown_case(case_id)
        occupant = occupant_of(case, seat)
        rows = repository.outcome_history(session, case_id, occupant.position)
        if not rows:
            raise NotFound(
                f"No outcome has been written for seat {seat.value!r} of case {case_id}."
            )
        history = [outcome_out(r, current=r is rows[-1]) for r in rows]
    return OutcomeRecord(current=history[-1], history=history)
