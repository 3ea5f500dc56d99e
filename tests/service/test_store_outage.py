"""The store fails under load: every answered case is stored exactly once.

A real PostgreSQL cluster of the test's own is made read-only, then stopped
(``pg_ctl stop``) and started again while threads keep POSTing notifications to
the app. Cases answered while the store is out are recorded in the spool (202,
``stored: false``, ``spooled: true``) and replayed into the store once it returns;
in the end every answered notification is stored once, under the case id it was
answered with, none lost, none doubled, and no request got a 5xx.
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import create_engine, text
from sqlalchemy.pool import NullPool

from service.app import create_app
from service.auth import Role, create_api_key
from service.settings import Settings
from tests.support import summary

pytestmark = pytest.mark.postgres

#: Bounds of the test's loops, s (it stops by itself).
PHASE_S = 1.5
OUTAGE_S = 2.5
DRAIN_TIMEOUT_S = 60.0


def _database(admin_url: str) -> str:
    name = "aacn_outage_" + uuid.uuid4().hex[:8]
    admin = create_engine(admin_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    admin.dispose()
    return admin_url.rsplit("/", 1)[0] + "/" + name


def _set_read_only(admin_url: str, on: bool) -> None:
    """Make the cluster read-only (or writable) and wait until the reload has taken.

    ``pg_reload_conf()`` only signals the postmaster; a fresh session showing the
    new value means it has reloaded and signalled the open sessions (the app's
    pooled ones apply it before their next command).
    """
    admin = create_engine(admin_url, isolation_level="AUTOCOMMIT", poolclass=NullPool)
    value = "on" if on else "off"
    with admin.connect() as conn:
        conn.execute(text(f"ALTER SYSTEM SET default_transaction_read_only = {value}"))
        conn.execute(text("SELECT pg_reload_conf()"))
    deadline = time.monotonic() + 30.0
    while time.monotonic() < deadline:
        with admin.connect() as conn:
            if conn.execute(text("SHOW default_transaction_read_only")).scalar() == value:
                break
        time.sleep(0.05)
    else:
        raise AssertionError(f"default_transaction_read_only never became {value}")
    admin.dispose()


class _Load:
    """Threads POSTing fresh notifications until stopped; every answer recorded."""

    def __init__(self, client: TestClient, key: str, threads: int = 2) -> None:
        self.client = client
        self.headers = {"Authorization": f"Bearer {key}"}
        self.answers: list[tuple[str, int, dict[str, Any]]] = []
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._threads = [threading.Thread(target=self._run) for _ in range(threads)]

    def _run(self) -> None:
        while not self._stop.is_set():
            body = summary(event_id=f"load-{uuid.uuid4().hex}")
            response = self.client.post("/v1/cases", json=body, headers=self.headers)
            with self._lock:
                self.answers.append((body["event_id"], response.status_code, response.json()))

    def __enter__(self) -> _Load:
        for t in self._threads:
            t.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        for t in self._threads:
            t.join(60)

    def wait_for(self, status: int, after: int = 0, timeout_s: float = 60.0) -> None:
        """Wait until an answer with ``status`` arrives after the first ``after`` answers.

        The phases of a load test are judged by what the clients saw, not by the clock: on
        a shared machine two threads may send nothing for seconds.
        """
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            with self._lock:
                if any(s == status for _, s, _ in self.answers[after:]):
                    return
            time.sleep(0.05)

    def count(self) -> int:
        with self._lock:
            return len(self.answers)


@pytest.fixture
def outage_app(own_postgres: Any, tmp_path: Path) -> Iterator[tuple[TestClient, str, Any]]:
    url = _database(own_postgres.admin_url)
    settings = Settings(
        database_url=url, spool_path=tmp_path / "spool.db", spool_replay_interval_s=0.2
    )
    app = create_app(settings)
    with TestClient(app) as client:
        _, key = create_api_key(app.state.ctx.sessions, name="center", role=Role.ADMIN)
        yield client, key, app.state.ctx


def _drain(client: TestClient, ctx: Any) -> None:
    deadline = time.monotonic() + DRAIN_TIMEOUT_S
    while ctx.spool.pending() and time.monotonic() < deadline:
        time.sleep(0.2)
    assert ctx.spool.pending() == 0, "the spool was replayed into the store"


def _stored(ctx: Any) -> dict[str, list[str]]:
    with ctx.db_engine.connect() as conn:
        rows = conn.execute(text("SELECT event_id, id FROM cases")).all()
    out: dict[str, list[str]] = {}
    for event_id, case_id in rows:
        out.setdefault(event_id, []).append(case_id)
    return out


def _check_exactly_once(answers: list[tuple[str, int, dict[str, Any]]], ctx: Any) -> None:
    statuses = {status for _, status, _ in answers}
    assert statuses <= {201, 202}, f"statuses {statuses}: {[a for a in answers if a[1] >= 300]}"
    stored = _stored(ctx)
    for event_id, status, body in answers:
        assert stored.get(event_id) == [body["case_id"]], (event_id, status)
        assert body["stored"] is (status == 201)
        assert body["spooled"] is (status == 202)
    assert len(stored) == len(answers), "nothing stored that was not answered"


def test_read_only_store_spools_then_recovers_without_restart(
    outage_app: tuple[TestClient, str, Any], own_postgres: Any
) -> None:
    client, key, ctx = outage_app
    h = {"Authorization": f"Bearer {key}"}
    before = client.post("/v1/cases", json=summary(), headers=h)
    assert before.status_code == 201
    assert client.get("/readyz").json()["status"] == "ready"

    _set_read_only(own_postgres.admin_url, True)
    try:
        ready = client.get("/readyz")
        assert ready.status_code == 200, "the spool records cases: degraded, still ready"
        assert ready.json()["status"] == "degraded"
        assert "SQLSTATE 25006" in ready.json()["store"], "read-only transaction noticed"
        body = summary(event_id="evt-read-only")
        spooled = client.post("/v1/cases", json=body, headers=h)
        assert spooled.status_code == 202, spooled.text
        assert spooled.json()["stored"] is False
        assert spooled.json()["spooled"] is True
        replay = client.post("/v1/cases", json=body, headers=h)
        assert replay.status_code == 200
        assert replay.json()["case_id"] == spooled.json()["case_id"]
    finally:
        _set_read_only(own_postgres.admin_url, False)

    _drain(client, ctx)
    assert client.get("/readyz").json()["status"] == "ready", "no restart needed"
    got = client.get(f"/v1/cases/{spooled.json()['case_id']}", headers=h)
    assert got.status_code == 200
    assert got.json()["notification"] == body
    again = client.post("/v1/cases", json=body, headers=h)
    assert again.status_code == 200
    assert again.json()["case_id"] == spooled.json()["case_id"]
    assert again.json()["stored"] is True
    after = client.post("/v1/cases", json=summary(), headers=h)
    assert after.status_code == 201, "fresh connections write again"


def test_postgres_stopped_and_started_under_load_loses_and_doubles_nothing(
    outage_app: tuple[TestClient, str, Any], own_postgres: Any
) -> None:
    client, key, ctx = outage_app
    with _Load(client, key) as load:
        time.sleep(PHASE_S)
        load.wait_for(201)
        own_postgres.pg_ctl("stop", "-m", "fast")
        try:
            time.sleep(OUTAGE_S)
            load.wait_for(202)
            ready = client.get("/readyz")
            assert ready.status_code == 200
            assert ready.json()["status"] == "degraded"
            listing = client.get("/v1/cases", headers={"Authorization": f"Bearer {key}"})
            assert listing.status_code == 503, "reads need the store: 503, not 500"
        finally:
            restarted_after = load.count()
            own_postgres.pg_ctl("start")
        time.sleep(PHASE_S)
        load.wait_for(201, after=restarted_after)
    answers = load.answers
    assert any(s == 202 for _, s, _ in answers), "some cases were answered from the spool"
    assert any(s == 201 for _, s, _ in answers)
    _drain(client, ctx)
    first = client.post("/v1/cases", json=summary(), headers={"Authorization": f"Bearer {key}"})
    assert first.status_code == 201
    _check_exactly_once([*answers, (first.json()["event_id"], 201, first.json())], ctx)
