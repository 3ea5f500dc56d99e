"""The `aacn-triage` command line.

Commands::

    aacn-triage serve [--host H] [--port P] [--workers N]
    aacn-triage db upgrade [REV] | db downgrade REV | db current
    aacn-triage keys create --role submitter|auditor|admin|metrics --name NAME
    aacn-triage keys list | keys revoke NAME|ID | keys rotate NAME|ID
    aacn-triage triage FILE.json
    aacn-triage triage --batch IN.jsonl|IN.parquet --out OUT.jsonl [--resume]
                       [--workers N | --scheduler tcp://HOST:8786]
    aacn-triage simulate FILE.json [--plot OUT.png]
    aacn-triage build-surrogates [--family NAME] [--workers N] ...
    aacn-triage validate-surrogates [--n N] [--seed S] [--family NAME] ...
    aacn-triage baseline fit [--data CSV] [--out JSON]
    aacn-triage fit-field [--out DIR] [--artifact JSON] [--cache DIR]
    aacn-triage evaluate FILE [--labels LABELS] [--out DIR] [--operating-point NAME]
                         [--workers N | --scheduler tcp://HOST:8786]
    aacn-triage cases rescore --model VERSION [--out FILE.csv] [--operating-point NAME]
"""

from __future__ import annotations

import argparse
import functools
import json
import os
import shutil
import sys
import tempfile
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from pydantic import ValidationError

__all__ = ["main"]


def _print(text: str, *, err: bool = False) -> None:
    stream = sys.stderr if err else sys.stdout
    stream.write(text + "\n")
    stream.flush()


def _settings() -> Any:
    from service.settings import get_settings

    return get_settings()


# ------------------------------------------------------------------- commands


def _cmd_serve(args: argparse.Namespace) -> int:
    """Serve HTTP with N worker processes (uvicorn's supervisor), each warmed before it
    accepts connections; SIGTERM lets in-flight requests finish, then exits. With more
    than one worker they share a table of requests in flight (`service.balance`)."""
    from service.logs import configure_logging

    settings = _settings()
    host = args.host or settings.host
    port = args.port or settings.port
    workers = args.workers or settings.workers or os.cpu_count() or 1
    configure_logging(settings.log_level)
    if settings.auto_migrate:  # once, before the workers start
        from service.db import migrate

        migrate.upgrade(settings.database_url)
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


def _cmd_db(args: argparse.Namespace) -> int:
    from service.db import migrate

    url = _settings().database_url
    if args.db_command == "upgrade":
        migrate.upgrade(url, args.revision)
    elif args.db_command == "downgrade":
        migrate.downgrade(url, args.revision)
    _print(f"database at revision {migrate.current_revision(url) or 'base'}")
    return 0


def _sessions() -> Any:
    from service.db import migrate
    from service.db.session import make_engine, make_sessionmaker

    settings = _settings()
    if settings.auto_migrate:
        migrate.upgrade(settings.database_url)
    return make_sessionmaker(make_engine(settings.database_url))


def _cmd_keys(args: argparse.Namespace) -> int:
    from service.auth import Role, create_api_key, revoke_api_key, rotate_api_key
    from service.db import repository

    sessions = _sessions()
    if args.keys_command == "create":
        try:
            row, secret = create_api_key(sessions, name=args.name, role=Role(args.role))
        except ValueError as exc:
            _print(f"error: {exc}", err=True)
            return 1
        _print(f"created key {row.name!r} (role {row.role}); it is shown once:", err=True)
        _print(secret)
        return 0
    if args.keys_command in ("revoke", "rotate"):
        try:
            if args.keys_command == "revoke":
                row = revoke_api_key(sessions, args.key)
                _print(f"revoked key {row.name!r} (id {row.id}); refused from now on", err=True)
            else:
                row, secret = rotate_api_key(sessions, args.key)
                _print(
                    f"rotated key {row.name!r} (id {row.id}); the old secret is refused from "
                    "now on; the new one is shown once:",
                    err=True,
                )
                _print(secret)
        except LookupError as exc:
            _print(f"error: {exc}", err=True)
            return 1
        return 0
    with sessions() as session:
        for key in repository.list_api_keys(session):
            state = "revoked" if key.revoked_at else "active"
            _print(
                f"{key.id}\t{key.name}\t{key.role}\t{key.key_prefix}...\t{state}\t{key.created_at}"
            )
    return 0


