"""`aacn-triage serve --workers N` as a real server: headers, and SIGTERM."""

from __future__ import annotations

import json
import signal
import socket
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import httpx2 as httpx
import pytest

from tests.support import console_server, example

#: Requests in flight when SIGTERM arrives.
IN_FLIGHT = 10


@pytest.fixture
def served(tmp_path: Path) -> Iterator[tuple[subprocess.Popen[bytes], str, str, Path]]:
    with console_server(tmp_path, "--workers", "2") as running:
        yield running


def _raw_post(port: int, key: str, body: bytes) -> socket.socket:
    """Open a POST and send its head and the first half of its body (the rest: later)."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=60)
    head = (
        f"POST /v1/cases HTTP/1.1\r\nHost: 127.0.0.1\r\nAuthorization: Bearer {key}\r\n"
        f"Content-Type: application/json\r\nContent-Length: {len(body)}\r\n"
        "Connection: close\r\n\r\n"
    ).encode()
    sock.sendall(head + body[: len(body) // 2])
    return sock


def _read_all(sock: socket.socket) -> bytes:
    chunks = []
    while chunk := sock.recv(65536):
        chunks.append(chunk)
    sock.close()
    return b"".join(chunks)


def test_two_workers_answer_without_a_server_banner_and_log_json(
    served: tuple[subprocess.Popen[bytes], str, str, Path],
) -> None:
    server, base, key, log = served
    h = {"Authorization": f"Bearer {key}"}
    created = httpx.post(base + "/v1/cases", json=example("summary"), headers=h, timeout=60)
    assert created.status_code == 201, created.text
    assert "server" not in created.headers
    assert created.headers["x-content-type-options"] == "nosniff"
    assert all(httpx.get(base + "/livez", timeout=10).status_code == 200 for _ in range(10))
    lines = [json.loads(line) for line in log.read_text().splitlines() if line.startswith("{")]
    assert any(line["logger"] == "uvicorn.access" for line in lines), "JSON access log"
    assert all("time" in line and "level" in line for line in lines)


def test_sigterm_lets_in_flight_requests_finish(
    served: tuple[subprocess.Popen[bytes], str, str, Path],
) -> None:
    server, base, key, log = served
    port = int(base.rsplit(":", 1)[1])
    bodies = [json.dumps(example("delta_v")).encode() for _ in range(IN_FLIGHT)]
    # each request is in flight for certain when the signal comes: accepted, its
    # head and half its body received, the rest sent after the signal
    socks = [_raw_post(port, key, body) for body in bodies]
    time.sleep(0.5)
    server.send_signal(signal.SIGTERM)
    time.sleep(0.5)
    for sock, body in zip(socks, bodies, strict=True):
        sock.sendall(body[len(body) // 2 :])
    answers = [_read_all(s) for s in socks]
    for answer in answers:
        assert answer.startswith(b"HTTP/1.1 201"), answer[:300]
    assert server.wait(timeout=60) == 0, log.read_text()[-2000:]
    # requests were in flight at the signal: uvicorn waited for them, or answered some
    # after it began to shut down (the access log lines follow its "Shutting down")
    text = log.read_text()
    after = text.split("Shutting down", 1)[1] if "Shutting down" in text else ""
    assert "Waiting for connections to close" in text or '"uvicorn.access"' in after, (
        "requests were in flight"
    )
    with pytest.raises(httpx.TransportError):
        httpx.get(base + "/livez", timeout=2)
