"""What this process knows of the API keys, for when the store cannot be read.

Every request reads its key from the store. While the store cannot be read (an
outage, when cases go to the spool) a key is judged by what this process last
knew of it: :class:`KeyStates` holds, per key hash, the caller of an active key or
the mark of a revoked one, with the time that was true. It learns from

* every request that read its key from the store (active, or unknown/revoked), and
* a snapshot of the whole key table, taken at start and then every
  ``key_refresh_interval_s`` by :class:`KeyRefresher` (a daemon thread), so a
  revocation made by another process (``aacn-triage keys revoke``, another
  replica) reaches this one within that interval while the store is up.

The outage rule (README, "API keys"): a key known revoked is refused (401); a key
known active within :data:`KEY_CACHE_MAX_AGE_S` is accepted; any other key (never
seen, rotated away, or known only from too long ago) is unknown: 503, retry later.
A revocation made less than one refresh interval before the outage, or during it,
is enforced once the store returns.

A process that has never read the key table (it started during an outage) knows no
key: every request would be 503, so ``/readyz`` answers 503 until it has read it
(:attr:`KeyStates.loaded`) and a balancer routes around the process. No snapshot is
kept on disk: one could not honour a revocation made while this process was down.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import Any, Final

from sqlalchemy import select
from sqlalchemy.exc import DBAPIError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError
from sqlalchemy.orm import Session, sessionmaker

from service.db.tables import ApiKey

__all__ = ["KEY_CACHE_MAX_AGE_S", "KeyRefresher", "KeyState", "KeyStates", "Verdict"]

log = logging.getLogger("aacn_triage.keys")

#: Seconds what this process knew of a key still counts while the store cannot be
#: read. [R] Long enough to ride out a database maintenance window.
KEY_CACHE_MAX_AGE_S: Final[float] = 24 * 3600.0


class Verdict(Enum):
    """A key's state during an outage."""

    ACTIVE = "active"
    REVOKED = "revoked"
    UNKNOWN = "unknown"


@dataclass(frozen=True)
class KeyState:
    """What was known of one key hash, and when (monotonic s).

    `caller` is the authenticated caller (``service.auth.Caller``) of an active
    key, None for a revoked or unknown one.
    """

    caller: object | None
    known_at: float


class KeyStates:
    """Key hash -> :class:`KeyState`, safe to share between threads."""

    def __init__(self) -> None:
        self._states: dict[str, KeyState] = {}
        self._lock = threading.Lock()
        self._loaded = False

    @property
    def loaded(self) -> bool:
        """Whether the key table was read at least once (a snapshot was taken)."""
        return self._loaded

    def seen_active(self, digest: str, caller: object) -> None:
        """A request read this key from the store: active."""
        with self._lock:
            self._states[digest] = KeyState(caller, time.monotonic())

    def seen_refused(self, digest: str) -> None:
        """A request read this key from the store: unknown or revoked.

        Only a key held already is marked (so random keys do not fill the table).
        """
        with self._lock:
            if digest in self._states:
                self._states[digest] = KeyState(None, time.monotonic())

    def replace(self, states: dict[str, KeyState], taken_at: float) -> None:
        """Take a snapshot of the key table read from `taken_at` (monotonic s) on.

        The snapshot is the truth at that time; only what requests learnt after it
        began is kept over it (a key rotated away drops out).
        """
        with self._lock:
            for digest, old in self._states.items():
                if old.known_at > taken_at:
                    states[digest] = old
            self._states = states
            self._loaded = True

    def verdict(self, digest: str) -> tuple[Verdict, object | None]:
        """The outage rule (module docstring) for one key hash, and its caller if active."""
        with self._lock:
            state = self._states.get(digest)
        if state is None:
            return Verdict.UNKNOWN, None
        if state.caller is None:
            # a refusal does not go stale: a revoked key never becomes active again
            return Verdict.REVOKED, None
        if time.monotonic() - state.known_at > KEY_CACHE_MAX_AGE_S:
            return Verdict.UNKNOWN, None
        return Verdict.ACTIVE, state.caller


def snapshot(
    sessions: sessionmaker[Session], make_caller: Callable[[Any], object]
) -> tuple[dict[str, KeyState], float]:
    """Every key of the store as a :class:`KeyState` (``make_caller(row)`` for active ones),
    and the monotonic time the read began.

    Raises the store's errors (``DBAPIError``, pool timeout).
    """
    at = time.monotonic()
    with sessions() as session:
        rows = session.execute(
            select(ApiKey.id, ApiKey.name, ApiKey.role, ApiKey.key_sha256, ApiKey.revoked_at)
        ).all()
    states = {
        row.key_sha256: KeyState(None if row.revoked_at is not None else make_caller(row), at)
        for row in rows
    }
    return states, at


class KeyRefresher:
    """Daemon thread: a snapshot of the key table every `interval_s` (store errors skipped)."""

    def __init__(
        self,
        states: KeyStates,
        sessions: sessionmaker[Session],
        make_caller: Callable[[Any], object],
        interval_s: float,
    ) -> None:
        self._states = states
        self._sessions = sessions
        self._make_caller = make_caller
        self._interval_s = interval_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="key-refresher", daemon=True)

    def refresh(self) -> bool:
        """One snapshot now; False when the store could not be read."""
        try:
            self._states.replace(*snapshot(self._sessions, self._make_caller))
        except (DBAPIError, PoolTimeoutError) as exc:
            log.debug("key table not refreshed: %s", type(exc).__name__)
            return False
        return True

    def start(self) -> None:
        self.refresh()
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)

    def _run(self) -> None:
        while not self._stop.wait(self._interval_s):
            try:
                self.refresh()
            except Exception:  # never end the thread: the next interval tries again
                log.exception("key table refresh failed")