def _cmd_cases(args: argparse.Namespace) -> int:
    """``cases rescore``: the stored cases whose decision another field model would change."""
    from tqdm import tqdm

    from models.field.model import artifact_for_version
    from service.context import engine_models_for
    from service.jobs.rescore import rescore, write_csv

    try:
        artifact = artifact_for_version(args.model)
    except LookupError as exc:
        _print(f"error: {exc}", err=True)
        return 2
    settings = _settings()
    # a recall may compare against a withdrawn version (that is what recalls are for)
    overrides: dict[str, Any] = {"field_artifact": artifact, "allow_withdrawn_field_model": True}
    if args.operating_point is not None:
        overrides["operating_point"] = args.operating_point
    try:
        models = engine_models_for(settings.model_copy(update=overrides))
    except ValueError as exc:
        _print(f"error: {exc}", err=True)
        return 2
    sessions = _sessions()
    with tqdm(desc="cases rescored", unit="case", file=sys.stderr) as bar:
        report = rescore(sessions, models, progress=bar.update)
    changed = report.changed
    out = write_csv(report.rows if args.all else changed, Path(args.out))
    _print(
        "case_id\tevent_id\treceived_at\told_model\told_p\told_decision\tnew_model\tnew_p"
        "\tnew_decision"
    )
    for r in changed:
        _print(
            f"{r.case_id}\t{r.event_id}\t{r.received_at.isoformat()}\t{r.old_model}\t"
            f"{r.old_probability:.4f}\t{_decision(r.old_decision)}\t{r.new_model}\t"
            f"{r.new_probability:.4f}\t{_decision(r.new_decision)}"
        )
    _print(
        f"{report.cases} stored cases, {len(report.rows)} run again with {report.new_model}: "
        f"{len(changed)} decisions change ({report.up} to trauma center, {report.down} away "
        f"from it); {len(report.refused)} refused; stored records unchanged; CSV: {out}",
        err=True,
    )
    for case_id, reason in report.refused:
        _print(f"refused: {case_id}: {reason}", err=True)
    return 0


def _decision(flagged: bool) -> str:
    return "ISS15+" if flagged else "not ISS15+"


def _problem_from_validation(exc: ValidationError) -> dict[str, Any]:
    from fastapi.exceptions import RequestValidationError

    from service.problems import validation_errors

    errors = validation_errors(RequestValidationError(exc.errors()))
    return {
        "title": "Invalid notification",
        "status": 422,
        "errors": [e.model_dump() for e in errors],
    }


def _evaluate_text(text: str, models: Any, *, reproducible: bool = False) -> dict[str, Any]:
    """One notification (JSON text) -> {"result": ...} or {"error": problem}."""
    from service.cases.notification import CrashNotificationIn
    from service.cases.service import evaluate
    from service.jsonbody import MalformedJson
    from service.problems import DomainError

    try:
        notification, _ = CrashNotificationIn.from_json(text)
    except MalformedJson as exc:
        return {"error": {"title": "Malformed JSON", "status": 400, "detail": str(exc)}}
    except ValidationError as exc:
        return {"error": _problem_from_validation(exc)}
    try:
        received_at = notification.occurred_at if reproducible else datetime.now(UTC)
        result = evaluate(notification, models, case_id=None, received_at=received_at)
    except DomainError as exc:
        return {
            "error": {
                "title": exc.title,
                "status": exc.status,
                "detail": exc.detail,
                "errors": [e.model_dump() for e in exc.errors or []],
            }
        }
    if reproducible:  # nothing of the run itself: the same input gives the same bytes
        result = result.model_copy(update={"timings_ms": {}})
    return {"result": result.model_dump(mode="json")}


