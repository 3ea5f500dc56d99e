"""Input and output of the batch commands, shared by the local pool and Dask.

Input: JSON Lines (one notification per line; the line number names it in the
output), or Parquet (``.parquet``/``.pq``) with a string column ``notification``
holding each notification's JSON; row *k* is "line" *k*. Both are read in chunks,
so that an input of millions of notifications is never held whole (Parquet needs
the ``dask`` extra's pyarrow). Output: JSON Lines in input order; with resume, the
complete lines already written are kept and the run continues after them.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

__all__ = [
    "PARQUET_COLUMN",
    "PARQUET_SUFFIXES",
    "count_items",
    "iter_chunks",
    "keep_complete_lines",
    "read_texts",
]

#: The Parquet column holding each notification as JSON text.
PARQUET_COLUMN = "notification"
#: File name suffixes read as Parquet; anything else is JSON Lines.
PARQUET_SUFFIXES = frozenset({".parquet", ".pq"})
#: Parquet rows read at a time. [R] Thousands of ~1-2 kB notifications: a few MB.
PARQUET_BATCH_ROWS = 4096


def _is_parquet(path: Path) -> bool:
    return path.suffix.lower() in PARQUET_SUFFIXES


def _parquet(path: Path) -> Any:
    try:
        import pyarrow.parquet as pq
    except ImportError as exc:  # pragma: no cover - the extra is in [test]
        raise RuntimeError("Parquet input needs pyarrow: pip install 'aacn-triage[dask]'") from exc
    parquet = pq.ParquetFile(path)
    if PARQUET_COLUMN not in parquet.schema_arrow.names:
        raise ValueError(f"{path}: no column {PARQUET_COLUMN!r} (the notification as JSON text)")
    return parquet


def _iter_texts(path: Path) -> Iterator[str]:
    if _is_parquet(path):
        parquet = _parquet(path)
        for batch in parquet.iter_batches(batch_size=PARQUET_BATCH_ROWS, columns=[PARQUET_COLUMN]):
            for value in batch.column(0).to_pylist():
                yield "" if value is None else str(value)
        return
    # binary lines end at b"\n" only: a bare CR is JSON whitespace, not a line end
    with path.open("rb") as fh:
        for raw in fh:
            yield raw.decode("utf-8").removesuffix("\n").removesuffix("\r")


def count_items(path: Path) -> int:
    """Notifications (lines or rows) in `path`, read in chunks (for the progress bar)."""
    if _is_parquet(path):
        return int(_parquet(path).metadata.num_rows)
    return sum(1 for _ in _iter_texts(path))


def read_texts(path: Path) -> list[str]:
    """Every notification text of `path` (the local pool holds its input whole).

    Lines end at ``\n`` (or ``\r\n``) only: not at a bare ``\r``, which JSON takes as
    whitespace between tokens, nor at the other separators of `str.splitlines`, such
    as U+2028, which JSON allows inside a string."""
    return list(_iter_texts(path))


def iter_chunks(path: Path, *, skip: int, size: int) -> Iterator[list[tuple[int, str]]]:
    """``(line number, text)`` chunks of `size` from `path`, after the first `skip`."""
    chunk: list[tuple[int, str]] = []
    for number, text in enumerate(_iter_texts(path), start=1):
        if number <= skip:
            continue
        chunk.append((number, text))
        if len(chunk) == size:
            yield chunk
            chunk = []
    if chunk:
        yield chunk


def keep_complete_lines(out: Path, *, resume: bool) -> int:
    """Prepare `out` for a run; returns how many input lines it already answers.

    With `resume`, the complete JSON lines of `out` are kept (a torn last line of an
    interrupted run is dropped, to be redone); without it, `out` is removed.
    """
    if not resume or not out.exists():
        out.unlink(missing_ok=True)
        return 0
    kept = []
    for raw in out.read_text(encoding="utf-8").splitlines():
        try:
            json.loads(raw)
        except json.JSONDecodeError:
            break  # a torn last line from an interrupted run: redo it
        kept.append(raw)
    out.write_text("".join(k + "\n" for k in kept), encoding="utf-8")
    return len(kept)
