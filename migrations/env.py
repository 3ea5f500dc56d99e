"""Alembic environment: URL from the caller (config attributes) or the settings."""

from __future__ import annotations

from alembic import context
from sqlalchemy import Connection, text

from service.db.session import make_engine, normalise_url
from service.db.tables import Base

config = context.config
target_metadata = Base.metadata

#: PostgreSQL advisory lock key held by a migration for its transaction, so that
#: processes migrating at once (workers, or replicas whose store just returned) run
#: one after the other: the later ones find the schema at head. Any fixed 64-bit value.
MIGRATION_LOCK_KEY = 0x41AC_4E17


def _url() -> str:
    url = config.attributes.get("database_url") or config.get_main_option("sqlalchemy.url")
    if not url:
        from service.settings import get_settings

        url = get_settings().database_url
    return normalise_url(str(url))


def _run(connection: Connection) -> None:
    context.configure(
        connection=connection,
        target_metadata=target_metadata,
        compare_type=True,
        render_as_batch=connection.dialect.name == "sqlite",
    )
    with context.begin_transaction():
        if connection.dialect.name == "postgresql":
            connection.execute(
                text("SELECT pg_advisory_xact_lock(:key)"), {"key": MIGRATION_LOCK_KEY}
            )
        context.run_migrations()


def run_migrations_offline() -> None:
    context.configure(url=_url(), target_metadata=target_metadata, literal_binds=True)
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_online() -> None:
    connection = config.attributes.get("connection")
    if connection is not None:
        _run(connection)
        return
    engine = make_engine(_url())
    try:
        with engine.connect() as conn:
            _run(conn)
    finally:
        engine.dispose()


if context.is_offline_mode():
    run_migrations_offline()
else:
    run_migrations_online()
