"""Two service processes on one PostgreSQL database.

Two ``aacn-triage serve`` processes, each its own connection pool, on one real
PostgreSQL database: 20 threads racing on one event id store one case (same
body: every answer is that case; different bodies: the others get 409), and a
load of distinct notifications spread over both loses nothing.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import threading
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx2 as httpx
import pytest
from sqlalchemy import create_engine, text

from tests.support import create_key, free_port, summary, wait_ready

pytestmark = pytest.mark.postgres

#: Racing threads on one event id (the issue's figure).
RACERS = 20


@pytest.fixture(scope="module")
def two_servers(
    postgres_admin_url: str, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[tuple[list[str], str, str]]:
    exe = shutil.which("aacn-triage")
    if exe is None:
        pytest.skip("the console script is not installed (pip install -e .)")
    tmp = tmp_path_factory.mktemp("two")
    name = "aacn_two_" + uuid.uuid4().hex[:8]
    admin = create_engine(postgres_admin_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    url = postgres_admin_url.rsplit("/", 1)[0] + "/" + name
    env = {**os.environ, "AACN_DATABASE_URL": url, "AACN_WORKERS": "1"}
    key = create_key([exe], env, "admin", "center")
    servers: list[tuple[subprocess.Popen[bytes], Path]] = []
    bases = []
    try:
        for i in range(2):
            port = free_port()
            log = tmp / f"server{i}.log"
            proc_env = {**env, "AACN_SPOOL_PATH": str(tmp / f"spool{i}.db")}
            with log.open("w") as sink:
                proc = subprocess.Popen(
                    [exe, "serve", "--port", str(port)],
                    env=proc_env,
                    stdout=sink,
                    stderr=subprocess.STDOUT,
                )
            servers.append((proc, log))
            bases.append(f"http://127.0.0.1:{port}")
        for base, (proc, log) in zip(bases, servers, strict=True):
            wait_ready(base, proc, log)
        yield bases, key, url
    finally:
        for proc, _ in servers:
            proc.terminate()
        for proc, _ in servers:
            proc.wait(timeout=60)
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


def _race(bases: list[str], key: str, bodies: list[dict[str, Any]]) -> list[httpx.Response]:
    start = threading.Barrier(len(bodies))
    answers: list[httpx.Response | None] = [None] * len(bodies)

    def post(i: int) -> None:
        with httpx.Client(timeout=60) as client:
            start.wait()
            answers[i] = client.post(
                bases[i % 2] + "/v1/cases",
                json=bodies[i],
                headers={"Authorization": f"Bearer {key}"},
            )

    threads = [threading.Thread(target=post, args=(i,)) for i in range(len(bodies))]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert all(a is not None for a in answers)
    return [a for a in answers if a is not None]


def _cases_of(url: str, event_id: str) -> list[str]:
    engine = create_engine(url)
    try:
        with engine.connect() as conn:
            rows = conn.execute(
                text("SELECT id FROM cases WHERE event_id = :e"), {"e": event_id}
            ).all()
    finally:
        engine.dispose()
    return [r[0] for r in rows]


def test_race_on_one_event_same_body(two_servers: tuple[list[str], str, str]) -> None:
    bases, key, url = two_servers
    body = summary(event_id="race-same")
    answers = _race(bases, key, [body] * RACERS)
    statuses = sorted(a.status_code for a in answers)
    assert statuses == [200] * (RACERS - 1) + [201], statuses
    stored = _cases_of(url, "race-same")
    assert len(stored) == 1
    assert {a.json()["case_id"] for a in answers} == set(stored)


def test_race_on_one_event_different_bodies(two_servers: tuple[list[str], str, str]) -> None:
    bases, key, url = two_servers
    variants = [summary(20.0 + 5 * (i % 4), event_id="race-mixed") for i in range(RACERS)]
    answers = _race(bases, key, variants)
    stored = _cases_of(url, "race-mixed")
    assert len(stored) == 1
    winners = [i for i, a in enumerate(answers) if a.status_code == 201]
    assert len(winners) == 1
    winning_dv = variants[winners[0]]["crash"]["pulse"]["delta_v_kmh"]
    for body, answer in zip(variants, answers, strict=True):
        same = body["crash"]["pulse"]["delta_v_kmh"] == winning_dv
        assert answer.status_code in ((200, 201) if same else (409,)), answer.text
        if same:
            assert answer.json()["case_id"] == stored[0]


def test_load_over_both_processes_loses_nothing(two_servers: tuple[list[str], str, str]) -> None:
    bases, key, url = two_servers
    bodies = [summary(10.0 + i, event_id=f"load2-{uuid.uuid4().hex}") for i in range(24)]
    answers = _race(bases, key, bodies)
    assert [a.status_code for a in answers] == [201] * len(bodies)
    for body, answer in zip(bodies, answers, strict=True):
        assert _cases_of(url, body["event_id"]) == [answer.json()["case_id"]]
