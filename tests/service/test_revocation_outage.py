"""A revoked key is refused whatever the store's state.

The key is revoked by another process (its own engine, as ``aacn-triage keys
revoke`` would) while PostgreSQL is up and the service has not seen the key since;
then the cluster is stopped. Posts with the revoked key get 401, not 202 spooled,
and nothing is stored under it once the store returns; a key still active is
spooled and stored as before, and a key the service never knew is 503 (unknown).
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import create_engine, text

from service.app import create_app
from service.auth import (
    Caller,
    Role,
    caller_of_row,
    create_api_key,
    hash_key,
    revoke_api_key,
    rotate_api_key,
)
from service.db import migrate
from service.db.session import make_sessionmaker
from service.key_cache import KeyState, KeyStates, Verdict, snapshot
from service.settings import Settings
from tests.service.test_store_outage import _database, _drain
from tests.support import summary

#: The service re-reads the key table this often in the test, s.
REFRESH_S = 0.3


@pytest.fixture
def keyed_app(own_postgres: Any, tmp_path: Path) -> Iterator[tuple[TestClient, str, Any]]:
    url = _database(own_postgres.admin_url)
    settings = Settings(
        database_url=url,
        spool_path=tmp_path / "spool.db",
        spool_replay_interval_s=0.2,
        key_refresh_interval_s=REFRESH_S,
    )
    app = create_app(settings)
    with TestClient(app) as client:
        yield client, url, app.state.ctx


def _post(client: TestClient, key: str, event_id: str | None = None) -> Any:
    body = summary(event_id=event_id or f"rev-{uuid.uuid4().hex}")
    return client.post("/v1/cases", json=body, headers={"Authorization": f"Bearer {key}"})


@pytest.mark.postgres
def test_a_key_revoked_before_an_outage_is_refused_during_it(
    keyed_app: tuple[TestClient, str, Any], own_postgres: Any
) -> None:
    client, url, ctx = keyed_app
    _, revoked = create_api_key(ctx.sessions, name="leaked", role=Role.SUBMITTER)
    _, good = create_api_key(ctx.sessions, name="center", role=Role.SUBMITTER)
    for _ in range(8):
        assert _post(client, revoked).status_code == 201
    assert _post(client, good).status_code == 201
    # revoked by another process: this one does not see it through a request
    other = create_engine(url)
    revoke_api_key(make_sessionmaker(other), "leaked")
    other.dispose()
    time.sleep(4 * REFRESH_S)
    own_postgres.pg_ctl("stop", "-m", "fast")
    try:
        refused = [_post(client, revoked, f"revoked-{i}") for i in range(4)]
        assert [r.status_code for r in refused] == [401] * 4, [r.text for r in refused]
        spooled = _post(client, good, "good-during-outage")
        assert spooled.status_code == 202, spooled.text
        assert spooled.json()["spooled"] is True
        # a key this process never knew: its state is unknown, 503 (retry later)
        unknown = _post(client, "aacn_" + uuid.uuid4().hex)
        assert unknown.status_code == 503, unknown.text
    finally:
        own_postgres.pg_ctl("start")
    _drain(client, ctx)
    with ctx.db_engine.connect() as conn:
        events = set(conn.execute(text("SELECT event_id FROM cases")).scalars())
    assert "good-during-outage" in events
    assert not any(e.startswith("revoked-") for e in events)


def _caller(name: str) -> Caller:
    return Caller(key_id=1, name=name, role=Role.SUBMITTER)


def test_the_key_table_snapshot_is_the_truth_at_its_time(sqlite_url: str) -> None:
    """Revoked and rotated-away keys drop out at the next snapshot; random keys are not kept."""
    engine = create_engine(sqlite_url)
    migrate.upgrade(sqlite_url)
    sessions = make_sessionmaker(engine)
    _, first = create_api_key(sessions, name="a", role=Role.SUBMITTER)
    _, second = create_api_key(sessions, name="b", role=Role.SUBMITTER)
    states = KeyStates()
    states.replace(*snapshot(sessions, caller_of_row))
    assert states.verdict(hash_key(first))[0] is Verdict.ACTIVE
    assert states.verdict(hash_key(second))[0] is Verdict.ACTIVE
    revoke_api_key(sessions, "a")
    _, rotated = rotate_api_key(sessions, "b")
    states.replace(*snapshot(sessions, caller_of_row))
    assert states.verdict(hash_key(first))[0] is Verdict.REVOKED
    assert states.verdict(hash_key(second))[0] is Verdict.UNKNOWN  # the old secret
    assert states.verdict(hash_key(rotated))[0] is Verdict.ACTIVE
    # a request's knowledge newer than the snapshot is kept; random keys are not recorded
    later = KeyStates()
    later.seen_active("x" * 64, _caller("x"))
    later.replace({}, taken_at=time.monotonic() - 10.0)
    assert later.verdict("x" * 64)[0] is Verdict.ACTIVE
    later.seen_refused("y" * 64)
    assert later.verdict("y" * 64)[0] is Verdict.UNKNOWN
    later.seen_refused("x" * 64)
    assert later.verdict("x" * 64)[0] is Verdict.REVOKED
    assert KeyState(None, 0.0).caller is None
    engine.dispose()