def _cmd_triage(args: argparse.Namespace) -> int:
    from service.context import engine_models_for

    if args.batch is not None and args.scheduler:  # on a Dask cluster (service.jobs.dask)
        return _run_batch_on_dask(args)

    try:
        models = engine_models_for(_settings())
    except ValueError as exc:
        _print(f"error: the models failed to load: {exc}", err=True)
        return 1
    if args.batch is None:
        if args.file is None:
            _print("error: give FILE.json or --batch IN.jsonl --out OUT.jsonl", err=True)
            return 2
        text = Path(args.file).read_text(encoding="utf-8")
        outcome = _evaluate_text(text, models, reproducible=args.reproducible)
        if "error" in outcome:
            _print(json.dumps(outcome["error"], indent=2), err=True)
            return 1
        _print(json.dumps(outcome["result"], indent=2))
        return 0
    if args.out is None:
        _print("error: --batch needs --out OUT.jsonl", err=True)
        return 2
    workers = args.workers or os.cpu_count() or 1
    return _run_batch(
        Path(args.batch),
        Path(args.out),
        models,
        resume=args.resume,
        workers=workers,
        reproducible=args.reproducible,
    )


#: The engine models of a batch worker process (loaded once by `_init_batch_worker`).
_BATCH_MODELS: Any = None
#: Lines handed to a batch worker at a time. [R] Big enough that the pool's IPC is
#: small beside ~10-50 ms of engine time per line, small enough to keep the bar live.
BATCH_CHUNK = 8


#: Whether the batch of this process is reproducible (`triage --reproducible`).
_BATCH_REPRODUCIBLE = False


def _init_batch_worker(reproducible: bool = False) -> None:
    global _BATCH_MODELS, _BATCH_REPRODUCIBLE
    from service.context import engine_models_for

    _BATCH_MODELS = engine_models_for(_settings())
    _BATCH_REPRODUCIBLE = reproducible


def _batch_line(item: tuple[int, str]) -> str:
    return _batch_record(*item, _BATCH_MODELS, reproducible=_BATCH_REPRODUCIBLE)


def _batch_record(number: int, text: str, models: Any, *, reproducible: bool = False) -> str:
    """One output line of a batch: the answer to input line `number`, or its error.

    With `reproducible`, ``received_at`` is the crash's time and there are no
    timings: an answer then holds nothing of the run that made it, so the same
    input and model versions give the same bytes on any machine, pool or cluster
    (a recall or a study can be re-run and compared with ``cmp``).
    """
    if not text.strip():
        record: dict[str, Any] = {"line": number, "error": {"title": "Empty line"}}
    else:
        record = {"line": number, **_evaluate_text(text, models, reproducible=reproducible)}
    return json.dumps(record, separators=(",", ":"))


def _run_batch_on_dask(args: argparse.Namespace) -> int:
    """`triage --batch` on the Dask cluster at ``--scheduler`` (service.jobs.dask)."""
    if args.out is None:
        _print("error: --batch needs --out OUT.jsonl", err=True)
        return 2
    try:
        from service.jobs.dask import triage_batch_on_dask

        evaluated, refused = triage_batch_on_dask(
            Path(args.batch),
            Path(args.out),
            scheduler=args.scheduler,
            settings=_settings(),
            record=functools.partial(_batch_record, reproducible=args.reproducible),
            resume=args.resume,
        )
    except (RuntimeError, ValueError, OSError) as exc:
        _print(f"error: {exc}", err=True)
        return 1
    _print(
        f"{evaluated} evaluated on the Dask cluster at {args.scheduler}, {refused} refused; "
        f"results in {args.out}",
        err=True,
    )
    return 0


