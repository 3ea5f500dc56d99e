"""Spreading keep-alive connections over `serve --workers N` (service.balance)."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import PlainTextResponse
from starlette.routing import Route

from service.app import create_app
from service.balance import LOADS_ENV, MAX_WORKERS, ConnectionBalance, WorkerLoads
from service.settings import Settings
from tests.support import console_server


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


@pytest.fixture
def loads(tmp_path: Path) -> Iterator[WorkerLoads]:
    table = WorkerLoads(WorkerLoads.create(tmp_path / "loads"))
    yield table
    table.close()


def test_fair_share_is_the_mean_load_rounded_up(loads: WorkerLoads, tmp_path: Path) -> None:
    other = WorkerLoads(tmp_path / "loads")
    assert loads.claim() != other.claim(os.getppid())  # two live workers, two slots
    assert loads.fair_share() == 1  # nothing in flight: a share of one
    loads.add(5)
    other.add(3)
    assert (loads.mine(), other.mine(), loads.fair_share()) == (5, 3, 4)
    other.add(-1)
    assert loads.fair_share() == 4  # 7 over 2, rounded up
    other.close()  # released: one worker left, holding everything
    assert loads.fair_share() == 5


def test_slots_of_dead_workers_are_reclaimed_and_the_table_bounded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = WorkerLoads.create(tmp_path / "loads")
    dead = WorkerLoads(path)
    slot = dead.claim(_dead_pid())
    dead.add(7)
    fresh = WorkerLoads(path)
    assert fresh.claim() == slot  # the dead worker's slot, its count cleared
    assert fresh.mine() == 0
    assert fresh.fair_share() == 1
    # every other slot taken by a live worker (pids that pass for alive): full
    monkeypatch.setattr("service.balance._alive", lambda pid: True)
    others = [WorkerLoads(path) for _ in range(MAX_WORKERS - 1)]
    for i, table in enumerate(others):
        table.claim(10_000_000 + i)
    with pytest.raises(RuntimeError, match="full"):
        WorkerLoads(path).claim(20_000_000)
    for table in [fresh, *others]:
        table.close()
    dead.slot = None
    dead.close()


def _app(loads: WorkerLoads) -> Starlette:
    async def hello(request: Request) -> PlainTextResponse:
        return PlainTextResponse("hello")

    app = Starlette(routes=[Route("/", hello)])
    app.add_middleware(ConnectionBalance, loads=loads)
    return app


def test_a_worker_over_its_share_asks_the_client_to_reconnect(
    loads: WorkerLoads, tmp_path: Path
) -> None:
    other = WorkerLoads(tmp_path / "loads")
    other.claim(os.getppid())
    loads.claim()
    with TestClient(_app(loads)) as client:
        r = client.get("/")  # 1 in flight here, 0 there: the share is 1
        assert r.status_code == 200
        assert "connection" not in r.headers
        assert loads.mine() == 0  # counted out again
        loads.add(2)  # two more requests held by this worker, none by the other
        r = client.get("/")
        assert r.headers["connection"] == "close"
        other.add(2)  # the other worker as busy: back within the share
        r = client.get("/")
        assert "connection" not in r.headers
    other.close()


def test_the_app_claims_a_slot_while_it_serves(tmp_path: Path) -> None:
    path = WorkerLoads.create(tmp_path / "loads")
    settings = Settings(database_url=f"sqlite:///{tmp_path / 'db.sqlite'}", worker_loads_path=path)
    watch = WorkerLoads(path)
    with TestClient(create_app(settings)) as client:
        assert client.get("/livez").status_code == 200
        assert watch._table[0] == os.getpid()  # claimed at start-up
    assert watch._table[0] == 0  # released at shutdown
    watch.close()


def _children(pid: int) -> list[int]:
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat.parent.name))
    return out


def _environ(pid: int) -> dict[str, str]:
    raw = Path(f"/proc/{pid}/environ").read_bytes().decode(errors="replace")
    return dict(kv.split("=", 1) for kv in raw.split("\0") if "=" in kv)


def _claimed(path: Path) -> set[int]:
    table = WorkerLoads(path)
    pids = {int(table._table[2 * s]) for s in range(MAX_WORKERS)} - {0}
    table.slot = None  # only looking: close() must not release anything
    table.close()
    return pids


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_serve_with_two_workers_gives_them_one_table(tmp_path: Path) -> None:
    """Both worker processes of `serve --workers 2` claim a slot of the same table."""
    with console_server(tmp_path, "--workers", "2") as (proc, _base, _key, _log):
        deadline = time.monotonic() + 120
        while True:
            workers = {c: _environ(c).get(LOADS_ENV) for c in _children(proc.pid)}
            workers = {c: p for c, p in workers.items() if p}
            paths = set(workers.values())
            claimed = _claimed(Path(paths.pop())) if len(paths) == 1 else set()
            # two of the children (the workers; another is multiprocessing's tracker)
            if len(claimed) == 2 and claimed <= set(workers):
                break
            assert time.monotonic() < deadline, (workers, claimed)
            time.sleep(0.2)
