"""Alembic: upgrade and downgrade on both databases; migrations match the tables."""

from __future__ import annotations

import multiprocessing
from typing import Any

import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from sqlalchemy import inspect

from service.db import migrate
from service.db.session import make_engine
from service.db.tables import Base

TABLES = {
    "api_keys",
    "cases",
    "case_occupants",
    "idempotency_records",
    "health_probe",
    "occupant_outcomes",
}


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


def _migrate_at(url: str, start: Any, out: Any) -> None:
    """In a process of its own (Alembic's ``context`` is one per process): migrate at once."""
    start.wait(60)
    try:
        migrate.upgrade(url)
    except Exception as exc:  # reported to the test
        out.put(f"{type(exc).__name__}: {exc}")
    else:
        out.put("ok")


@pytest.mark.postgres
def test_processes_migrating_at_once_take_turns(postgres_url: str) -> None:
    """Workers or replicas whose store just returned migrate at the same moment: the
    advisory lock of migrations/env.py lets one migrate and the others find it done."""
    ctx = multiprocessing.get_context("spawn")
    start, out = ctx.Barrier(3), ctx.Queue()
    procs = [ctx.Process(target=_migrate_at, args=(postgres_url, start, out)) for _ in range(3)]
    for p in procs:
        p.start()
    results = [out.get(timeout=240) for _ in procs]
    for p in procs:
        p.join(60)
    assert results == ["ok"] * 3
    assert migrate.current_revision(postgres_url) == migrate.head_revision()
