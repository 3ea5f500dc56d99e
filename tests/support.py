"""Test support: the API client bundle, notification builders, problem checks."""

from __future__ import annotations

import copy
import os
import shutil
import subprocess
import uuid
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from service.cases.examples import EXAMPLE_NOTIFICATIONS
from service.settings import Settings


@dataclass
class ApiClient:
    """A TestClient plus one key per role."""

    client: TestClient
    keys: dict[str, str]
    settings: Settings

    def headers(self, role: str) -> dict[str, str]:
        return {"Authorization": f"Bearer {self.keys[role]}"}


def example(kind: str, *, event_id: str | None = None) -> dict[str, Any]:
    """A deep copy of a documented example with a fresh event_id."""
    body = copy.deepcopy(EXAMPLE_NOTIFICATIONS[kind]["value"])
    body["event_id"] = event_id or f"test-{uuid.uuid4().hex}"
    return body


def summary(
    delta_v_kmh: float = 56.0,
    pdof_deg: float = 0.0,
    *,
    belted: bool = True,
    airbag: str = "deployed",
    seat: str = "driver",
    event_id: str | None = None,
) -> dict[str, Any]:
    """A one-occupant summary-pulse notification."""
    body = example("summary", event_id=event_id)
    body["crash"]["pulse"] = {"kind": "summary", "delta_v_kmh": delta_v_kmh, "pdof_deg": pdof_deg}
    occ = body["occupants"][0]
    occ.update(seat=seat, belted=belted, frontal_airbag=airbag)
    return body


def post_case(api: ApiClient, body: dict[str, Any]) -> dict[str, Any]:
    """POST a JSON notification as the submitter; the 201 answer."""
    r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    assert r.status_code == 201, r.text
    result: dict[str, Any] = r.json()
    return result


def stored_case(api: ApiClient, case_id: str) -> dict[str, Any]:
    """GET a stored case as the auditor."""
    r = api.client.get(f"/v1/cases/{case_id}", headers=api.headers("auditor"))
    assert r.status_code == 200, r.text
    stored: dict[str, Any] = r.json()
    return stored


def assert_problem(response: Any, status: int) -> dict[str, Any]:
    """The response is an RFC 9457 problem with `status`; returns its body."""
    assert response.status_code == status, response.text
    assert response.headers["content-type"].startswith("application/problem+json")
    body: dict[str, Any] = response.json()
    for member in ("type", "title", "status", "detail"):
        assert member in body, f"problem lacks {member}: {body}"
    assert body["status"] == status
    return body


def free_port() -> int:
    """A free loopback TCP port."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def wait_ready(base: str, server: Any, log_path: Any, timeout_s: float = 120.0) -> None:
    """Wait until `base`/readyz answers 200 (a cold start on a busy machine is slow)."""
    import time

    import httpx2 as httpx

    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            if httpx.get(base + "/readyz", timeout=1.0).status_code == 200:
                return
        except httpx.TransportError:
            pass
        if server.poll() is not None:
            raise AssertionError(f"server exited: {log_path.read_text()[-3000:]}")
        time.sleep(0.1)
    raise AssertionError(f"server never became ready: {log_path.read_text()[-3000:]}")


def create_key(
    cli: Sequence[str], env: Mapping[str, str], role: str, name: str, timeout_s: float = 120.0
) -> str:
    """A new API key made by the command line (`cli` + ``keys create``), as it prints it."""
    return subprocess.run(
        [*cli, "keys", "create", "--role", role, "--name", name],
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=timeout_s,
    ).stdout.strip()


@contextmanager
def console_server(
    tmp_path: Path, *serve_args: str
) -> Iterator[tuple[subprocess.Popen[bytes], str, str, Path]]:
    """The installed ``aacn-triage serve`` on a free port, with an admin key, until ready.

    Yields ``(process, base URL, admin key, log path)``; the process is stopped
    afterwards if it still runs. Skips when the console script is not installed.
    """
    exe = shutil.which("aacn-triage")
    if exe is None:
        pytest.skip("the console script is not installed (pip install -e .)")
    env = {**os.environ, "AACN_DATABASE_URL": f"sqlite:///{tmp_path / 'served.db'}"}
    key = create_key([exe], env, "admin", "ops")
    port = free_port()
    log = tmp_path / "server.log"
    with log.open("w") as sink:
        server = subprocess.Popen(
            [exe, "serve", "--port", str(port), *serve_args],
            env=env,
            stdout=sink,
            stderr=subprocess.STDOUT,
        )
    base = f"http://127.0.0.1:{port}"
    try:
        wait_ready(base, server, log)
        yield server, base, key, log
    finally:
        if server.poll() is None:
            server.terminate()
            try:
                server.wait(timeout=30)
            except subprocess.TimeoutExpired:
                server.kill()
                server.wait(timeout=30)
