"""What the commands share: output lines, the settings, the database's sessions."""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the command line imports this module: nothing heavy at run time
    from sqlalchemy.orm import Session, sessionmaker

__all__ = ["echo", "load_settings", "open_sessions"]


def echo(text: str, *, err: bool = False) -> None:
    stream = sys.stderr if err else sys.stdout
    stream.write(text + "\n")
    stream.flush()


def load_settings() -> Any:
    from service.settings import get_settings

    return get_settings()


@contextmanager
def open_sessions() -> Iterator[sessionmaker[Session]]:
    """The database's session factory, migrated first if the settings say so.

    The engine behind it is disposed on leaving the block, so no connection is
    left to the garbage collector.
    """
    from service.db import migrate
    from service.db.session import make_engine, make_sessionmaker

    settings = load_settings()
    if settings.auto_migrate:
        migrate.upgrade(settings.database_url)
    engine = make_engine(settings.database_url)
    try:
        yield make_sessionmaker(engine)
    finally:
        engine.dispose()
