"""A reset of the store's connection pool leaves no connection for the garbage collector.

After a store error the pool is replaced (``ServiceContext.reset_store_connections``); a
connection checked out at that moment comes back to the replaced pool. It is closed at
the next reset, or when the app shuts down, never left open for the garbage collector
(whose psycopg ResourceWarning can land in any later test).
"""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import text

from service.app import create_app
from service.settings import Settings


def _is_closed(raw: sqlite3.Connection) -> bool:
    try:
        raw.execute("SELECT 1")
    except sqlite3.ProgrammingError:
        return True
    return False


@pytest.mark.parametrize("closed_by", ["next_reset", "shutdown"])
def test_a_connection_checked_out_at_a_reset_is_closed_later(
    sqlite_url: str, tmp_path: Path, closed_by: str
) -> None:
    app = create_app(Settings(database_url=sqlite_url, spool_path=tmp_path / "spool.db"))
    with TestClient(app):
        ctx = app.state.ctx
        conn = ctx.db_engine.connect()
        conn.execute(text("SELECT 1"))
        raw = conn.connection.dbapi_connection
        assert isinstance(raw, sqlite3.Connection)
        ctx._last_reset = 0.0  # the reset's rate limit aside
        ctx.reset_store_connections()
        conn.close()  # back to the replaced pool, still open there
        assert not _is_closed(raw)
        if closed_by == "next_reset":
            ctx._last_reset = 0.0
            ctx.reset_store_connections()
            assert _is_closed(raw)
    assert _is_closed(raw)
