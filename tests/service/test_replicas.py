"""Replicas behind a real nginx, one killed mid-load (issue 33; `tests.replicas`).

Three ``aacn-triage serve`` processes on one real PostgreSQL database behind
Debian's nginx with the repository's site configuration. Several hundred POSTs
from several threads, some replaying an earlier ``event_id`` and some conflicting
with it; one replica is killed with SIGKILL mid-load and started again. Every
acknowledged case is stored exactly once under the case id it was answered with,
replays and 409s hold whichever replica answers, nginx routes around the dead
replica and back to it once restarted, and no client is left with a 5xx (the ones
it may retry, and why: `tests.replicas`).
"""

from __future__ import annotations

import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text

from tests.replicas import LoadPlan, Nginx, Replica, find_nginx, prepare_database, run_load
from tests.support import free_port

pytestmark = pytest.mark.postgres

#: Replicas behind nginx (the recipe's figure).
REPLICAS = 3


@pytest.fixture
def database(postgres_admin_url: str) -> Iterator[str]:
    name = "aacn_lb_" + uuid.uuid4().hex[:8]
    admin = create_engine(postgres_admin_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    try:
        yield postgres_admin_url.rsplit("/", 1)[0] + "/" + name
    finally:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


def test_a_replica_killed_mid_load_loses_and_doubles_nothing(database: str, tmp_path: Path) -> None:
    binary = find_nginx()
    if binary is None:
        pytest.skip("no nginx binary: apt-get install nginx (.ci/run installs it)")
    env, key = prepare_database(database, tmp_path)
    replicas = [Replica(i, free_port(), tmp_path, env) for i in range(REPLICAS)]
    nginx = Nginx(binary, tmp_path, [r.address for r in replicas])
    try:
        replicas[0].start()  # the first start fills the shared numba cache when it is cold
        replicas[0].wait_ready()
        for r in replicas[1:]:
            r.start()
        for r in replicas[1:]:
            r.wait_ready()
        nginx.start()
        report = run_load(nginx, replicas, key, LoadPlan(), database, victim=1)
    finally:
        nginx.stop()
        for r in replicas:
            r.stop()
    figures = report.figures()
    assert not report.problems(), (report.problems()[:20], figures)
    assert figures["duplicates"] == 0
    assert figures["lost"] == 0
    assert figures["stored"] == figures["events_acknowledged"]
    assert figures["conflict_409"] > 0, "the plan holds conflicts"
    assert figures["replayed_200"] > 0, "the plan holds replays"
    assert figures["served_by_killed_after_restart"] > 0, "nginx sends to the restarted replica"
