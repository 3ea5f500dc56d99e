"""The NEMSIS records of many stored cases (``aacn-triage cases export --nemsis``).

Each case received since a time (all, without ``--since``), oldest first, becomes
``OUT/<case_id>.xml`` (its EMSDataSet, validated as the API's) and
``OUT/<case_id>.json`` (its report: what was filled, left out, and the placeholders).
The files are written atomically (a temporary file renamed), the report first, so
a record that exists is complete. With ``--resume`` the cases whose record exists
are kept and skipped, so an interrupted export continues where it stopped; without
it every record is written again (the same bytes: records are deterministic). A
case whose record would not validate is refused, never written: ``OUT/<case_id>.error.json``
names the violations, and the command exits 1 after the others are written.
The stored cases are only read.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass
from datetime import datetime
from pathlib import Path
from typing import Final

from sqlalchemy.orm import Session, sessionmaker

from service.cases.result import StoredCase
from service.cases.service import stored_case
from service.db import repository
from service.nemsis.mapping import Agency, NemsisRecord
from service.nemsis.service import NemsisRecordInvalid, checked_record

__all__ = ["ExportSummary", "export_records"]

#: Cases read from the store at a time. [R] A case with its result is a few kB.
PAGE_SIZE: Final = 200


@dataclass(frozen=True)
class ExportSummary:
    """What an export did.

    Attributes
    ----------
    cases : int
        Stored cases received since the time asked for.
    written : int
        Records written by this run.
    kept : int
        Records found complete from an earlier run and kept (``resume``).
    refused : tuple of (str, str)
        Case id and reason of each case whose record would not validate.
    """

    cases: int
    written: int
    kept: int
    refused: tuple[tuple[str, str], ...]


def _write_atomic(path: Path, data: bytes) -> None:
    with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f".{path.name}.", delete=False) as fh:
        fh.write(data)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(fh.name, path)


def _report_json(record: NemsisRecord) -> bytes:
    report = record.report
    doc = {
        "case_id": record.case_id,
        "filled": [
            {"occupant": occupant, "element": element, "source": source}
            for occupant, element, source in report.filled
        ],
        "left_out": [asdict(o) for o in report.left_out],
        "placeholders": list(report.placeholders),
    }
    return (json.dumps(doc, indent=2) + "\n").encode("utf-8")


def _stored_cases(sessions: sessionmaker[Session], since: datetime | None) -> Iterator[StoredCase]:
    """Cases received at or after `since`, oldest first, a page at a time."""
    # keyset (received_at, id): ids are never empty, so ("", since) starts at `since`
    after = (since, "") if since is not None else None
    while True:
        with sessions() as session:
            page = repository.cases_oldest_first(session, limit=PAGE_SIZE, after=after)
            stored = [stored_case(c) for c in page]
        if not stored:
            return
        yield from stored
        last = page[-1]
        after = (last.received_at, last.id)


def export_records(
    sessions: sessionmaker[Session],
    agency: Agency,
    out: Path,
    *,
    since: datetime | None = None,
    resume: bool = False,
    progress: Callable[[int], object] | None = None,
    total: Callable[[int], object] | None = None,
) -> ExportSummary:
    """Write the NEMSIS record of every case received since `since` into `out`.

    Parameters
    ----------
    progress : callable, optional
        Called with 1 after each case (a progress bar's ``update``).
    total : callable, optional
        Called once with the number of cases, before the first.
    """
    out.mkdir(parents=True, exist_ok=True)
    with sessions() as session:
        count = repository.count_cases(session, received_from=since)
    if total is not None:
        total(count)
    written = kept = 0
    refused: list[tuple[str, str]] = []
    for case in _stored_cases(sessions, since):
        target = out / f"{case.case_id}.xml"
        if resume and target.exists():
            kept += 1
        else:
            try:
                record = checked_record(case, agency)
            except NemsisRecordInvalid as exc:
                errors = [e.model_dump() for e in exc.errors or []]
                error = {"case_id": case.case_id, "detail": exc.detail, "errors": errors}
                _write_atomic(out / f"{case.case_id}.error.json", json.dumps(error).encode())
                refused.append((case.case_id, exc.detail))
            else:
                _write_atomic(out / f"{case.case_id}.json", _report_json(record))
                _write_atomic(target, record.document)
                (out / f"{case.case_id}.error.json").unlink(missing_ok=True)
                written += 1
        if progress is not None:
            progress(1)
    return ExportSummary(cases=count, written=written, kept=kept, refused=tuple(refused))
