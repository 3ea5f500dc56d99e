"""Operator commands: serve, db, keys, cases (recall rescoring), triage (one file or a batch)."""

from __future__ import annotations

import argparse
import functools
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from service.cli.common import echo, load_settings, open_sessions
from service.jobs.batch import batch_record, evaluate_text, run_batch
from service.jobs.worker import models_for

if TYPE_CHECKING:
    from sqlalchemy.orm import Session, sessionmaker

__all__ = ["cmd_serve", "cmd_db", "cmd_keys", "cmd_cases", "cmd_triage"]


def cmd_serve(args: argparse.Namespace) -> int:
    """Serve HTTP with N worker processes (uvicorn's supervisor), each warmed before it
    accepts connections; SIGTERM lets in-flight requests finish, then exits. With more
    than one worker they share a table of requests in flight (`service.balance`). A
    store that cannot be reached does not stop the start: each worker says so once and
    migrates when it returns (`service.db.migrate.upgrade_or_wait`)."""
    from service.logs import configure_logging

    settings = load_settings()
    host = args.host or settings.host
    port = args.port or settings.port
    workers = args.workers or settings.workers or os.cpu_count() or 1
    configure_logging(settings.log_level)
    if workers > 1:  # one worker's start refuses it itself; several would be restarted
        from service.context import check_high_risk_threshold

        try:
            check_high_risk_threshold(settings)
        except ValueError as exc:
            echo(f"error: {exc}", err=True)
            return 2
    if settings.auto_migrate and workers > 1:  # once, before the workers start
        from sqlalchemy.exc import OperationalError

        from service.db import migrate

        try:
            migrate.upgrade(settings.database_url)
        except OperationalError:  # unreachable: each worker says so and migrates on its return
            pass
    loads_dir = None
    if workers > 1:
        # compile the kernels into the shared numba cache once, so that every worker
        # loads them instead of compiling them side by side
        from models.triage import warm_up
        from service.balance import LOADS_ENV, WorkerLoads

        warm_up()
        # the workers' shared table of requests in flight (service.balance)
        loads_dir = tempfile.mkdtemp(prefix="aacn-serve-")
        os.environ[LOADS_ENV] = str(WorkerLoads.create(Path(loads_dir) / "loads"))
        # one session secret for every worker of this start (service.session_secret)
        from service.session_secret import share_with_workers

        share_with_workers(settings, Path(loads_dir))
    try:
        _run_uvicorn(host, port, workers, settings)
    finally:
        if loads_dir is not None:
            shutil.rmtree(loads_dir, ignore_errors=True)
    return 0


def _run_uvicorn(host: str, port: int, workers: int, settings: Any) -> None:
    import uvicorn

    from service.logs import log_config

    uvicorn.run(
        "service.app:create_app",
        factory=True,
        host=host,
        port=port,
        workers=workers,
        log_level=settings.log_level.lower(),
        log_config=log_config(settings.log_level),
        proxy_headers=True,
        server_header=False,
        timeout_graceful_shutdown=settings.shutdown_timeout_s,
    )


def cmd_db(args: argparse.Namespace) -> int:
    from service.db import migrate

    url = load_settings().database_url
    if args.db_command == "upgrade":
        migrate.upgrade(url, args.revision)
    elif args.db_command == "downgrade":
        migrate.downgrade(url, args.revision)
    echo(f"database at revision {migrate.current_revision(url) or 'base'}")
    return 0


def cmd_keys(args: argparse.Namespace) -> int:
    with open_sessions() as sessions:
        return _keys(args, sessions)


def _keys(args: argparse.Namespace, sessions: sessionmaker[Session]) -> int:
    from service.auth import Role, create_api_key, revoke_api_key, rotate_api_key
    from service.db import repository

    if args.keys_command == "create":
        try:
            row, secret = create_api_key(sessions, name=args.name, role=Role(args.role))
        except ValueError as exc:
            echo(f"error: {exc}", err=True)
            return 1
        echo(f"created key {row.name!r} (role {row.role}); it is shown once:", err=True)
        echo(secret)
        return 0
    if args.keys_command in ("revoke", "rotate"):
        try:
            if args.keys_command == "revoke":
                row = revoke_api_key(sessions, args.key)
                echo(f"revoked key {row.name!r} (id {row.id}); refused from now on", err=True)
            else:
                row, secret = rotate_api_key(sessions, args.key)
                echo(
                    f"rotated key {row.name!r} (id {row.id}); the old secret is refused from "
                    "now on; the new one is shown once:",
                    err=True,
                )
                echo(secret)
        except LookupError as exc:
            echo(f"error: {exc}", err=True)
            return 1
        return 0
    with sessions() as session:
        for key in repository.list_api_keys(session):
            state = "revoked" if key.revoked_at else "active"
            echo(
                f"{key.id}\t{key.name}\t{key.role}\t{key.key_prefix}...\t{state}\t{key.created_at}"
            )
    return 0


