"""The local spool: where a triaged case is recorded durably when the store fails.

When the audit store (PostgreSQL, or the SQLite file) cannot take a case, being
down, read-only or full, the service still answers the triage (202, `stored:
false`, `spooled: true`) once the case is committed here: a SQLite file next to the
service (WAL, ``synchronous=FULL``: the row is on disk before the answer is sent).
A replayer in each service process moves spooled cases into the store in spool
order; the store's unique (client, event_id) makes the move idempotent, so a case
is stored exactly once even when a replay is interrupted between the store's
commit and the spool's delete, or two processes replay at once (a file lock lets
one replay at a time, which also keeps the order).

Tables::

    spool(seq, client_name, event_id, request_sha256, case_id, received_at,
          spooled_at, notification, result, source)   UNIQUE(client_name, event_id)
    probe(id, at)                              readiness write check
"""

from __future__ import annotations

import fcntl
import json
import logging
import sqlite3
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

__all__ = ["Spool", "SpoolEntry", "SpoolError", "SpoolReplayer"]

log = logging.getLogger("aacn_triage.spool")

#: Milliseconds a spool write waits for another process's lock. [R] Spool writes
#: are single-row inserts of a few kilobytes; 30 s is SQLite's usual generous bound.
BUSY_TIMEOUT_MS = 30_000
#: Spooled cases moved per replay round (each in its own store transaction).
REPLAY_BATCH = 100

_SCHEMA = (
    """CREATE TABLE IF NOT EXISTS spool (
        seq INTEGER PRIMARY KEY AUTOINCREMENT,
        client_name TEXT NOT NULL,
        event_id TEXT NOT NULL,
        request_sha256 TEXT NOT NULL,
        case_id TEXT NOT NULL,
        received_at TEXT NOT NULL,
        spooled_at TEXT NOT NULL,
        notification TEXT NOT NULL,
        result TEXT NOT NULL,
        source TEXT,
        UNIQUE (client_name, event_id)
    )""",
    "CREATE TABLE IF NOT EXISTS probe (id INTEGER PRIMARY KEY, at TEXT NOT NULL)",
)


def _add_source_column(conn: sqlite3.Connection) -> None:
    """Give a spool file written before VEDS input its ``source`` column (idempotent)."""
    columns = {row[1] for row in conn.execute("PRAGMA table_info(spool)")}
    if "source" not in columns:
        conn.execute("ALTER TABLE spool ADD COLUMN source TEXT")


class SpoolError(Exception):
    """The spool could not record or read a case (its disk failed too)."""


@dataclass(frozen=True)
class SpoolEntry:
    """A case waiting in the spool."""

    seq: int | None
    client_name: str
    event_id: str
    request_sha256: str
    case_id: str
    received_at: datetime
    spooled_at: datetime
    notification: Any
    result: dict[str, Any]
    #: How the notification came in, when not as JSON (``ReceivedSource.record()``:
    #: the VEDS document as received and its mapping); None for JSON.
    source: dict[str, Any] | None = None


def _entry(row: sqlite3.Row) -> SpoolEntry:
    return SpoolEntry(
        seq=row["seq"],
        client_name=row["client_name"],
        event_id=row["event_id"],
        request_sha256=row["request_sha256"],
        case_id=row["case_id"],
        received_at=datetime.fromisoformat(row["received_at"]),
        spooled_at=datetime.fromisoformat(row["spooled_at"]),
        notification=json.loads(row["notification"]),
        result=json.loads(row["result"]),
        source=json.loads(row["source"]) if row["source"] is not None else None,
    )


