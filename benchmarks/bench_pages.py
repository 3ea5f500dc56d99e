"""Case page benchmark: server-side time to render a stored case as HTML.

Run: ``python benchmarks/bench_pages.py [--renders N]``. Prints the figures and
rewrites the "case-page" section of ``benchmarks/RESULTS.md``.

Cases: the three documented examples, a five-occupant case with rollover, and the
largest pulse the contract accepts (60,000 acceleration samples a series, drawn
after min/max decimation). Two measures per case, median and p99 over N renders:

- render: ``service.pages.views.case_page`` on the stored documents (view model, SVG
  geometry, Jinja2), the work of the page itself;
- request: the server's own time for ``GET /v1/cases/{id}/report`` through the
  ASGI app on a SQLite file (authentication, the read of the stored case and
  the render), from its ``Server-Timing`` header; and the wall time of the
  in-process request, for scale.

Target (issue 25): under 200 ms server time.
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import platform
import statistics
import tempfile
import time
import uuid
from datetime import UTC, datetime
from typing import Any

from results_md import RESULTS, write_section

TARGET_MS = 200.0


def _stats(samples_ms: list[float]) -> tuple[float, float]:
    ms = sorted(samples_ms)
    p99 = ms[min(len(ms) - 1, math.ceil(0.99 * len(ms)) - 1)]
    return statistics.median(ms), p99


def _cases() -> dict[str, dict[str, Any]]:
    from service.cases.examples import EXAMPLE_NOTIFICATIONS

    cases = {f"example {k}": copy.deepcopy(v["value"]) for k, v in EXAMPLE_NOTIFICATIONS.items()}
    five = copy.deepcopy(EXAMPLE_NOTIFICATIONS["delta_v"]["value"])
    five["crash"]["rollover"] = True
    five["crash"]["multiple_impacts"] = True
    for seat in ("rear_left", "rear_middle", "rear_right"):
        five["occupants"].append(
            {"seat": seat, "body": "female_5th", "belted": True, "frontal_airbag": "absent"}
        )
    cases["five occupants, rollover"] = five
    big = copy.deepcopy(EXAMPLE_NOTIFICATIONS["acceleration"]["value"])
    n, rate, dur_ms, dv_kmh = 60_000, 20_000.0, 90.0, 48.0
    amp = 2.0 * dv_kmh / 3.6 / (9.80665 * dur_ms / 1000.0)
    lon = [
        round(-amp * math.sin(math.pi * (1000.0 * i / rate) / dur_ms) ** 2, 2)
        if 1000.0 * i / rate <= dur_ms
        else 0.0
        for i in range(n)
    ]
    big["crash"]["pulse"] = {
        "kind": "acceleration",
        "sample_rate_hz": rate,
        "longitudinal_g": lon,
        "lateral_g": [0.0] * n,
    }
    cases["acceleration, 60,000 samples"] = big
    return cases


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--renders", type=int, default=100, help="renders per case")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    from fastapi.testclient import TestClient

    from service.app import create_app
    from service.auth import Role, create_api_key
    from service.cases import service as cases_service
    from service.pages import views as report
    from service.settings import Settings

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        settings = Settings(database_url=f"sqlite:///{tmp}/bench.db", max_body_bytes=4_000_000)
        app = create_app(settings)
        with TestClient(app) as client:
            ctx = app.state.ctx
            _, key = create_api_key(ctx.sessions, name="bench", role=Role.ADMIN)
            headers = {"Authorization": f"Bearer {key}"}
            chrome = {"root": "", "signed_in": True, "logout_token": ""}
            for name, body in _cases().items():
                body["event_id"] = f"bench-{uuid.uuid4().hex}"
                body["occurred_at"] = datetime.now(UTC).isoformat()
                r = client.post("/v1/cases", json=body, headers=headers)
                assert r.status_code == 201, r.text
                case_id = r.json()["case_id"]
                record = cases_service.load_case_record(ctx.sessions, case_id)
                assert record is not None
                html = report.case_page(record, now=datetime.now(UTC), chrome=chrome)  # warm
                render_ms = []
                for _ in range(args.renders):
                    t0 = time.perf_counter()
                    report.case_page(record, now=datetime.now(UTC), chrome=chrome)
                    render_ms.append(1000.0 * (time.perf_counter() - t0))
                url = f"/v1/cases/{case_id}/report"
                assert client.get(url, headers=headers).status_code == 200  # warm
                server_ms, wall_ms = [], []
                for _ in range(args.renders):
                    t0 = time.perf_counter()
                    got = client.get(url, headers=headers)
                    wall_ms.append(1000.0 * (time.perf_counter() - t0))
                    assert got.status_code == 200
                    timing = got.headers["server-timing"]
                    server_ms.append(float(timing.split("dur=")[1].split(";")[0]))
                rows.append(
                    (
                        name,
                        len(body["occupants"]),
                        len(html) / 1024.0,
                        *_stats(render_ms),
                        *_stats(server_ms),
                        *_stats(wall_ms),
                    )
                )

    worst = max(max(r[4], r[6]) for r in rows)
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    lines = [
        "## Case page",
        "",
        f"`python benchmarks/bench_pages.py` ({now}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs, Python {platform.python_version()}; load average "
        f"{load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}: other sessions share the machine). "
        f"Server-side time to draw `GET /v1/cases/{{id}}/report` from the stored case, median "
        f"and p99 over {args.renders} renders each. *render*: `service.pages.views.case_page` "
        "(view model, SVG geometry, Jinja2); *server*: the request's own `Server-Timing` "
        "(authentication, one read of the stored case, render), through the ASGI app on "
        "SQLite; *wall*: the in-process request, for scale.",
        "",
        "| case | occupants | HTML (KiB) | render median | render p99 | server median "
        "| server p99 | wall median | wall p99 |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| {n} | {k} | {kib:.0f} | {a:.1f} | {b:.1f} | {c:.1f} | {d:.1f} | {e:.1f} | {f:.1f} |"
        for n, k, kib, a, b, c, d, e, f in rows
    ]
    verdict = "within" if worst < TARGET_MS else "OVER"
    lines += [
        "",
        f"All times in ms. Largest p99 (render or server): {worst:.1f} ms, {verdict} the "
        f"{TARGET_MS:.0f} ms target of issue 25.",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("case-page", text)
        print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