def cmd_cases(args: argparse.Namespace) -> int:
    """``cases rescore``: the stored cases whose decision another field model would change."""
    from tqdm import tqdm

    from models.field.versions import artifact_for_version
    from service.context import engine_models_for
    from service.jobs.rescore import rescore, write_csv

    settings = load_settings()
    try:  # shipped, or this site's recalibrated models (outcomes recalibrate)
        artifact = artifact_for_version(args.model, (settings.local_model_dir,))
    except LookupError as exc:
        echo(f"error: {exc}", err=True)
        return 2
    # a recall may compare against a withdrawn version (that is what recalls are for)
    overrides: dict[str, Any] = {"field_artifact": artifact, "allow_withdrawn_field_model": True}
    if args.operating_point is not None:
        overrides["operating_point"] = args.operating_point
    try:
        models = engine_models_for(settings.model_copy(update=overrides))
    except ValueError as exc:
        echo(f"error: {exc}", err=True)
        return 2
    with (
        open_sessions() as sessions,
        tqdm(desc="cases rescored", unit="case", file=sys.stderr) as bar,
    ):
        report = rescore(sessions, models, progress=bar.update)
    changed = report.changed
    out = write_csv(report.rows if args.all else changed, Path(args.out))
    echo(
        "case_id\tevent_id\treceived_at\told_model\told_p\told_decision\tnew_model\tnew_p"
        "\tnew_decision"
    )
    for r in changed:
        echo(
            f"{r.case_id}\t{r.event_id}\t{r.received_at.isoformat()}\t{r.old_model}\t"
            f"{r.old_probability:.4f}\t{_decision(r.old_decision)}\t{r.new_model}\t"
            f"{r.new_probability:.4f}\t{_decision(r.new_decision)}"
        )
    echo(
        f"{report.cases} stored cases, {len(report.rows)} run again with {report.new_model}: "
        f"{len(changed)} decisions change ({report.up} to trauma center, {report.down} away "
        f"from it); {len(report.refused)} refused; stored records unchanged; CSV: {out}",
        err=True,
    )
    for case_id, reason in report.refused:
        echo(f"refused: {case_id}: {reason}", err=True)
    return 0


def _decision(flagged: bool) -> str:
    return "ISS15+" if flagged else "not ISS15+"


def cmd_triage(args: argparse.Namespace) -> int:
    if args.batch is not None and args.scheduler:  # on a Dask cluster (service.jobs.dask)
        return _run_batch_on_dask(args)

    settings = load_settings()
    try:
        models = models_for(settings, occupant_models=not args.decision_only)
    except ValueError as exc:
        echo(f"error: the models failed to load: {exc}", err=True)
        return 1
    if args.batch is None:
        if args.file is None:
            echo("error: give FILE.json or --batch IN.jsonl --out OUT.jsonl", err=True)
            return 2
        text = Path(args.file).read_text(encoding="utf-8")
        outcome = evaluate_text(
            text, models, reproducible=args.reproducible, decision_only=args.decision_only
        )
        if outcome.problem is not None:
            echo(json.dumps(outcome.problem, indent=2), err=True)
            return 1
        echo(json.dumps(outcome.result, indent=2))
        return 0
    if args.out is None:
        echo("error: --batch needs --out OUT.jsonl", err=True)
        return 2
    workers = args.workers or os.cpu_count() or 1
    return run_batch(
        Path(args.batch),
        Path(args.out),
        settings,
        resume=args.resume,
        workers=workers,
        reproducible=args.reproducible,
        decision_only=args.decision_only,
    )


def _run_batch_on_dask(args: argparse.Namespace) -> int:
    """`triage --batch` on the Dask cluster at ``--scheduler`` (service.jobs.dask)."""
    if args.out is None:
        echo("error: --batch needs --out OUT.jsonl", err=True)
        return 2
    try:
        from service.jobs.dask import triage_batch_on_dask

        evaluated, refused = triage_batch_on_dask(
            Path(args.batch),
            Path(args.out),
            scheduler=args.scheduler,
            settings=load_settings(),
            record=functools.partial(
                batch_record, reproducible=args.reproducible, decision_only=args.decision_only
            ),
            resume=args.resume,
        )
    except (RuntimeError, ValueError, OSError) as exc:
        echo(f"error: {exc}", err=True)
        return 1
    echo(
        f"{evaluated} evaluated on the Dask cluster at {args.scheduler}, {refused} refused; "
        f"results in {args.out}",
        err=True,
    )
    return 0
