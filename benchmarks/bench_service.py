"""Service benchmark: engine time per notification and POST /v1/cases latency.

Run: ``python benchmarks/bench_service.py [--requests N]``. Prints the figures
and rewrites the "Service" section of ``benchmarks/RESULTS.md``.

Engine: `models.triage.triage` on each documented example (summary, EDR
delta-V, acceleration) and on an out-of-coverage case (baseline only).
HTTP: POST through the ASGI app (FastAPI TestClient, in process) on a SQLite
file, each request a new event, so every one runs the engine and commits; plus
GET of a stored case.
"""

from __future__ import annotations

import argparse
import copy
import os
import platform
import statistics
import tempfile
import time
import uuid
from collections.abc import Callable
from datetime import UTC, datetime
from typing import Any

from results_md import RESULTS, write_section


def _percentiles(samples_s: list[float]) -> tuple[float, float]:
    ms = sorted(1000.0 * s for s in samples_s)
    p95 = ms[min(len(ms) - 1, round(0.95 * (len(ms) - 1)))]
    return statistics.median(ms), p95


def _time(fn: Callable[[], object], repeats: int) -> tuple[float, float]:
    fn()  # warm
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return _percentiles(samples)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=60, help="POSTs per example")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    from fastapi.testclient import TestClient

    from models.triage import load_engine_models, triage
    from service.app import create_app
    from service.auth import Role, create_api_key
    from service.cases.examples import EXAMPLE_NOTIFICATIONS
    from service.cases.notification import CrashNotificationIn
    from service.settings import Settings

    t0 = time.perf_counter()
    models = load_engine_models()
    load_s = time.perf_counter() - t0

    cases: dict[str, dict[str, Any]] = {
        k: copy.deepcopy(v["value"]) for k, v in EXAMPLE_NOTIFICATIONS.items()
    }
    oblique = copy.deepcopy(cases["summary"])
    oblique["crash"]["pulse"]["pdof_deg"] = 50.0
    cases["summary, outside coverage (baseline)"] = oblique

    rows = []
    for name, body in cases.items():
        engine_input, _ = CrashNotificationIn.model_validate(body).to_engine()
        result = triage(engine_input, models)
        methods = "/".join(sorted({o.method for o in result.occupants}))
        med, p95 = _time(lambda e=engine_input: triage(e, models), 30)
        rows.append((name, len(result.occupants), methods, med, p95))

    http_rows = []
    with tempfile.TemporaryDirectory() as tmp:
        app = create_app(Settings(database_url=f"sqlite:///{tmp}/bench.db"))
        with TestClient(app) as client:
            _, key = create_api_key(app.state.ctx.sessions, name="bench", role=Role.ADMIN)
            headers = {"Authorization": f"Bearer {key}"}
            location = ""
            for name, body in cases.items():
                samples = []
                for _ in range(args.requests):
                    fresh = dict(body, event_id=f"bench-{uuid.uuid4().hex}")
                    t = time.perf_counter()
                    r = client.post("/v1/cases", json=fresh, headers=headers)
                    samples.append(time.perf_counter() - t)
                    assert r.status_code == 201, r.text
                    location = r.headers["Location"]
                http_rows.append((f"POST {name}", *_percentiles(samples)))
            samples = []
            for _ in range(args.requests):
                t = time.perf_counter()
                assert client.get(location, headers=headers).status_code == 200
                samples.append(time.perf_counter() - t)
            http_rows.append(("GET /v1/cases/{id}", *_percentiles(samples)))

    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    lines = [
        "## Service",
        "",
        f"`python benchmarks/bench_service.py` ({now}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs, Python {platform.python_version()}; load average "
        f"{load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}: other sessions share the machine). "
        f"Model load and warm-up at start: {load_s:.2f} s.",
        "",
        "Engine, `models.triage.triage` per notification (median and p95 of 30 calls):",
        "",
        "| notification | occupants | method | median (ms) | p95 (ms) |",
        "|---|---:|---|---:|---:|",
    ]
    lines += [f"| {n} | {k} | {m} | {a:.1f} | {b:.1f} |" for n, k, m, a, b in rows]
    lines += [
        "",
        f"HTTP through the ASGI app on SQLite ({args.requests} requests each; POST runs "
        "the engine and commits the case before answering):",
        "",
        "| request | median (ms) | p95 (ms) |",
        "|---|---:|---:|",
    ]
    lines += [f"| {n} | {a:.1f} | {b:.1f} |" for n, a, b in http_rows]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("service", text)
        print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
