"""The local batch pool of ``aacn-triage triage --batch``: one answer line per input
line, in input order, resumable, on a pool of processes (never on the request path)."""

from __future__ import annotations

import json
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from pydantic import ValidationError

__all__ = [
    "BATCH_CHUNK",
    "batch_record",
    "evaluate_text",
    "init_batch_worker",
    "problem_from_validation",
    "run_batch",
]


def problem_from_validation(exc: ValidationError) -> dict[str, Any]:
    from fastapi.exceptions import RequestValidationError

    from service.problems import validation_errors

    errors = validation_errors(RequestValidationError(exc.errors()))
    return {
        "title": "Invalid notification",
        "status": 422,
        "errors": [e.model_dump() for e in errors],
    }


def evaluate_text(text: str, models: Any, *, reproducible: bool = False) -> dict[str, Any]:
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
        return {"error": problem_from_validation(exc)}
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


#: The engine models of a batch worker process (loaded once by `init_batch_worker`).
_BATCH_MODELS: Any = None


#: Lines handed to a batch worker at a time. [R] Big enough that the pool's IPC is
#: small beside ~10-50 ms of engine time per line, small enough to keep the bar live.
BATCH_CHUNK = 8


#: Whether the batch of this process is reproducible (`triage --reproducible`).
_BATCH_REPRODUCIBLE = False


def init_batch_worker(reproducible: bool = False) -> None:
    global _BATCH_MODELS, _BATCH_REPRODUCIBLE
    from service.context import engine_models_for
    from service.settings import get_settings

    _BATCH_MODELS = engine_models_for(get_settings())
    _BATCH_REPRODUCIBLE = reproducible


def _batch_line(item: tuple[int, str]) -> str:
    return batch_record(*item, _BATCH_MODELS, reproducible=_BATCH_REPRODUCIBLE)


def batch_record(number: int, text: str, models: Any, *, reproducible: bool = False) -> str:
    """One output line of a batch: the answer to input line `number`, or its error.

    With `reproducible`, ``received_at`` is the crash's time and there are no
    timings: an answer then holds nothing of the run that made it, so the same
    input and model versions give the same bytes on any machine, pool or cluster
    (a recall or a study can be re-run and compared with ``cmp``).
    """
    if not text.strip():
        record: dict[str, Any] = {"line": number, "error": {"title": "Empty line"}}
    else:
        record = {"line": number, **evaluate_text(text, models, reproducible=reproducible)}
    return json.dumps(record, separators=(",", ":"))


def run_batch(
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
                initializer=init_batch_worker,
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
    # the run's summary line, on stderr (the command line's own output)
    sys.stderr.write(
        f"{len(todo)} evaluated by {workers} process{'es' if workers > 1 else ''}, "
        f"{failures} refused; results in {out}\n"
    )
    sys.stderr.flush()
    return 0