class Spool:
    """A durable, ordered, idempotent queue of cases in one SQLite file.

    Safe for several threads and several processes on one host (SQLite locking).

    Parameters
    ----------
    path : Path
        The spool file; its directory is created. Put it on another volume than a
        SQLite store to survive that disk filling up.
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._lock_path = self.path.with_name(self.path.name + ".replay-lock")
        self._ready = False

    @contextmanager
    def _connect(self) -> Iterator[sqlite3.Connection]:
        try:
            if not self._ready:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            conn = sqlite3.connect(self.path, timeout=BUSY_TIMEOUT_MS / 1000, isolation_level=None)
        except (OSError, sqlite3.Error) as exc:
            raise SpoolError(f"spool unavailable: {type(exc).__name__}: {exc}") from exc
        try:
            conn.row_factory = sqlite3.Row
            conn.execute("PRAGMA synchronous=FULL")
            if not self._ready:
                conn.execute("PRAGMA journal_mode=WAL")
                for statement in _SCHEMA:
                    conn.execute(statement)
                _add_source_column(conn)
                self._ready = True
            yield conn
        except sqlite3.Error as exc:
            raise SpoolError(f"spool unavailable: {type(exc).__name__}: {exc}") from exc
        finally:
            conn.close()

    def put(self, entry: SpoolEntry) -> SpoolEntry:
        """Record a case durably; returns the entry already spooled for its event, if any.

        The returned entry is `entry` itself when it was recorded; another one when the
        same (client, event_id) was spooled first (the caller replays or refuses it).
        """
        with self._connect() as conn:
            try:
                conn.execute(
                    "INSERT INTO spool (client_name, event_id, request_sha256, case_id, "
                    "received_at, spooled_at, notification, result, source) "
                    "VALUES (?,?,?,?,?,?,?,?,?)",
                    (
                        entry.client_name,
                        entry.event_id,
                        entry.request_sha256,
                        entry.case_id,
                        entry.received_at.isoformat(),
                        entry.spooled_at.isoformat(),
                        json.dumps(entry.notification, separators=(",", ":")),
                        json.dumps(entry.result, separators=(",", ":")),
                        None
                        if entry.source is None
                        else json.dumps(entry.source, separators=(",", ":")),
                    ),
                )
            except sqlite3.IntegrityError:
                existing = self.find(entry.client_name, entry.event_id)
                if existing is None:  # pragma: no cover - replayed in between
                    raise SpoolError("spool entry vanished during a concurrent replay") from None
                return existing
        return entry

    def find(self, client_name: str, event_id: str) -> SpoolEntry | None:
        """The spooled case of an event, if it is waiting."""
        with self._connect() as conn:
            row = conn.execute(
                "SELECT * FROM spool WHERE client_name = ? AND event_id = ?",
                (client_name, event_id),
            ).fetchone()
        return _entry(row) if row is not None else None

    def oldest(self, limit: int) -> list[SpoolEntry]:
        """Up to `limit` waiting cases, in the order they were spooled."""
        with self._connect() as conn:
            rows = conn.execute("SELECT * FROM spool ORDER BY seq LIMIT ?", (limit,)).fetchall()
        return [_entry(r) for r in rows]

    def remove(self, seq: int) -> None:
        with self._connect() as conn:
            conn.execute("DELETE FROM spool WHERE seq = ?", (seq,))

    def pending(self) -> int:
        """How many cases wait to be stored."""
        with self._connect() as conn:
            return int(conn.execute("SELECT count(*) FROM spool").fetchone()[0])

    def probe(self) -> None:
        """A committed write, for readiness (raises SpoolError)."""
        with self._connect() as conn:
            conn.execute(
                "INSERT OR REPLACE INTO probe (id, at) VALUES (1, ?)",
                (datetime.now(UTC).isoformat(),),
            )

    @contextmanager
    def replay_lock(self) -> Iterator[bool]:
        """Hold the replay lock if no other process does; yields whether it is held."""
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            handle = self._lock_path.open("a")
        except OSError:
            yield False
            return
        try:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                yield False
                return
            try:
                yield True
            finally:
                fcntl.flock(handle, fcntl.LOCK_UN)
        finally:
            handle.close()


class SpoolReplayer:
    """A daemon thread that moves spooled cases into the store, oldest first.

    Parameters
    ----------
    spool : Spool
    store : callable
        ``store(entry) -> None`` commits one case to the store; it raises
        `StoreUnavailable`-like errors (any exception) while the store is down and
        treats "already stored" as success.
    interval_s : float
        Seconds between looks at the spool.
    """

    def __init__(
        self, spool: Spool, store: Callable[[SpoolEntry], None], *, interval_s: float
    ) -> None:
        self.spool = spool
        self.store = store
        self.interval_s = interval_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="aacn-spool-replay", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout_s: float = 10.0) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout_s)

    def _run(self) -> None:
        while not self._stop.wait(self.interval_s):
            try:
                self.replay_once()
            except Exception:  # never let the thread die; the next round retries
                log.exception("spool replay failed")

    def replay_once(self) -> int:
        """Move waiting cases into the store until the spool is empty or the store fails.

        Returns
        -------
        int
            Cases moved in this call.
        """
        moved = 0
        with self.spool.replay_lock() as held:
            if not held:
                return 0
            while not self._stop.is_set():
                batch = self.spool.oldest(REPLAY_BATCH)
                if not batch:
                    break
                for entry in batch:
                    try:
                        self.store(entry)
                    except Exception as exc:
                        log.warning(
                            "spool replay paused, the store failed",
                            extra={"error_type": type(exc).__name__, "pending": len(batch)},
                        )
                        return moved
                    assert entry.seq is not None
                    self.spool.remove(entry.seq)
                    moved += 1
        if moved:
            log.info("spool replayed", extra={"stored": moved})
        return moved
