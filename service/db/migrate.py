"""Run Alembic programmatically against a URL (used by the CLI, the app and tests).

A service that starts while its store cannot be reached does not exit:
:func:`upgrade_or_wait` logs one line and :class:`MigrationRetry` migrates once the
store returns (``docs/deploy.md``, "A replica started during an outage").
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Final

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy.exc import OperationalError

import migrations
from service.db.session import make_engine, normalise_url

__all__ = [
    "MIGRATION_RETRY_INTERVAL_S",
    "MigrationRetry",
    "alembic_config",
    "current_revision",
    "downgrade",
    "head_revision",
    "upgrade",
    "upgrade_or_wait",
]

logger = logging.getLogger("aacn_triage")

#: Seconds between two migration attempts while the store cannot be reached. [R] A
#: stopped server refuses at once, an unreachable host costs the connect timeout
#: (``service.db.session.CONNECT_TIMEOUT_S``); the store's return is noticed within this.
MIGRATION_RETRY_INTERVAL_S: Final[float] = 2.0


def alembic_config(database_url: str) -> Config:
    """An Alembic config pointing at the packaged migrations and `database_url`."""
    cfg = Config()
    cfg.set_main_option("script_location", str(Path(migrations.__file__).parent))
    cfg.attributes["database_url"] = normalise_url(database_url)
    return cfg


def upgrade(database_url: str, revision: str = "head") -> None:
    """Migrate up to `revision`; logs one line when the schema changed (Alembic's own
    INFO lines are kept out of the service's log, `service.logs.log_config`)."""
    before = current_revision(database_url)
    command.upgrade(alembic_config(database_url), revision)
    after = current_revision(database_url)
    if after != before:
        logger.info(
            "database migrated", extra={"from_revision": before or "base", "to_revision": after}
        )


def downgrade(database_url: str, revision: str) -> None:
    command.downgrade(alembic_config(database_url), revision)


def head_revision() -> str | None:
    return ScriptDirectory.from_config(alembic_config("sqlite://")).get_current_head()


def current_revision(database_url: str) -> str | None:
    engine = make_engine(database_url)
    try:
        with engine.connect() as conn:
            return MigrationContext.configure(conn).get_current_revision()
    finally:
        engine.dispose()


def _unreachable(exc: OperationalError) -> str:
    """The error's driver type, never its text (which names hosts and ports)."""
    return type(getattr(exc, "orig", None) or exc).__name__


def upgrade_or_wait(database_url: str) -> bool:
    """Migrate to head now; False, with one WARNING line and no traceback, when the store
    cannot be reached (any other failure of the migration is raised)."""
    try:
        upgrade(database_url)
    except OperationalError as exc:
        logger.warning(
            "the store is unreachable (%s): serving without it; /readyz answers 503 until "
            "an API key can be verified, and the migration runs once the store returns",
            _unreachable(exc),
        )
        return False
    return True


class MigrationRetry:
    """Daemon thread: :func:`upgrade` every `interval_s` until it succeeds.

    Started when :func:`upgrade_or_wait` found the store unreachable. `done` is set
    once the schema is at head; `on_done` runs then (re-reading the key table).
    Attempts the store refuses are logged at DEBUG only (the start logged the outage).
    """

    def __init__(
        self,
        database_url: str,
        *,
        interval_s: float = MIGRATION_RETRY_INTERVAL_S,
        on_done: Callable[[], object] | None = None,
    ) -> None:
        self._url = database_url
        self._interval_s = interval_s
        self._on_done = on_done
        self.done = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="migration-retry", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)

    def _run(self) -> None:
        while not self._stop.wait(self._interval_s):
            try:
                upgrade(self._url)
            except OperationalError as exc:
                logger.debug("the store is still unreachable (%s)", _unreachable(exc))
                continue
            except Exception:  # a failed migration: logged, tried again (never ends the thread)
                logger.exception("the migration failed; trying again")
                continue
            logger.info("the store is reachable: the schema is at head")
            self.done.set()
            if self._on_done is not None:
                self._on_done()
            return
