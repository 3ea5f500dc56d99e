"""What the commands share: output lines, the settings, a database session factory."""

from __future__ import annotations

import sys
from typing import Any

__all__ = ["echo", "load_settings", "open_sessions"]


def echo(text: str, *, err: bool = False) -> None:
    stream = sys.stderr if err else sys.stdout
    stream.write(text + "\n")
    stream.flush()


def load_settings() -> Any:
    from service.settings import get_settings

    return get_settings()


def open_sessions() -> Any:
    from service.db import migrate
    from service.db.session import make_engine, make_sessionmaker

    settings = load_settings()
    if settings.auto_migrate:
        migrate.upgrade(settings.database_url)
    return make_sessionmaker(make_engine(settings.database_url))
