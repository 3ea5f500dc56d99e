"""Occupant benchmark: the cost of a notification by its number of occupants.

Run: ``python benchmarks/bench_occupants.py [--requests N]``. Prints the figures
and rewrites the "Occupants" section of ``benchmarks/RESULTS.md``.

A minivan notification (45 km/h frontal) with 1, 2, 3, 5 and 9 occupants,
every seat the wire names, filled in one order: driver and front passenger
with everything known (the occupant models run), then the rear seats with
their ages unknown (the field risk model integrates over the unknown inputs).
Engine: `models.triage.triage` (median of 30 calls); HTTP: POST through the
ASGI app on a SQLite file (each request a new event, committed before the
answer). The cost per occupant should not grow with the number of occupants.
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

#: Seats in the order they are filled, and who sits there.
SEATS: list[dict[str, Any]] = [
    {"seat": "driver", "age_years": 44, "sex": "female", "stature_cm": 165, "mass_kg": 62},
    {"seat": "front_passenger", "age_years": 46, "sex": "male", "stature_cm": 180, "mass_kg": 85},
    {"seat": "rear_left"},
    {"seat": "rear_right"},
    {"seat": "rear_middle"},
    {"seat": "third_row_left"},
    {"seat": "third_row_right"},
    {"seat": "third_row_middle"},
    {"seat": "front_middle"},
]


def notification(n: int) -> dict[str, Any]:
    """The minivan notification with its first `n` seats filled."""
    occupants = []
    for s in SEATS[:n]:
        occ = {**s, "belted": True}
        occ["frontal_airbag"] = (
            "deployed" if s["seat"] in ("driver", "front_passenger", "front_middle") else "absent"
        )
        occupants.append(occ)
    return {
        "event_id": "bench",
        "occurred_at": "2026-11-23T08:15:30Z",
        "crash": {"pulse": {"kind": "summary", "delta_v_kmh": 45, "pdof_deg": 0}},
        "occupants": occupants,
    }


def _median_ms(fn: Callable[[], object], repeats: int) -> float:
    fn()
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        samples.append(1000.0 * (time.perf_counter() - t0))
    return statistics.median(samples)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=40, help="POSTs per notification")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    from fastapi.testclient import TestClient

    from models.triage import load_engine_models, triage
    from service.app import create_app
    from service.auth import Role, create_api_key
    from service.cases.notification import CrashNotificationIn
    from service.settings import Settings

    models = load_engine_models()
    counts = (1, 2, 3, 5, 9)
    engine_ms = {}
    for n in counts:
        engine_input, _ = CrashNotificationIn.model_validate(notification(n)).to_engine()
        engine_ms[n] = _median_ms(lambda e=engine_input: triage(e, models), 30)
    http_ms = {}
    with tempfile.TemporaryDirectory() as tmp:
        app = create_app(Settings(database_url=f"sqlite:///{tmp}/bench.db"))
        with TestClient(app) as client:
            _, key = create_api_key(app.state.ctx.sessions, name="bench", role=Role.ADMIN)
            headers = {"Authorization": f"Bearer {key}"}
            for n in counts:
                body = notification(n)

                def post(body: dict[str, Any] = body) -> None:
                    fresh = copy.deepcopy(body)
                    fresh["event_id"] = f"bench-{uuid.uuid4().hex}"
                    r = client.post("/v1/cases", json=fresh, headers=headers)
                    assert r.status_code == 201, r.text

                http_ms[n] = _median_ms(post, args.requests)

    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    lines = [
        "## Occupants",
        "",
        f"`python benchmarks/bench_occupants.py` ({now}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs, Python {platform.python_version()}; load average "
        f"{load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}: other sessions share the machine). A "
        "45 km/h frontal crash; the two front occupants fully described (the occupant models "
        "run), every further occupant with age, sex, stature and mass unknown (integrated over "
        "32 donors each by the field risk model). Medians: engine of 30 calls, POST of "
        f"{args.requests} requests.",
        "",
        "| occupants | engine (ms) | engine per occupant (ms) | POST (ms) "
        "| POST per occupant (ms) |",
        "|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {n} | {engine_ms[n]:.1f} | {engine_ms[n] / n:.1f} | {http_ms[n]:.1f} | "
        f"{http_ms[n] / n:.1f} |"
        for n in counts
    ]
    growth = (http_ms[9] / 9) / (http_ms[2] / 2)
    lines += [
        "",
        f"POST per occupant at nine over at two: {growth:.2f} (at most 1 means the cost grows "
        "no faster than the number of occupants).",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("occupants", text)
        print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
