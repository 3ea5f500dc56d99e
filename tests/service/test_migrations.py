"""Alembic: upgrade and downgrade on both databases; migrations match the tables."""

from __future__ import annotations

import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from sqlalchemy import inspect

from service.db import migrate
from service.db.session import make_engine
from service.db.tables import Base

TABLES = {"api_keys", "cases", "case_occupants", "idempotency_records", "health_probe"}


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def url(request: pytest.FixtureRequest) -> str:
    name = "sqlite_url" if request.param == "sqlite" else "postgres_url"
    return str(request.getfixturevalue(name))


def test_upgrade_downgrade_upgrade(url: str) -> None:
    migrate.upgrade(url)
    assert migrate.current_revision(url) == migrate.head_revision()
    engine = make_engine(url)
    try:
        assert TABLES <= set(inspect(engine).get_table_names())
        migrate.downgrade(url, "base")
        assert migrate.current_revision(url) is None
        assert not TABLES & set(inspect(engine).get_table_names())
        migrate.upgrade(url)
        assert TABLES <= set(inspect(engine).get_table_names())
    finally:
        engine.dispose()


def test_migrations_match_the_table_definitions(url: str) -> None:
    migrate.upgrade(url)
    engine = make_engine(url)
    try:
        with engine.connect() as conn:
            diff = compare_metadata(
                MigrationContext.configure(conn, opts={"compare_type": True}), Base.metadata
            )
    finally:
        engine.dispose()
    assert diff == [], f"the tables and the migrations disagree: {diff}"
