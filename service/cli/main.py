"""The `aacn-triage` command line.

Commands::

    aacn-triage serve [--host H] [--port P] [--workers N]
    aacn-triage db upgrade [REV] | db downgrade REV | db current
    aacn-triage keys create --role submitter|auditor|admin|metrics|registry --name NAME
    aacn-triage keys list | keys revoke NAME|ID | keys rotate NAME|ID
    aacn-triage triage FILE.json
    aacn-triage triage --batch IN.jsonl|IN.parquet --out OUT.jsonl [--resume]
                       [--workers N | --scheduler tcp://HOST:8786] [--decision-only]
    aacn-triage simulate FILE.json [--plot OUT.png]
    aacn-triage build-surrogates [--family NAME] [--workers N] ...
    aacn-triage validate-surrogates [--n N] [--seed S] [--family NAME] ...
    aacn-triage baseline fit [--data CSV] [--out JSON]
    aacn-triage fit-field [--out DIR] [--artifact JSON] [--cache DIR] [--quick]
    aacn-triage fit-field-mais3 [--out DIR] [--artifact JSON] [--cache DIR]
    aacn-triage evaluate FILE [--labels LABELS] [--out DIR] [--operating-point NAME]
                         [--workers N | --scheduler tcp://HOST:8786]
    aacn-triage cases rescore --model VERSION [--out FILE.csv] [--operating-point NAME]
    aacn-triage cases export --nemsis --out DIR [--since TIME] [--resume] [--agency-...]
    aacn-triage outcomes import FILE.csv [--dry-run] [--by NAME]
    aacn-triage outcomes recalibrate --site NAME [--out-dir DIR] [--dry-run]

Layout: :mod:`service.cli.operate` (operator commands), :mod:`service.cli.research`
(hand-overs to the offline tools), :mod:`service.cli.common` (shared helpers); batch
work in :mod:`service.jobs`; ``cases export --nemsis`` in :mod:`service.cli.export`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from service.cli import export as nemsis_export
from service.cli import outcomes as outcomes_command
from service.cli.operate import cmd_cases, cmd_db, cmd_keys, cmd_serve, cmd_triage
from service.cli.research import (
    HANDED_OVER,
    cmd_baseline,
    cmd_evaluate,
    cmd_handed_over,
    cmd_simulate,
)

__all__ = ["build_parser", "main"]


_SCHEDULER_HELP = (
    "a Dask scheduler address (tcp://host:8786): run on that cluster instead of the local "
    "process pool (the dask extra; docs/deploy.md)"
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="aacn-triage", description="AACN occupant injury triage service and tools."
    )
    sub = parser.add_subparsers(dest="command", required=True)

    serve = sub.add_parser("serve", help="run the HTTP service")
    serve.add_argument("--host", help="bind address (default AACN_HOST or 127.0.0.1)")
    serve.add_argument("--port", type=int, help="port (default AACN_PORT or 8000)")
    serve.add_argument(
        "--workers", type=int, help="worker processes (default AACN_WORKERS or the CPU count)"
    )
    serve.set_defaults(func=cmd_serve)

    db = sub.add_parser("db", help="database migrations")
    db_sub = db.add_subparsers(dest="db_command", required=True)
    up = db_sub.add_parser("upgrade", help="migrate up (default: head)")
    up.add_argument("revision", nargs="?", default="head")
    down = db_sub.add_parser("downgrade", help="migrate down to REV (e.g. base)")
    down.add_argument("revision")
    db_sub.add_parser("current", help="print the current revision")
    db.set_defaults(func=cmd_db)

    keys = sub.add_parser("keys", help="API keys")
    keys_sub = keys.add_subparsers(dest="keys_command", required=True)
    create = keys_sub.add_parser("create", help="create a key and print it once")
    create.add_argument(
        "--role", required=True, choices=["submitter", "auditor", "admin", "metrics", "registry"]
    )
    create.add_argument("--name", required=True, help="client name, recorded with its cases")
    keys_sub.add_parser("list", help="list keys (ids, names, roles, prefixes)")
    revoke = keys_sub.add_parser("revoke", help="revoke a key (refused at once)")
    revoke.add_argument("key", help="the key's name or id")
    rotate = keys_sub.add_parser(
        "rotate", help="new secret for a key (same name and role); the old one is refused at once"
    )
    rotate.add_argument("key", help="the key's name or id")
    keys.set_defaults(func=cmd_keys)

    tri = sub.add_parser("triage", help="triage notifications offline (no server, no database)")
    tri.add_argument("file", nargs="?", help="one notification (JSON)")
    tri.add_argument(
        "--batch", help="JSON Lines input, one notification per line (or Parquet: docs/deploy.md)"
    )
    tri.add_argument("--out", help="JSON Lines output (with --batch)")
    tri.add_argument("--resume", action="store_true", help="keep OUT's lines and continue")
    tri.add_argument("--workers", type=int, help="processes for --batch (default: the CPU count)")
    tri.add_argument("--scheduler", help=_SCHEDULER_HELP)
    tri.add_argument(
        "--reproducible",
        action="store_true",
        help="answers hold nothing of the run: received_at is the crash's occurred_at and "
        "timings_ms is empty, so the same input gives the same bytes (pool or Dask)",
    )
    tri.add_argument(
        "--decision-only",
        action="store_true",
        help="the field risk model's decision only, for rescoring a fleet: the occupant "
        "models are not run (no explanation); the decision fields are a full run's",
    )
    tri.set_defaults(func=cmd_triage)

    sim = sub.add_parser("simulate", help="run the occupant models of one notification")
    sim.add_argument("file", help="one notification (JSON)")
    sim.add_argument("--plot", help="draw pulse, motion and measures to this image (PNG)")
    sim.set_defaults(func=cmd_simulate)

    ev = sub.add_parser(
        "evaluate",
        help="score the decision against real outcomes (AUC, calibration, triage rates)",
    )
    ev.add_argument(
        "file",
        help="JSON Lines of notifications, or a NASS-CDS CSV (MAIS calibration or 1997-2000 "
        "format, labelled by its own outcome column)",
    )
    ev.add_argument("--labels", help="CSV or JSON Lines with event_id and the outcome column")
    ev.add_argument(
        "--label-field", default="outcome", help="outcome column or field, 0/1 (default outcome)"
    )
    ev.add_argument("--weight-field", help="case weight column or field (survey weights)")
    ev.add_argument("--out", default="evaluation", help="report directory (default ./evaluation)")
    ev.add_argument("--operating-point", help="field model operating point (default: its own)")
    ev.add_argument("--workers", type=int, help="processes (default: the CPU count)")
    ev.add_argument("--scheduler", help=_SCHEDULER_HELP)
    ev.set_defaults(func=cmd_evaluate)

    cases = sub.add_parser("cases", help="stored cases (operator commands on the database)")
    cases_sub = cases.add_subparsers(dest="cases_command", required=True)
    resc = cases_sub.add_parser(
        "rescore",
        help="list the stored cases whose decision another field model version would change "
        "(model recall report; stored records are not altered)",
    )
    resc.add_argument("--model", required=True, help="field model version, e.g. 2.0.0")
    resc.add_argument(
        "--out", default="rescore.csv", help="CSV of the changed cases (default rescore.csv)"
    )
    resc.add_argument("--all", action="store_true", help="write every case to the CSV")
    resc.add_argument(
        "--operating-point", help="operating point (default AACN_OPERATING_POINT or the model's)"
    )
    cases.set_defaults(func=cmd_cases)
    nemsis_export.add_parser(cases_sub)  # cases export --nemsis (service/cli/export.py)
    outcomes_command.add_parser(sub)  # outcomes import|recalibrate (service/cli/outcomes.py)

    for command, (_, text) in HANDED_OVER.items():
        handed = sub.add_parser(command, help=text, add_help=False)
        handed.add_argument("args", nargs=argparse.REMAINDER, help="see --help")

    base = sub.add_parser("baseline", help="statistical baseline")
    base_sub = base.add_subparsers(dest="baseline_command", required=True)
    fit_cmd = base_sub.add_parser("fit", help="refit the logistic baseline on NASS-CDS")
    fit_cmd.add_argument("--data", help="CSV (default: the shipped NASS-CDS extract)")
    fit_cmd.add_argument("--out", help="artifact path (default: the shipped artifact)")
    fit_cmd.add_argument("--seed", type=int, default=0, help="seed of the cross-validation folds")
    fit_cmd.add_argument(
        "--fit-date", help="date to record (YYYY-MM-DD); the same date gives the same bytes"
    )
    base.set_defaults(func=cmd_baseline)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    raw = list(sys.argv[1:] if argv is None else argv)
    if raw[:1] and raw[0] in HANDED_OVER:
        return cmd_handed_over(raw[0], raw[1:])
    args = build_parser().parse_args(raw)
    return int(args.func(args))


if __name__ == "__main__":
    raise SystemExit(main())
