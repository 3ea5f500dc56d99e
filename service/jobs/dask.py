"""The batch on a Dask cluster (``--scheduler tcp://host:8786``).

``aacn-triage triage --batch IN --out OUT --scheduler ADDR`` hands its
notifications to the workers of a ``dask.distributed`` scheduler in chunks of
:data:`CHUNK_LINES`, keep at most
:data:`TASKS_PER_THREAD` chunks in flight per worker thread (so that an input of
millions of lines is never held whole, here or on the cluster), and take the
answers back in input order: the output is the local pool's, line for line. Every
worker process loads the engine models once (from its numba cache) for the
settings the command was given, which travel with each task, so the workers'
own ``AACN_*`` environment does not change the answers. The research command's
``evaluate --scheduler`` uses the same client and window
(``service.cli.research_dask``).

A worker must have this package installed at the same version with the ``dask``
extra (``pip install 'aacn-triage[dask]'``). Dask is imported here only, and
this module only by those commands: the service never imports Dask.
"""

from __future__ import annotations

import sys
from collections import deque
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from service.jobs.io import count_items, iter_chunks, keep_complete_lines
from service.jobs.worker import BatchLine, models_for

if TYPE_CHECKING:
    from service.settings import Settings

__all__ = ["CHUNK_LINES", "TASKS_PER_THREAD", "connect", "in_order", "triage_batch_on_dask"]

#: Notifications per Dask task. [R] At ~5-50 ms of engine time each, a task takes
#: 0.3-3 s: long beside the scheduler's ~1 ms per task and the shipping of ~100 kB of
#: text, short enough that the bar moves and a lost worker's chunk is soon redone.
CHUNK_LINES = 64
#: Chunks in flight per worker thread: one running, the next ones queued, so no
#: worker waits while the client writes the answers in order.
TASKS_PER_THREAD = 3
#: Bound on connecting to the scheduler, s.
CONNECT_TIMEOUT_S = 30.0

#: One line of a batch answer: (line number, text, engine models) -> the line.
Record = Callable[[int, str, Any], BatchLine]


def _triage_chunk(
    settings: Settings, record: Record, chunk: list[tuple[int, str]]
) -> list[BatchLine]:
    """A worker's task: the answer lines of one chunk."""
    models = models_for(settings)
    return [record(number, text, models) for number, text in chunk]


def connect(scheduler: str) -> Any:
    """A client of the scheduler at `scheduler` (Dask is imported here only)."""
    try:
        from distributed import Client
    except ImportError as exc:
        raise RuntimeError(
            "--scheduler needs Dask: pip install 'aacn-triage[dask]' (here and on the workers)"
        ) from exc
    return Client(scheduler, timeout=CONNECT_TIMEOUT_S)


def in_order(client: Any, function: Callable[..., Any], *args: Any, chunks: Iterator[Any]) -> Any:
    """The results of ``function(*args, chunk)`` on the cluster, in the chunks' order.

    At most :data:`TASKS_PER_THREAD` chunks per worker thread are in flight.
    """
    threads = sum(client.nthreads().values()) or 1
    window = max(2, TASKS_PER_THREAD * threads)
    pending: deque[Any] = deque()
    for chunk in chunks:
        pending.append(client.submit(function, *args, chunk, pure=False))
        if len(pending) >= window:
            yield pending.popleft().result()
    while pending:
        yield pending.popleft().result()


def triage_batch_on_dask(
    src: Path,
    out: Path,
    *,
    scheduler: str,
    settings: Settings,
    record: Record,
    resume: bool,
) -> tuple[int, int]:
    """Triage JSON Lines or Parquet `src` into `out` on the cluster at `scheduler`.

    Parameters
    ----------
    src, out : Path
        Input (`service.jobs.io`) and JSON Lines output, one line per input line in
        input order.
    scheduler : str
        The scheduler's address, e.g. ``tcp://10.0.0.5:8786``.
    settings : Settings
        The settings the workers load the engine models for.
    record : callable
        Makes one output line (the local pool's own, so the lines are the same).
    resume : bool
        Keep the complete lines of `out` and continue after them.

    Returns
    -------
    (int, int)
        Lines evaluated in this run, and how many of them were refused.
    """
    from tqdm import tqdm

    done = keep_complete_lines(out, resume=resume)
    total = count_items(src)
    evaluated = refused = 0
    with (
        connect(scheduler) as dask,
        out.open("a", encoding="utf-8") as sink,
        tqdm(total=total, initial=done, unit="case", file=sys.stderr, desc="triage") as bar,
    ):
        chunks = iter_chunks(src, skip=done, size=CHUNK_LINES)
        for lines in in_order(dask, _triage_chunk, settings, record, chunks=chunks):
            for line in lines:
                refused += line.refused
                sink.write(line.text + "\n")
            sink.flush()
            evaluated += len(lines)
            bar.update(len(lines))
    return evaluated, refused
