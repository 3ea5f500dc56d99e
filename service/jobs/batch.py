"""The local batch pool of ``aacn-triage triage --batch``: one answer line per input
line, in input order, resumable, on a pool of processes (never on the request path)."""

from __future__ import annotations

import functools
import json
import sys
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError

from service.jobs.worker import BatchLine, models_for

if TYPE_CHECKING:
    from models.triage import EngineModels
    from service.settings import Settings

__all__ = ["BATCH_CHUNK", "Evaluation", "batch_record", "evaluate_text", "run_batch"]


@dataclass(frozen=True, slots=True)
class Evaluation:
    """The answer to one notification's text: its result, or the problem that refused it.

    Exactly one of the two is set; both are the JSON forms a batch line holds.
    """

    result: dict[str, Any] | None = None
    problem: dict[str, Any] | None = None

    def fields(self) -> dict[str, Any]:
        """``{"result": ...}`` or ``{"error": problem}``: the line's own fields."""
        return {"result": self.result} if self.problem is None else {"error": self.problem}


def evaluate_text(
    text: str, models: EngineModels, *, reproducible: bool = False, decision_only: bool = False
) -> Evaluation:
    """One notification (JSON text) -> its result, or the problem that refused it.

    With `decision_only` the occupant models are not run: the answer's decision
    fields are a full run's, without the occupant models' explanation.
    """
    from service.cases.notification import CrashNotificationIn
    from service.cases.service import evaluate
    from service.jsonbody import MalformedJson
    from service.problems import (
        DomainError,
        malformed_json_problem,
        problem_from_domain_error,
        problem_from_validation,
    )

    try:
        notification, _ = CrashNotificationIn.from_json(text)
    except MalformedJson as exc:
        return Evaluation(problem=malformed_json_problem(str(exc)))
    except ValidationError as exc:
        return Evaluation(problem=problem_from_validation(exc))
    try:
        received_at = notification.occurred_at if reproducible else datetime.now(UTC)
        result = evaluate(
            notification,
            models,
            case_id=None,
            received_at=received_at,
            occupant_models=not decision_only,
        )
    except DomainError as exc:
        return Evaluation(problem=problem_from_domain_error(exc))
    if reproducible:  # nothing of the run itself: the same input gives the same bytes
        result = result.model_copy(update={"timings_ms": {}})
    return Evaluation(result=result.model_dump(mode="json"))


#: Lines handed to a batch worker at a time. [R] Big enough that the pool's IPC is
#: small beside ~10-50 ms of engine time per line, small enough to keep the bar live.
BATCH_CHUNK = 8


def _batch_line(
    settings: Settings, reproducible: bool, decision_only: bool, item: tuple[int, str]
) -> BatchLine:
    """A pool worker's task: one line, with this process's models for `settings`."""
    models = models_for(settings, occupant_models=not decision_only)
    return batch_record(*item, models, reproducible=reproducible, decision_only=decision_only)


def batch_record(
    number: int,
    text: str,
    models: EngineModels,
    *,
    reproducible: bool = False,
    decision_only: bool = False,
) -> BatchLine:
    """One output line of a batch: the answer to input line `number`, or its error.

    With `reproducible`, ``received_at`` is the crash's time and there are no
    timings: an answer then holds nothing of the run that made it, so the same
    input and model versions give the same bytes on any machine, pool or cluster
    (a recall or a study can be re-run and compared with ``cmp``). With
    `decision_only`, the occupant models are not run (:func:`evaluate_text`).
    """
    from service.problems import empty_line_problem

    if not text.strip():
        evaluation = Evaluation(problem=empty_line_problem())
    else:
        evaluation = evaluate_text(
            text, models, reproducible=reproducible, decision_only=decision_only
        )
    record = {"line": number, **evaluation.fields()}
    return BatchLine(json.dumps(record, separators=(",", ":")), evaluation.problem is not None)


def run_batch(
    src: Path,
    out: Path,
    settings: Settings,
    *,
    resume: bool,
    workers: int = 1,
    reproducible: bool = False,
    decision_only: bool = False,
) -> int:
    """Evaluate a JSONL file into OUT (one line per input line, in order).

    The engine models are this process's for `settings` (``service.jobs.worker``).
    With `workers` > 1 the lines are triaged by a pool of processes (forked from this
    one with its loaded models where the platform forks; else spawned, each loading
    them once from the shared numba cache) and written back in input order. With
    `resume`, the complete lines already in OUT are kept and skipped, so an
    interrupted run continues where it stopped; without it OUT is rewritten. With
    `decision_only` the occupant models are not run (a fleet's rescoring: the
    decision fields of a full run, without the explanation).
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from tqdm import tqdm

    from service.jobs.io import keep_complete_lines, read_texts

    lines = read_texts(src)  # JSON Lines or Parquet (service.jobs.io)
    done = keep_complete_lines(out, resume=resume)
    failures = 0
    todo = list(enumerate(lines[done:], start=done + 1))
    workers = max(1, min(workers, len(todo)))
    if workers > 1 and settings.occupant_threads is None:
        # the processes fill the cores: an occupant's helper thread would only wait for one
        settings = settings.model_copy(update={"occupant_threads": 1})
    task = functools.partial(_batch_line, settings, reproducible, decision_only)
    models_for(settings, occupant_models=not decision_only)  # forked workers inherit them
    with (
        out.open("a", encoding="utf-8") as sink,
        tqdm(total=len(lines), initial=done, unit="case", file=sys.stderr, desc="triage") as bar,
    ):
        if workers == 1:
            results: Any = map(task, todo)
            pool = None
        else:
            # forked workers inherit the loaded, warmed models: no start-up per worker;
            # spawned ones load them once each, from the shared numba cache
            method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
            pool = ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context(method))
            results = pool.map(task, todo, chunksize=BATCH_CHUNK)
        try:
            for line in results:
                failures += line.refused
                sink.write(line.text + "\n")
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
