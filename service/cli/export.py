"""The command ``aacn-triage cases export --nemsis`` (``service.nemsis.export`` does the work).

Registered by the command line with :func:`add_parser`; this module imports nothing
heavy, so that the command line starts fast whatever the command.
"""

from __future__ import annotations

import argparse
import sys
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the command line imports this module: nothing heavy at run time
    from sqlalchemy.orm import Session, sessionmaker

    from service.nemsis.export import ExportSummary
    from service.nemsis.mapping import Agency

__all__ = ["add_parser"]


def _since(text: str) -> datetime:
    at = datetime.fromisoformat(text)
    if at.tzinfo is None:
        raise argparse.ArgumentTypeError(f"{text!r} has no UTC offset (e.g. 2026-11-23T00:00Z)")
    return at


def _export(
    args: argparse.Namespace, sessions: sessionmaker[Session], agency: Agency
) -> ExportSummary:
    """Run the export with a progress bar on standard error."""
    from tqdm import tqdm

    from service.nemsis.export import export_records

    with tqdm(desc="NEMSIS records", unit="case", file=sys.stderr) as bar:

        def set_total(n: int) -> None:
            bar.total = n
            bar.refresh()

        return export_records(
            sessions,
            agency,
            Path(args.out),
            since=args.since,
            resume=args.resume,
            progress=bar.update,
            total=set_total,
        )


def _run(args: argparse.Namespace) -> int:
    from service.cli.common import load_settings, open_sessions
    from service.nemsis.service import AgencyMissing, NemsisSchemaUnavailable, agency_from

    def say(text: str) -> None:
        sys.stderr.write(text + "\n")

    if not args.nemsis:
        say("error: name the format of the records: --nemsis (NEMSIS v3.5.1 EMSDataSet)")
        return 2
    settings = load_settings()
    try:
        agency = agency_from(
            settings,
            state_id=args.agency_state_id,
            number=args.agency_number,
            state=args.agency_state,
        )
    except AgencyMissing as exc:
        flags = ", ".join("--" + (e.field.replace("_", "-")) for e in exc.errors or [])
        say(f"error: {exc.detail} ({flags})")
        return 2
    try:
        with open_sessions() as sessions:
            summary = _export(args, sessions, agency)
    except NemsisSchemaUnavailable as exc:
        say(f"error: {exc.detail}")
        return 1
    say(
        f"{summary.cases} cases: {summary.written} records written, {summary.kept} kept from "
        f"an earlier run, {len(summary.refused)} refused; in {args.out}"
    )
    for case_id, reason in summary.refused:
        say(f"refused: {case_id}: {reason}")
    return 1 if summary.refused else 0


def add_parser(cases_sub: Any) -> None:
    """Register ``cases export`` under the ``cases`` command's subparsers."""
    export = cases_sub.add_parser(
        "export",
        help="write the stored cases as NEMSIS v3.5.1 records (progress; --resume)",
    )
    export.add_argument(
        "--nemsis", action="store_true", help="NEMSIS v3.5.1 EMSDataSet XML (the format)"
    )
    export.add_argument(
        "--since", type=_since, help="only cases received at or after this time (RFC 3339)"
    )
    export.add_argument("--out", required=True, help="directory of the records")
    export.add_argument(
        "--resume", action="store_true", help="keep the records OUT has and continue"
    )
    for flag, text in (
        ("--agency-state-id", "dAgency.01 (default AACN_NEMSIS_AGENCY_STATE_ID)"),
        ("--agency-number", "dAgency.02 (default AACN_NEMSIS_AGENCY_NUMBER)"),
        ("--agency-state", "dAgency.04, two digits (default AACN_NEMSIS_AGENCY_STATE)"),
    ):
        export.add_argument(flag, help=f"the receiving EMS agency: {text}")
    export.set_defaults(func=_run)
