"""Spreading keep-alive connections over the worker processes (`serve --workers N`).

Each worker process of ``serve`` accepts connections from one shared socket, and a
keep-alive connection stays with the worker that accepted it. A client that opens a
few connections at once (a call center's pool) can land most of them on one worker:
measured with 8 connections on 2 workers, 6 went to one and 2 to the other, whose
requests then waited three times longer (p50 175 ms against 61 ms), and the p99 of
the service was that of the crowded worker (benchmarks/RESULTS.md, Load).

The workers share a small table of their requests in flight (:class:`WorkerLoads`,
a memory-mapped file that ``serve`` creates before it starts them). A worker holding
more than its fair share (the total in flight over the live workers, rounded up)
answers with ``Connection: close`` (:class:`ConnectionBalance`): the client
reconnects (HTTP/1.1 clients must handle it), and the new connection goes to the
worker that accepts it first, more often the less busy one (a busy worker's event
loop waits for its engine threads). Connections drift from crowded workers to idle
ones; spread evenly, they are kept. Proxies cap requests per connection for the
same reason (nginx ``keepalive_requests``, Envoy ``max_requests_per_connection``);
this cap is the imbalance itself, so a balanced client never reconnects.

Why hand-written: uvicorn and gunicorn balance connections, not requests, and
have no such rule; a front proxy would be a second service to run.
"""

from __future__ import annotations

import fcntl
import math
import mmap
import os
from pathlib import Path
from typing import Final

from starlette.datastructures import MutableHeaders
from starlette.types import ASGIApp, Message, Receive, Scope, Send

__all__ = ["LOADS_ENV", "ConnectionBalance", "WorkerLoads"]

#: Environment variable through which ``serve`` hands the table's path to its workers.
LOADS_ENV: Final[str] = "AACN_WORKER_LOADS_PATH"

#: Slots of the table: the most worker processes it can follow.
MAX_WORKERS: Final[int] = 256

#: Bytes of one slot: the worker's pid and its requests in flight, two int64.
_SLOT: Final[int] = 16


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, another user's
        return True
    return True


class WorkerLoads:
    """The shared table of requests in flight per worker process.

    One slot per worker (its pid, its count); a worker writes only its own
    slot (an aligned 8-byte store, read whole by the others) and reads all of
    them. Slots of dead workers (uvicorn restarts a worker that dies) are
    reclaimed by the next worker that claims one.

    Parameters
    ----------
    path : Path
        The table file (created with :meth:`create`).
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._fd = os.open(self.path, os.O_RDWR)
        self._map = mmap.mmap(self._fd, MAX_WORKERS * _SLOT)
        self._table = memoryview(self._map).cast("q")
        self.slot: int | None = None

    @staticmethod
    def create(path: Path) -> Path:
        """Write an empty table at `path` (every slot free) and return the path."""
        Path(path).write_bytes(bytes(MAX_WORKERS * _SLOT))
        return Path(path)

    def claim(self, pid: int | None = None) -> int:
        """Take a free slot (or a dead worker's) for process `pid` (default: this one)."""
        pid = os.getpid() if pid is None else pid
        fcntl.flock(self._fd, fcntl.LOCK_EX)
        try:
            for slot in range(MAX_WORKERS):
                owner = self._table[2 * slot]
                if owner == 0 or owner == pid or not _alive(owner):
                    self._table[2 * slot + 1] = 0
                    self._table[2 * slot] = pid
                    self.slot = slot
                    return slot
        finally:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
        raise RuntimeError(f"the worker table {self.path} is full ({MAX_WORKERS} workers)")

    def mine(self) -> int:
        """This worker's requests in flight (0 before a slot is claimed)."""
        return 0 if self.slot is None else int(self._table[2 * self.slot + 1])

    def add(self, delta: int) -> int:
        """Change this worker's count by `delta` (nothing before a slot is claimed)."""
        if self.slot is None:
            return 0
        i = 2 * self.slot + 1
        self._table[i] = self._table[i] + delta
        return int(self._table[i])

    def fair_share(self) -> int:
        """The requests in flight over the workers with a slot, rounded up (at least 1)."""
        total = 0
        workers = 0
        for slot in range(MAX_WORKERS):
            if self._table[2 * slot] != 0:
                workers += 1
                total += max(int(self._table[2 * slot + 1]), 0)
        return max(1, math.ceil(total / max(workers, 1)))

    def release(self) -> None:
        """Free this worker's slot (at shutdown)."""
        if self.slot is not None:
            self._table[2 * self.slot + 1] = 0
            self._table[2 * self.slot] = 0
            self.slot = None

    def close(self) -> None:
        """Release the slot and unmap the table."""
        self.release()
        self._table.release()
        self._map.close()
        os.close(self._fd)


class ConnectionBalance:
    """``Connection: close`` on responses sent while this worker holds more than its share.

    Parameters
    ----------
    app : ASGIApp
    loads : WorkerLoads
        The shared table, with this worker's slot claimed.
    """

    def __init__(self, app: ASGIApp, loads: WorkerLoads) -> None:
        self.app = app
        self.loads = loads

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        loads = self.loads

        async def send_balanced(message: Message) -> None:
            if message["type"] == "http.response.start" and loads.mine() > loads.fair_share():
                MutableHeaders(scope=message)["Connection"] = "close"
            await send(message)

        loads.add(1)
        try:
            await self.app(scope, receive, send_balanced)
        finally:
            loads.add(-1)
