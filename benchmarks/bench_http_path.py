"""What POST /v1/cases costs beyond the engine: the HTTP, JSON and database path.

Run: ``PYTHONPATH=TREE python benchmarks/bench_http_path.py [--requests N]
[--engine real|replayed] [--profile]``. Prints figures only (no RESULTS.md section:
the speed notes quote it). ``TREE`` is the checkout measured, so that two commits
can be compared in alternate runs on the same machine.

The app is built as ``serve`` builds it (``create_app``, its lifespan: migration of a
fresh SQLite file with ``synchronous=FULL``, the models loaded) and called as ASGI in
process, without a socket: the request as uvicorn hands it over, the answer's bytes
collected. Each request is the issue's two-occupant notification (the decision pins'
``readme_two_occupants``) with a new ``event_id``, so each one runs the engine and
commits a case.

* ``--engine real``: the engine runs; the engine's own time (``triage``, timed around
  the call) is subtracted from each request's.
* ``--engine replayed``: ``triage`` answers the result it computed once for this
  notification (the same object each time), so what is measured is the path alone,
  with less noise.

Per request: wall time, and CPU time of the process (every thread: the event loop,
the threadpool, SQLite). Medians and p90 of N after 20 warm-up requests.
``--profile``: cProfile of the event loop's thread and of the worker threads, the
top functions by cumulative time of each.
"""

from __future__ import annotations

import argparse
import asyncio
import cProfile
import io
import json
import pstats
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.append(str(ROOT))  # the tests' notifications, after the measured TREE

from tests.decision_pins import readme_two_occupants  # noqa: E402

WARM_UP_REQUESTS = 20


class _Timer:
    """Wall time spent inside the engine's `triage` during one request."""

    def __init__(self) -> None:
        self.engine_s = 0.0


def _instrument(mode: str, timer: _Timer) -> None:
    from service.cases import service as cases_service

    real = cases_service.triage
    cached: dict[int, Any] = {}

    def timed(notification: Any, models: Any) -> Any:
        t0 = time.perf_counter()
        try:
            if mode == "replayed":
                if 0 not in cached:
                    cached[0] = real(notification, models)
                return cached[0]
            return real(notification, models)
        finally:
            timer.engine_s += time.perf_counter() - t0

    cases_service.triage = timed  # type: ignore[assignment]


async def _request(app: Any, body: bytes, key: str) -> tuple[int, bytes]:
    scope = {
        "type": "http",
        "asgi": {"version": "3.0", "spec_version": "2.3"},
        "http_version": "1.1",
        "method": "POST",
        "scheme": "http",
        "path": "/v1/cases",
        "raw_path": b"/v1/cases",
        "root_path": "",
        "query_string": b"",
        "headers": [
            (b"host", b"127.0.0.1:8000"),
            (b"authorization", f"Bearer {key}".encode()),
            (b"content-type", b"application/json"),
            (b"content-length", str(len(body)).encode()),
        ],
        "client": ("127.0.0.1", 50000),
        "server": ("127.0.0.1", 8000),
        "state": {},
    }
    sent = False

    async def receive() -> dict[str, Any]:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        await asyncio.sleep(3600)
        return {"type": "http.disconnect"}

    status = 0
    chunks: list[bytes] = []

    async def send(message: dict[str, Any]) -> None:
        nonlocal status
        if message["type"] == "http.response.start":
            status = message["status"]
        elif message["type"] == "http.response.body":
            chunks.append(message.get("body", b""))

    await app(scope, receive, send)
    return status, b"".join(chunks)


def _quantile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


async def _run(args: argparse.Namespace, work: Path) -> dict[str, Any]:
    from service.app import create_app
    from service.auth import Role, create_api_key
    from service.settings import Settings

    settings = Settings(
        database_url=f"sqlite:///{work / 'bench.db'}",
        spool_path=work / "spool.db",
        key_refresh_interval_s=3600.0,
        spool_replay_interval_s=3600.0,
    )
    app = create_app(settings)
    timer = _Timer()
    _instrument(args.engine, timer)
    doc = readme_two_occupants()
    if args.profile:  # every thread started from here on (the threadpool's)
        threading.setprofile(_thread_profiler)
    async with app.router.lifespan_context(app):
        _, key = create_api_key(app.state.ctx.sessions, name="bench", role=Role.ADMIN)
        walls, cpus, engines = [], [], []
        profiles = (cProfile.Profile(), _THREAD_PROFILES) if args.profile else None
        for i in range(WARM_UP_REQUESTS + args.requests):
            body = json.dumps({**doc, "event_id": f"bench-{i}-{time.time_ns()}"}).encode()
            timer.engine_s = 0.0
            measuring = i >= WARM_UP_REQUESTS
            if profiles is not None and measuring:
                profiles[0].enable()
            c0, t0 = time.process_time(), time.perf_counter()
            status, answer = await _request(app, body, key)
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            if profiles is not None and measuring:
                profiles[0].disable()
            if status != 201:
                raise SystemExit(f"POST answered {status}: {answer[:300]!r}")
            if measuring:
                walls.append(1000.0 * wall)
                cpus.append(1000.0 * cpu)
                engines.append(1000.0 * timer.engine_s)
        threading.setprofile(None)  # type: ignore[arg-type]
    beyond = [w - e for w, e in zip(walls, engines, strict=True)]
    out: dict[str, Any] = {
        "engine": args.engine,
        "requests": args.requests,
        "wall_p50_ms": statistics.median(walls),
        "wall_p90_ms": _quantile(walls, 0.9),
        "engine_p50_ms": statistics.median(engines),
        "beyond_engine_p50_ms": statistics.median(beyond),
        "beyond_engine_p90_ms": _quantile(beyond, 0.9),
        "cpu_p50_ms": statistics.median(cpus),
        "answer_bytes": len(answer),
    }
    if profiles is not None:
        out["profile_loop"] = _top(profiles[0], args.top)
        out["profile_threads"] = _top(list(_THREAD_PROFILES.values()), args.top)
    return out


#: One profile per worker thread (a cProfile profile follows one thread).
_THREAD_PROFILES: dict[int, cProfile.Profile] = {}


def _thread_profiler(*_: Any) -> None:
    """A `threading.setprofile` hook: each new thread's calls into a profile of its own."""
    sys.setprofile(None)
    profile = _THREAD_PROFILES.setdefault(threading.get_ident(), cProfile.Profile())
    profile.enable()


def _top(profile: cProfile.Profile | list[cProfile.Profile], n: int) -> str:
    out = io.StringIO()
    many = profile if isinstance(profile, list) else [profile]
    if not many:
        return ""
    stats = pstats.Stats(many[0], stream=out)
    for more in many[1:]:
        stats.add(more)
    stats.sort_stats("cumulative").print_stats(n)
    text = out.getvalue()
    return text[text.index("ncalls") :] if "ncalls" in text else text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=200, help="measured POSTs")
    parser.add_argument("--engine", choices=("real", "replayed"), default="replayed")
    parser.add_argument("--profile", action="store_true", help="cProfile the requests")
    parser.add_argument("--top", type=int, default=45, help="profile lines")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-http-") as tmp:
        figures = asyncio.run(_run(args, Path(tmp)))
    for key in ("profile_loop", "profile_threads"):
        if key in figures:
            print(f"--- {key}\n{figures.pop(key)}")
    print(json.dumps({k: round(v, 3) if isinstance(v, float) else v for k, v in figures.items()}))


if __name__ == "__main__":
    main()
