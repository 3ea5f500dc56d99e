"""``aacn-triage evaluate FILE --scheduler ADDR``: research scoring on a Dask cluster.

The labelled notifications go to the cluster in chunks of
``service.jobs.dask.CHUNK_LINES`` through the batch's client and window; each worker
scores its chunk with the offline evaluation (``models.offline.field.evaluate``), so
this module, beside the research command, is where the lab meets the cluster.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

from service.jobs.dask import CHUNK_LINES, connect, in_order

if TYPE_CHECKING:
    from models.notification import CrashNotification
    from models.offline.field.evaluate import ScoredCase

__all__ = ["evaluate_on_dask"]


def _score_chunk(
    operating_point: str | None, chunk: Sequence[tuple[CrashNotification, bool, float]]
) -> list[ScoredCase]:
    """A worker's task: the scored cases of one chunk."""
    from models.offline.field.evaluate import score_chunk

    return score_chunk(chunk, operating_point=operating_point)


def evaluate_on_dask(
    labelled: Sequence[tuple[CrashNotification, bool, float]],
    *,
    scheduler: str,
    operating_point: str | None,
) -> list[ScoredCase]:
    """Score labelled notifications on the cluster (``aacn-triage evaluate``), in order."""
    from tqdm import tqdm

    def chunks() -> Iterator[Sequence[tuple[CrashNotification, bool, float]]]:
        for start in range(0, len(labelled), CHUNK_LINES):
            yield labelled[start : start + CHUNK_LINES]

    cases: list[ScoredCase] = []
    with (
        connect(scheduler) as client,
        tqdm(total=len(labelled), unit="case", file=sys.stderr, desc="triage") as bar,
    ):
        for scored in in_order(client, _score_chunk, operating_point, chunks=chunks()):
            cases.extend(scored)
            bar.update(len(scored))
    return cases