def _run_batch(
    src: Path,
    out: Path,
    models: Any,
    *,
    resume: bool,
    workers: int = 1,
    reproducible: bool = False,
) -> int:
    """Evaluate a JSONL file into OUT (one line per input line, in order).

    With `workers` > 1 the lines are triaged by a pool of processes (forked from this
    one with its loaded models where the platform forks; else spawned, each loading
    them once from the shared numba cache) and written back in input order. With
    `resume`, the complete lines already in OUT are kept and skipped, so an
    interrupted run continues where it stopped; without it OUT is rewritten.
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from tqdm import tqdm

    global _BATCH_MODELS, _BATCH_REPRODUCIBLE

    from service.jobs.io import keep_complete_lines, read_texts

    lines = read_texts(src)  # JSON Lines or Parquet (service.jobs.io)
    done = keep_complete_lines(out, resume=resume)
    failures = 0
    todo = list(enumerate(lines[done:], start=done + 1))
    workers = max(1, min(workers, len(todo)))
    with (
        out.open("a", encoding="utf-8") as sink,
        tqdm(total=len(lines), initial=done, unit="case", file=sys.stderr, desc="triage") as bar,
    ):
        _BATCH_MODELS = models
        _BATCH_REPRODUCIBLE = reproducible
        if workers == 1:
            results: Any = map(_batch_line, todo)
            pool = None
        elif "fork" in multiprocessing.get_all_start_methods():
            # forked workers inherit the loaded, warmed models: no start-up per worker
            pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork"))
            results = pool.map(_batch_line, todo, chunksize=BATCH_CHUNK)
        else:  # spawned workers load the models once each, from the shared numba cache
            pool = ProcessPoolExecutor(
                workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_init_batch_worker,
                initargs=(reproducible,),
            )
            results = pool.map(_batch_line, todo, chunksize=BATCH_CHUNK)
        try:
            for line in results:
                failures += '"error":' in line[:40]
                sink.write(line + "\n")
                sink.flush()
                bar.update(1)
        finally:
            if pool is not None:
                pool.shutdown(cancel_futures=True)
    _print(
        f"{len(todo)} evaluated by {workers} process{'es' if workers > 1 else ''}, "
        f"{failures} refused; results in {out}",
        err=True,
    )
    return 0


def _labelled_jsonl(
    path: Path, labels: Path | None, label_field: str, weight_field: str | None
) -> tuple[list[tuple[Any, bool, float]], int]:
    """Notifications of a JSON Lines file with their outcomes (engine form).

    The outcome (0/1) is the `label_field` of each line (removed before the
    notification is validated) or, with `labels`, the row of a CSV or JSON Lines
    file with the same ``event_id``. Returns the labelled notifications and the
    number of lines refused (invalid, or without a label).
    """
    import csv

    from service.cases.notification import CrashNotificationIn

    table: dict[str, dict[str, Any]] = {}
    if labels is not None:
        if labels.suffix.lower() == ".csv":
            with labels.open(newline="", encoding="utf-8") as fh:
                table = {r["event_id"]: dict(r) for r in csv.DictReader(fh)}
        else:
            for raw in labels.read_text(encoding="utf-8").splitlines():
                if raw.strip():
                    rec = json.loads(raw)
                    table[str(rec["event_id"])] = rec
    out: list[tuple[Any, bool, float]] = []
    refused = 0
    for raw in path.read_text(encoding="utf-8").splitlines():
        if not raw.strip():
            continue
        doc = json.loads(raw)
        label_doc = table.get(str(doc.get("event_id"))) if labels is not None else doc
        outcome = None if label_doc is None else label_doc.get(label_field)
        weight = 1.0
        if weight_field and label_doc is not None and label_doc.get(weight_field) is not None:
            weight = float(label_doc[weight_field])
        for key in (label_field, weight_field):
            if key:
                doc.pop(key, None)
        try:
            notification = CrashNotificationIn.model_validate(doc)
        except ValidationError:
            refused += 1
            continue
        if outcome is None or str(outcome) not in ("0", "1", "True", "False", "true", "false"):
            refused += 1
            continue
        engine_input, _ = notification.to_engine()
        out.append((engine_input, str(outcome) in ("1", "True", "true"), weight))
    return out, refused


def _cmd_evaluate(args: argparse.Namespace) -> int:
    """Score labelled notifications: AUC, calibration, triage rates; Markdown + PNG."""
    from models.offline.field.evaluate import evaluate_notifications, write_evaluation
    from models.offline.field.rows import (
        load_calibration_rows,
        police_notification,
        row_notification,
    )
    from models.offline.field_check import field_cases

    _settings()
    src = Path(args.file)
    weighted = False
    if src.suffix.lower() == ".csv":
        with src.open(encoding="utf-8") as fh:
            header = fh.readline()
        if "mais3pl" in header:
            labelled = [(row_notification(r), r.mais3, 1.0) for r in load_calibration_rows(src)]
        elif "injSeverity" in header:
            labelled = [
                (police_notification(c, i), c.serious, c.weight)
                for i, c in enumerate(field_cases(src))
            ]
            weighted = True
        else:
            _print(
                "error: a CSV must be the NASS-CDS MAIS calibration format (mais3pl) or the "
                "NASS-CDS 1997-2000 format (injSeverity); other data: JSON Lines",
                err=True,
            )
            return 2
        refused = 0
    else:
        labels = Path(args.labels) if args.labels else None
        labelled, refused = _labelled_jsonl(src, labels, args.label_field, args.weight_field)
        weighted = args.weight_field is not None
    if not labelled:
        _print("error: no labelled notification to score", err=True)
        return 1
    if args.scheduler:  # on a Dask cluster (service.jobs.dask)
        from service.jobs.dask import evaluate_on_dask

        cases = evaluate_on_dask(
            labelled, scheduler=args.scheduler, operating_point=args.operating_point
        )
    else:
        cases = evaluate_notifications(
            labelled, operating_point=args.operating_point, workers=args.workers
        )
    out = write_evaluation(
        cases, Path(args.out), title=f"Evaluation of {src.name}", weighted=weighted
    )
    _print(f"{len(cases)} scored, {refused} refused; report in {out}", err=True)
    return 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    """Run the occupant models of one notification; print the measures, draw the plot."""
    import dataclasses

    from models.offline.lpm.plot import plot_simulation
    from models.triage import UnknownVehicleModel, load_engine_models, simulate_notification
    from service.cases.notification import CrashNotificationIn

    _settings()
    try:
        notification = CrashNotificationIn.model_validate_json(
            Path(args.file).read_text(encoding="utf-8")
        )
    except ValidationError as exc:
        _print(json.dumps(_problem_from_validation(exc), indent=2), err=True)
        return 1
    engine_input, notes = notification.to_engine()
    models = load_engine_models(use_surrogates=False)
    try:
        pulse, simulations, assumptions = simulate_notification(engine_input, models)
    except (UnknownVehicleModel, ValueError) as exc:
        _print(f"error: {exc}", err=True)
        return 1
    report: dict[str, Any] = {
        "event_id": engine_input.event_id,
        "delta_v_kmh": pulse.delta_v_kmh,
        "pdof_deg": pulse.pdof_deg,
        "assumptions": [
            {"code": a.code.value, "message": a.message, "occupant": a.occupant}
            for a in (*notes, *assumptions)
        ],
        "occupants": [],
    }
    plots = []
    for sim in simulations:
        entry: dict[str, Any] = {
            "seat": sim.occupant.seat.value,
            "impact_mode": sim.impact.mode.value,
            "in_lpm_coverage": sim.impact.in_lpm_coverage,
        }
        if sim.result is not None:
            r = sim.result
            entry["status"] = r.status
            entry["message"] = r.message
            entry["measures"] = {
                k: v for k, v in dataclasses.asdict(r.measures).items() if v is not None
            }
            if r.assessment is not None:
                entry["region_ais"] = dict(r.assessment.region_ais)
                entry["iss"] = r.assessment.iss
                entry["p_iss15"] = r.assessment.p_iss15
            if args.plot:
                out = Path(args.plot)
                if len(simulations) > 1:
                    out = out.with_name(f"{out.stem}-{sim.occupant.seat.value}{out.suffix}")
                plot_simulation(
                    r,
                    out,
                    body=sim.occupant.body,
                    title=f"{engine_input.event_id}: {sim.occupant.seat.value}, "
                    f"{sim.impact.mode.value}, {pulse.delta_v_kmh:.0f} km/h",
                )
                plots.append(str(out))
        report["occupants"].append(entry)
    report["plots"] = plots
    _print(json.dumps(report, indent=2))
    return 0


#: Commands handed over whole to an engine module's ``main(argv)``: argparse's
#: REMAINDER does not pass on arguments that start with "--" (``--family NAME``,
#: ``--help``), so ``main`` below hands them their arguments itself.
_HANDED_OVER: dict[str, tuple[str, str]] = {
    "build-surrogates": (
        "models.offline.surrogate.command",
        "build the PCE surrogate artifacts (offline, resumable; numpy only, no chaospy)",
    ),
    "validate-surrogates": (
        "models.offline.surrogate.validate",
        "score the surrogates on fresh direct LPM runs (resumable)",
    ),
    "fit-field": (
        "models.offline.field.command",
        "fit the field risk model on real crashes, cross-validate, write the model card",
    ),
}


def _cmd_handed_over(command: str, argv: list[str]) -> int:
    import importlib

    module = importlib.import_module(_HANDED_OVER[command][0])
    return int(module.main(argv) or 0)


def _cmd_baseline(args: argparse.Namespace) -> int:
    from models.offline.baseline.fit import main as fit_main

    argv: list[str] = ["--seed", str(args.seed)]
    if args.data:
        argv += ["--data", args.data]
    if args.out:
        argv += ["--out", args.out]
    if args.fit_date:
        argv += ["--fit-date", args.fit_date]
    return int(fit_main(argv) or 0)


# --------------------------------------------------------------------- parser

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
    serve.set_defaults(func=_cmd_serve)

    db = sub.add_parser("db", help="database migrations")
    db_sub = db.add_subparsers(dest="db_command", required=True)
    up = db_sub.add_parser("upgrade", help="migrate up (default: head)")
    up.add_argument("revision", nargs="?", default="head")
    down = db_sub.add_parser("downgrade", help="migrate down to REV (e.g. base)")
    down.add_argument("revision")
    db_sub.add_parser("current", help="print the current revision")
    db.set_defaults(func=_cmd_db)

    keys = sub.add_parser("keys", help="API keys")
    keys_sub = keys.add_subparsers(dest="keys_command", required=True)
    create = keys_sub.add_parser("create", help="create a key and print it once")
    create.add_argument(
        "--role", required=True, choices=["submitter", "auditor", "admin", "metrics"]
    )
    create.add_argument("--name", required=True, help="client name, recorded with its cases")
    keys_sub.add_parser("list", help="list keys (ids, names, roles, prefixes)")
    revoke = keys_sub.add_parser("revoke", help="revoke a key (refused at once)")
    revoke.add_argument("key", help="the key's name or id")
    rotate = keys_sub.add_parser(
        "rotate", help="new secret for a key (same name and role); the old one is refused at once"
    )
    rotate.add_argument("key", help="the key's name or id")
    keys.set_defaults(func=_cmd_keys)

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
    tri.set_defaults(func=_cmd_triage)

    sim = sub.add_parser("simulate", help="run the occupant models of one notification")
    sim.add_argument("file", help="one notification (JSON)")
    sim.add_argument("--plot", help="draw pulse, motion and measures to this image (PNG)")
    sim.set_defaults(func=_cmd_simulate)

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
    ev.set_defaults(func=_cmd_evaluate)

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
    cases.set_defaults(func=_cmd_cases)

    for command, (_, text) in _HANDED_OVER.items():
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
    base.set_defaults(func=_cmd_baseline)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    raw = list(sys.argv[1:] if argv is None else argv)
    if raw[:1] and raw[0] in _HANDED_OVER:
        return _cmd_handed_over(raw[0], raw[1:])
    args = build_parser().parse_args(raw)
    return int(args.func(args))


if __name__ == "__main__":
    raise SystemExit(main())
