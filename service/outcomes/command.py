"""The command ``aacn-triage outcomes import FILE.csv [--dry-run]``.

Registered by the command line with :func:`add_parser`; the work is
:func:`service.outcomes.importer.import_outcomes`. Exit status: 0 imported (or a dry
run found every line good), 1 lines refused (nothing written), 2 the file cannot be
read as an extract.
"""

from __future__ import annotations

import argparse
import getpass
import sys
from pathlib import Path
from typing import Any

__all__ = ["add_parser"]


def _say(text: str, *, err: bool = False) -> None:
    stream = sys.stderr if err else sys.stdout
    stream.write(text + "\n")
    stream.flush()


def _run(args: argparse.Namespace) -> int:
    from service.db import migrate
    from service.db.session import make_engine, make_sessionmaker
    from service.outcomes.importer import ImportFileError, import_outcomes
    from service.settings import get_settings

    settings = get_settings()
    path = Path(args.file)
    if not path.is_file():
        _say(f"error: {path} is not a file", err=True)
        return 2
    if settings.auto_migrate:
        migrate.upgrade(settings.database_url)
    engine = make_engine(settings.database_url)
    by = args.by or f"{getpass.getuser()} (import of {path.name})"
    try:
        report = import_outcomes(
            make_sessionmaker(engine), path, written_by=by, dry_run=args.dry_run
        )
    except ImportFileError as exc:
        _say(f"error: {path}: {exc}; nothing imported", err=True)
        return 2
    finally:
        engine.dispose()
    for line, reason in report.refused:
        _say(f"{path.name}:{line}: refused: {reason}", err=True)
    counts = ", ".join(f"{n} {action}" for action, n in report.actions.items())
    if report.refused:
        _say(
            f"{len(report.refused)} of {report.lines} lines refused: nothing imported "
            "(a file is taken whole or not at all)",
            err=True,
        )
        return 1
    if args.dry_run:
        _say(f"dry run: {report.lines} lines good ({counts}); nothing written")
        return 0
    _say(f"imported {report.lines} lines ({counts}), written by {by!r}")
    return 0


def add_parser(sub: Any) -> None:
    """Add ``outcomes import`` to the command line's subcommands."""
    outcomes = sub.add_parser("outcomes", help="outcomes of stored occupants (registry links)")
    outcomes_sub = outcomes.add_subparsers(dest="outcomes_command", required=True)
    imp = outcomes_sub.add_parser(
        "import",
        help="import a registry extract (CSV keyed by case_id and seat, or by client, "
        "event_id and seat): taken whole, or not at all",
    )
    imp.add_argument("file", help="the CSV extract (service/outcomes/importer.py: the columns)")
    imp.add_argument(
        "--dry-run", action="store_true", help="check every line and report; write nothing"
    )
    imp.add_argument(
        "--by", help="who the audit trail names as the writer (default: this account and file)"
    )
    imp.set_defaults(func=_run)
