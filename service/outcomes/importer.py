"""Bulk import of a registry extract (CSV): every line checked, the file taken whole or not.

Columns (header line, any order):

- the occupant: ``case_id`` and ``seat``, or ``client``, ``event_id`` and ``seat`` (an
  event id is unique only per client: ``client`` is the name of the key that posted it);
- the outcome: ``source``, ``recorded_at`` (RFC 3339 with offset), and optionally
  ``iss``, ``mais``, ``died`` (true/false, 1/0, yes/no), ``disposition`` and
  ``weight`` (a survey weight; 1 when absent or empty). An empty cell is "not known".

Each line is written as a PUT would write it (a replay when the content is current, a
correction otherwise), in one transaction: when any line is refused, none is written,
and every refused line is named with the reason. A dry run checks and reports the
same without writing.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Final, Literal

from pydantic import ValidationError
from sqlalchemy.orm import Session, sessionmaker

from models.notification import Seat
from service.db import repository
from service.db.tables import Case
from service.outcomes.schemas import OutcomeIn
from service.outcomes.service import stage_outcome
from service.problems import DomainError

__all__ = ["COLUMNS", "ImportFileError", "ImportReport", "import_outcomes"]

OUTCOME_COLUMNS: Final = ("iss", "mais", "died", "disposition", "source", "recorded_at", "weight")
KEY_COLUMNS: Final = ("case_id", "client", "event_id", "seat")
COLUMNS: Final = (*KEY_COLUMNS, *OUTCOME_COLUMNS)
_TRUE: Final = frozenset({"true", "1", "yes", "y"})
_FALSE: Final = frozenset({"false", "0", "no", "n"})
#: Largest extract read, bytes. [R] A year of a state registry's crash patients is tens of
#: thousands of lines of about 100 bytes; 64 MB leaves room and bounds the memory used.
MAX_FILE_BYTES: Final[int] = 64 * 1024 * 1024

Action = Literal["new", "correction", "unchanged"]


class ImportFileError(ValueError):
    """The file as a whole cannot be read as an extract (its header, its encoding, its size)."""


@dataclass
class ImportReport:
    """What an import did, or (dry run, or refused) would have done."""

    lines: int = 0
    actions: dict[Action, int] = field(
        default_factory=lambda: {"new": 0, "correction": 0, "unchanged": 0}
    )
    refused: list[tuple[int, str]] = field(default_factory=list)
    written: bool = False


def _header(fieldnames: Sequence[str] | None) -> None:
    if not fieldnames:
        raise ImportFileError("the file has no header line")
    names = [n.strip() for n in fieldnames]
    unknown = sorted(set(names) - set(COLUMNS))
    if unknown:
        raise ImportFileError(
            f"unknown column(s) {', '.join(unknown)}; the columns are {', '.join(COLUMNS)}"
        )
    if len(set(names)) != len(names):
        raise ImportFileError("a column is named twice in the header")
    missing = [c for c in ("seat", "source", "recorded_at") if c not in names]
    if "case_id" not in names and not {"client", "event_id"} <= set(names):
        missing.append("case_id (or client and event_id)")
    if missing:
        raise ImportFileError(f"missing column(s): {', '.join(missing)}")


def _cell_int(text: str, name: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise ValueError(f"{name}: {text!r} is not a whole number") from None


def _outcome(row: dict[str, str]) -> OutcomeIn:
    """The line's outcome (ValueError naming the column and the reason)."""
    given: dict[str, Any] = {}
    for name in OUTCOME_COLUMNS:
        text = (row.get(name) or "").strip()
        if not text:
            continue
        if name in ("iss", "mais"):
            given[name] = _cell_int(text, name)
        elif name == "died":
            if text.lower() not in _TRUE | _FALSE:
                raise ValueError(f"died: {text!r} is not true or false")
            given[name] = text.lower() in _TRUE
        elif name == "weight":
            try:
                given[name] = float(text)
            except ValueError:
                raise ValueError(f"weight: {text!r} is not a number") from None
        else:
            given[name] = text
    try:
        outcome = OutcomeIn.model_validate(given)
    except ValidationError as exc:
        raise ValueError(
            "; ".join(
                f"{'.'.join(str(p) for p in e['loc']) or 'line'}: "
                + str(e["msg"]).removeprefix("Value error, ")
                for e in exc.errors()
            )
        ) from None
    problems = outcome.problems()
    if problems:
        raise ValueError("; ".join(f"{p.field}: {p.reason}" for p in problems))
    return outcome


def _case(session: Session, row: dict[str, str]) -> Case:
    case_id = (row.get("case_id") or "").strip()
    if case_id:
        case = repository.get_case(session, case_id)
        if case is None:
            raise ValueError(f"case_id: no stored case {case_id!r}")
        return case
    client, event = (row.get("client") or "").strip(), (row.get("event_id") or "").strip()
    if not client or not event:
        raise ValueError("case_id, or client and event_id, must be given")
    case = repository.find_case_by_event(session, client, event)
    if case is None:
        raise ValueError(f"event_id: client {client!r} stored no case for event {event!r}")
    return case


def _seat(row: dict[str, str]) -> Seat:
    text = (row.get("seat") or "").strip()
    try:
        return Seat(text)
    except ValueError:
        raise ValueError(
            f"seat: {text!r} is not a seat ({', '.join(s.value for s in Seat)})"
        ) from None


def _read(path: Path) -> csv.DictReader[str]:
    if path.stat().st_size > MAX_FILE_BYTES:
        raise ImportFileError(f"the file is larger than {MAX_FILE_BYTES // 2**20} MB")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as exc:
        raise ImportFileError(f"the file is not UTF-8 text: {exc}") from exc
    reader = csv.DictReader(io.StringIO(text, newline=""))
    _header(reader.fieldnames)
    reader.fieldnames = [n.strip() for n in reader.fieldnames or []]
    return reader


def import_outcomes(
    sessions: sessionmaker[Session],
    path: Path,
    *,
    written_by: str,
    dry_run: bool = False,
    clock: Callable[[], datetime] = lambda: datetime.now(UTC),
) -> ImportReport:
    """Check every line of an extract and write them all in one transaction, or none.

    Raises
    ------
    ImportFileError
        The file cannot be read as an extract (nothing is written).
    """
    reader = _read(path)
    report = ImportReport()
    seen: dict[tuple[str, str], int] = {}
    now = clock()
    with sessions() as session:
        for row in reader:
            line = reader.line_num
            report.lines += 1
            if None in row:  # more cells than the header names
                report.refused.append((line, "more cells than the header has columns"))
                continue
            try:
                outcome = _outcome(row)
                case = _case(session, row)
                seat = _seat(row)
                first = seen.setdefault((case.id, seat.value), line)
                if first != line:
                    raise ValueError(f"names the same occupant as line {first}")
                written = stage_outcome(
                    session,
                    case,
                    seat,
                    outcome,
                    written_by=written_by,
                    channel="import",
                    mode="put",
                    now=now,
                )
            except (ValueError, DomainError) as exc:
                reason = str(exc)
                if isinstance(exc, DomainError) and exc.errors:
                    reason = "; ".join(f"{e.field}: {e.reason}" for e in exc.errors)
                report.refused.append((line, reason))
                continue
            action: Action = (
                "unchanged"
                if not written.stored
                else "correction"
                if written.corrected is not None
                else "new"
            )
            report.actions[action] += 1
        if report.refused or dry_run:
            session.rollback()
        else:
            session.commit()
            report.written = True
    return report
