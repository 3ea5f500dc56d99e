"""A replica restarted while PostgreSQL is down waits for it, then takes notifications.

The replica test's recipe (``tests.replicas``: ``aacn-triage serve`` processes on one
real PostgreSQL database, their own spools), here two replicas. PostgreSQL is stopped;
the first replica keeps acknowledging notifications from its spool (``202``). The
second is restarted during the outage with the default ``AACN_AUTO_MIGRATE=true``:
it must not exit (it used to, with a traceback from the migration), says so in one
log line, and answers ``/readyz`` 503 because it has never read the key table and so
can verify no API key (a balancer routes around it); a POST to it is a clear 503 to
retry. PostgreSQL is started again: the restarted replica migrates, reads the keys,
becomes ready and takes notifications; every acknowledged case is stored once.
"""

from __future__ import annotations

import os
import subprocess
import time
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest

from tests.replicas import (
    CLI,
    READY_TIMEOUT_S,
    SESSION_SECRET,
    Replica,
    prepare_database,
    read_store,
)
from tests.service.test_store_outage import _database
from tests.support import free_port, summary

pytestmark = pytest.mark.postgres


def _wait_alive(replica: Replica) -> None:
    """Until the replica answers /livez (it binds its port once warm), or fail if it exits."""
    assert replica.proc is not None
    deadline = time.monotonic() + READY_TIMEOUT_S
    while time.monotonic() < deadline:
        if replica.proc.poll() is not None:
            raise AssertionError(f"the replica exited: {replica.log.read_text()[-3000:]}")
        try:
            if httpx.get(replica.base + "/livez", timeout=2.0).status_code == 200:
                return
        except httpx.TransportError:
            pass
        time.sleep(0.1)
    raise AssertionError(f"the replica never answered: {replica.log.read_text()[-3000:]}")


def _post(replica: Replica, key: str, event_id: str) -> Any:
    return httpx.post(
        replica.base + "/v1/cases",
        json=summary(event_id=event_id),
        headers={"Authorization": f"Bearer {key}"},
        timeout=60.0,
    )


def test_a_replica_restarted_during_an_outage_waits_and_loses_nothing(
    own_postgres: Any, tmp_path: Path
) -> None:
    url = _database(own_postgres.admin_url)
    env, key = prepare_database(url, tmp_path)
    steady = Replica(0, free_port(), tmp_path, env)
    restarted = Replica(1, free_port(), tmp_path, {**env, "AACN_AUTO_MIGRATE": "true"})
    acknowledged: dict[str, str] = {}
    try:
        for replica in (steady, restarted):
            replica.start()
            replica.wait_ready()
        for replica in (steady, restarted):
            r = _post(replica, key, f"before-{replica.index}")
            assert r.status_code == 201, r.text
            acknowledged[r.json()["event_id"]] = r.json()["case_id"]

        own_postgres.pg_ctl("stop", "-m", "fast")
        try:
            spooled = _post(steady, key, "during-outage")
            assert spooled.status_code == 202, spooled.text
            acknowledged["during-outage"] = spooled.json()["case_id"]
            restarted.stop()
            restarted.start()
            _wait_alive(restarted)
            ready = httpx.get(restarted.base + "/readyz", timeout=30.0)
            assert ready.status_code == 503, ready.text
            assert "no API key can be verified" in ready.json()["detail"]
            assert "migration runs once it returns" in ready.json()["detail"]
            refused = _post(restarted, key, "to-the-restarted")
            assert refused.status_code == 503, refused.text
            assert refused.headers["Retry-After"]
            assert httpx.get(steady.base + "/readyz", timeout=30.0).json()["status"] == "degraded"
            assert restarted.proc is not None
            assert restarted.proc.poll() is None, "still serving"
        finally:
            own_postgres.pg_ctl("start")

        restarted.wait_ready()
        taken = _post(restarted, key, "after-outage")
        assert taken.status_code == 201, taken.text
        acknowledged["after-outage"] = taken.json()["case_id"]
        replay = _post(restarted, key, "to-the-restarted")  # refused before: stored now, once
        assert replay.status_code == 201, replay.text
        acknowledged["to-the-restarted"] = replay.json()["case_id"]
        log = restarted.log.read_text(errors="replace").split("--- start 2", 1)[1]
        assert log.count("the store is unreachable") == 1, "one clear line, not one per attempt"
        assert "current_revision" not in log, "no traceback of the migration"
        assert "the schema is at head" in log
    finally:
        for replica in (steady, restarted):
            replica.stop()
    stored = read_store(url, set(acknowledged.values()))
    assert {event: ids for (_, event), ids in stored.items()} == {
        event: [case_id] for event, case_id in acknowledged.items()
    }


def test_serve_starts_without_its_store_and_migrates_when_it_returns(
    own_postgres: Any, tmp_path: Path
) -> None:
    """A fresh database that was never migrated: the migration runs once the store is back."""
    url = _database(own_postgres.admin_url)  # empty: no table yet
    env = {
        **os.environ,
        "AACN_DATABASE_URL": url,
        "AACN_WORKERS": "1",
        "AACN_SESSION_SECRET": SESSION_SECRET,
        "AACN_AUTO_MIGRATE": "true",
    }
    replica = Replica(0, free_port(), tmp_path, env)
    own_postgres.pg_ctl("stop", "-m", "fast")
    try:
        try:
            replica.start()
            _wait_alive(replica)
            assert httpx.get(replica.base + "/readyz", timeout=30.0).status_code == 503
        finally:
            own_postgres.pg_ctl("start")
        replica.wait_ready()
        key = subprocess.run(
            [*CLI, "keys", "create", "--role", "submitter", "--name", "after"],
            env=env,
            capture_output=True,
            text=True,
            check=True,
            timeout=300,
        ).stdout.strip()
        taken = _post(replica, key, "first-case")
        assert taken.status_code == 201, taken.text
    finally:
        replica.stop()
