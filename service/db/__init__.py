"""Persistence: typed tables, engine/session factory, the repository, migrations."""
