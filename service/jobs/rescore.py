"""Model recall report: the stored cases whose decision another model version would change.

When a defect is found in a model (e.g. a field model fitted on mph read as
km/h), an operator must be able to say which past dispatch advice it
touched. :func:`rescore` runs every stored notification again, as it was
received, through the engine with another field model version, and compares
the case-level decision (the worst occupant's) with the one stored. The stored
records are only read, never altered: the audit trail keeps what was answered.

``aacn-triage cases rescore --model VERSION --out FILE.csv`` (an operator's
command: it needs the database, as ``keys`` does) prints the changed cases and
writes them as CSV.
"""

from __future__ import annotations

import csv
import json
from collections.abc import Callable, Iterator
from dataclasses import dataclass, fields
from datetime import datetime
from pathlib import Path
from typing import Any, Final

from pydantic import ValidationError
from sqlalchemy.orm import Session, sessionmaker

from models.triage import EngineModels
from service.cases.notification import CrashNotificationIn
from service.cases.result import CaseResult
from service.cases.service import evaluate
from service.db import repository
from service.db.tables import Case
from service.jsonbody import MalformedJson
from service.problems import DomainError

__all__ = ["RescoreReport", "RescoreRow", "rescore", "write_csv"]

#: Cases read from the store at a time. [R] Bounds memory on a large store
#: (a case with its result is a few kB) while keeping round trips few.
PAGE_SIZE: Final[int] = 200


@dataclass(frozen=True)
class RescoreRow:
    """One stored case against another model version (case level: the worst occupant).

    Attributes
    ----------
    case_id, event_id, client_name : str
    received_at : datetime
    old_model, new_model : str
        ``name@version`` of the model that decided, stored and now.
    old_probability, new_probability : float
        The case-level probability the decision was made on.
    old_threshold, new_threshold : float
    old_decision, new_decision : bool
        ISS15+ (trauma center) stored and under the other version.
    occupants_changed : str
        Positions (0-based, ``;``-separated) of the occupants whose decision changes.
    """

    case_id: str
    event_id: str
    client_name: str
    received_at: datetime
    old_model: str
    new_model: str
    old_probability: float
    new_probability: float
    old_threshold: float
    new_threshold: float
    old_decision: bool
    new_decision: bool
    occupants_changed: str

    @property
    def changed(self) -> bool:
        """The case-level decision differs."""
        return self.old_decision != self.new_decision


@dataclass(frozen=True)
class RescoreReport:
    """What a rescore found.

    Attributes
    ----------
    new_model : str
        ``name@version`` of the field model the cases were run with.
    cases : int
        Stored cases read.
    rows : tuple of RescoreRow
        Every case that could be run again, in (received_at, id) order.
    refused : tuple of (str, str)
        Case id and reason for stored notifications the engine refuses now.
    """

    new_model: str
    cases: int
    rows: tuple[RescoreRow, ...]
    refused: tuple[tuple[str, str], ...]

    @property
    def changed(self) -> tuple[RescoreRow, ...]:
        """The cases whose decision changes."""
        return tuple(r for r in self.rows if r.changed)

    @property
    def up(self) -> int:
        """Cases not flagged before and flagged now (missed trauma-center advice)."""
        return sum(1 for r in self.changed if r.new_decision)

    @property
    def down(self) -> int:
        """Cases flagged before and not now (over-triage that the new version withdraws)."""
        return sum(1 for r in self.changed if not r.new_decision)


def _stored_cases(sessions: sessionmaker[Session]) -> Iterator[Case]:
    """Every stored case, oldest first, a page at a time (keyset on received_at, id)."""
    after: tuple[datetime, str] | None = None
    while True:
        with sessions() as session:
            page = list(repository.cases_oldest_first(session, limit=PAGE_SIZE, after=after))
            session.expunge_all()
        if not page:
            return
        yield from page
        after = (page[-1].received_at, page[-1].id)


def _occupant_decisions(result: CaseResult) -> list[bool]:
    return [o.triage.iss15_plus for o in result.occupants]


def _row(case: Case, old: CaseResult, new: CaseResult) -> RescoreRow:
    before, after = _occupant_decisions(old), _occupant_decisions(new)
    moved = [str(i) for i, (a, b) in enumerate(zip(before, after, strict=True)) if a != b]
    return RescoreRow(
        case_id=case.id,
        event_id=case.event_id,
        client_name=case.client_name,
        received_at=case.received_at,
        old_model=old.triage.model,
        new_model=new.triage.model,
        old_probability=old.triage.probability,
        new_probability=new.triage.probability,
        old_threshold=old.triage.threshold,
        new_threshold=new.triage.threshold,
        old_decision=old.triage.iss15_plus,
        new_decision=new.triage.iss15_plus,
        occupants_changed=";".join(moved),
    )


def _notification(document: dict[str, Any]) -> CrashNotificationIn:
    """The stored notification validated as a request is (strict JSON mode)."""
    notification, _ = CrashNotificationIn.from_json(json.dumps(document))
    return notification


def rescore(
    sessions: sessionmaker[Session],
    models: EngineModels,
    *,
    progress: Callable[[int], None] | None = None,
) -> RescoreReport:
    """Run every stored case again with `models` and compare the decisions.

    Parameters
    ----------
    sessions : sessionmaker
        The audit store (read only: nothing is written).
    models : EngineModels
        With the field model version to compare against.
    progress : callable, optional
        Called with 1 after each case.

    Returns
    -------
    RescoreReport
    """
    if models.field is None:
        raise ValueError("rescore needs engine models with a field model")
    new_model = f"{models.field.name}@{models.field.version}"
    rows: list[RescoreRow] = []
    refused: list[tuple[str, str]] = []
    count = 0
    for case in _stored_cases(sessions):
        count += 1
        old = CaseResult.model_validate(case.result)
        try:
            new = evaluate(
                _notification(case.notification),
                models,
                case_id=case.id,
                received_at=case.received_at,
            )
        except (ValidationError, MalformedJson, DomainError) as exc:
            refused.append((case.id, str(exc).splitlines()[0]))
        else:
            rows.append(_row(case, old, new))
        if progress is not None:
            progress(1)
    return RescoreReport(new_model, count, tuple(rows), tuple(refused))


#: CSV columns, in order (the fields of :class:`RescoreRow`).
CSV_COLUMNS: Final[tuple[str, ...]] = tuple(f.name for f in fields(RescoreRow))


def write_csv(rows: tuple[RescoreRow, ...], path: Path) -> Path:
    """Write `rows` as CSV (header :data:`CSV_COLUMNS`, probabilities with 6 decimals)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="", encoding="utf-8") as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(CSV_COLUMNS)
        for r in rows:
            writer.writerow(
                [
                    r.case_id,
                    r.event_id,
                    r.client_name,
                    r.received_at.isoformat(),
                    r.old_model,
                    r.new_model,
                    f"{r.old_probability:.6f}",
                    f"{r.new_probability:.6f}",
                    f"{r.old_threshold:.6f}",
                    f"{r.new_threshold:.6f}",
                    str(r.old_decision).lower(),
                    str(r.new_decision).lower(),
                    r.occupants_changed,
                ]
            )
    return path
