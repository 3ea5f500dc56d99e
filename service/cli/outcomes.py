"""The commands ``aacn-triage outcomes import FILE.csv [--dry-run]`` and
``aacn-triage outcomes recalibrate --site NAME [--out-dir DIR] [--dry-run]``.

Registered by the command line with :func:`add_parser`. ``import``:
:func:`service.outcomes.importer.import_outcomes`; exit status 0 imported (or a dry
run found every line good), 1 lines refused (nothing written), 2 the file cannot be
read as an extract. ``recalibrate``: :func:`service.outcomes.recalibrate.recalibrate`;
exit status 0 written (or a dry run fitted), 1 refused (too few outcomes: the message
says how many are needed), 2 the served model or the site cannot be used.
"""

from __future__ import annotations

import argparse
import getpass
from pathlib import Path
from typing import Any

from service.cli.common import echo as _say
from service.cli.common import load_settings, open_sessions

__all__ = ["add_parser"]


def _run(args: argparse.Namespace) -> int:
    from service.outcomes.importer import ImportFileError, import_outcomes

    path = Path(args.file)
    if not path.is_file():
        _say(f"error: {path} is not a file", err=True)
        return 2
    by = args.by or f"{getpass.getuser()} (import of {path.name})"
    try:
        with open_sessions() as sessions:
            report = import_outcomes(sessions, path, written_by=by, dry_run=args.dry_run)
    except ImportFileError as exc:
        _say(f"error: {path}: {exc}; nothing imported", err=True)
        return 2
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


def _run_recalibrate(args: argparse.Namespace) -> int:
    from models.field.recalibration import SE_LOGIT_REQUIRED, TooFewOutcomes
    from models.field.risk_model import RiskModel, load_default
    from models.field.versions import load_field_artifact
    from service.outcomes.recalibrate import recalibrate

    settings = load_settings()
    try:
        served = (
            load_default()
            if settings.field_artifact is None
            else load_field_artifact(settings.field_artifact)
        )
    except (OSError, ValueError) as exc:
        _say(f"error: the served field model: {exc}", err=True)
        return 2
    if not isinstance(served, RiskModel):
        _say(f"error: {served.name} {served.version} is not an ISS 15+ risk model", err=True)
        return 2
    out_dir = Path(args.out_dir) if args.out_dir else settings.local_model_dir
    try:
        with open_sessions() as sessions:
            result = recalibrate(
                sessions,
                served,
                site=args.site,
                out_dir=out_dir,
                dry_run=args.dry_run,
                local_dirs=(settings.local_model_dir,),
                high_threshold=settings.high_risk_threshold,
                operating_point=settings.operating_point,
            )
    except TooFewOutcomes as exc:
        _say(f"refused: {exc}", err=True)
        return 1
    except ValueError as exc:
        _say(f"error: {exc}", err=True)
        return 2
    r, cv = result.recalibration, result.cross_validation
    _say(
        f"{result.version}: recalibrated {served.name} {result.served_version} on "
        f"{result.occupants} linked occupants of {result.cases} cases; {result.plan.reason}"
    )
    _say(
        f"logit P = {r.intercept:.4f} (SE {r.intercept_se:.4f}) + {r.slope:.4f} "
        f"(SE {r.slope_se:.4f}) logit P_served  [{r.method}]"
    )
    _say(
        f"cross-validation by crash ({cv.folds} folds): weighted predicted/observed "
        f"{cv.served_ratio:.3f} served -> {cv.recalibrated_ratio:.3f} recalibrated; log loss "
        f"{cv.served_log_loss:.5f} -> {cv.recalibrated_log_loss:.5f}"
    )
    if not cv.improves:
        _say("warning: held out, the recalibration does not lower the log loss", err=True)
    if r.intercept_se > SE_LOGIT_REQUIRED:
        _say(
            f"warning: the intercept's robust SE {r.intercept_se:.3f} exceeds the required "
            f"{SE_LOGIT_REQUIRED:.3f}: the outcomes cluster within cases, so they carry less "
            "than their count (docs/outcomes.md)",
            err=True,
        )
    for name, (before, after) in result.thresholds.items():
        _say(f"operating point {name}: threshold {before:.5f} -> {after:.5f} (same occupants)")
    if result.path is None:
        _say("dry run: nothing written")
    else:
        _say(
            f"wrote {result.path}; compare: aacn-triage cases rescore --model {result.version}; "
            f"serve: AACN_FIELD_ARTIFACT={result.path}"
        )
    return 0


def add_parser(sub: Any) -> None:
    """Add ``outcomes import`` and ``outcomes recalibrate`` to the subcommands."""
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
    rec = outcomes_sub.add_parser(
        "recalibrate",
        help="fit a logistic recalibration of the served field model on the linked local "
        "outcomes, check it by cross-validation by crash and write it as a new version",
    )
    rec.add_argument(
        "--site",
        required=True,
        help="this site's name in the new version (<version>+local.<site>.<n>): lower-case "
        "letters, digits, hyphens",
    )
    rec.add_argument("--out-dir", help="where to write the artifact (default AACN_LOCAL_MODEL_DIR)")
    rec.add_argument("--dry-run", action="store_true", help="fit and report; write nothing")
    rec.set_defaults(func=_run_recalibrate)
