"""Load benchmark: real `aacn-triage serve` processes under concurrent POSTs, and batch rates.

Run: ``python benchmarks/bench_load.py [--seconds S] [--connections C] [--batch N]``.
Prints the figures and rewrites the "Load" section of ``benchmarks/RESULTS.md``.

HTTP: the installed console script serves on a loopback port with ``--workers 1``,
then ``--workers 2`` (same machine, same run), on a fresh SQLite file each. A
closed loop of C connections (keep-alive, stdlib ``http.client``, one thread each)
POSTs the two-occupant EDR example with a fresh event id for S seconds; every
answer must be 201 (anything else counts as an error). Unloaded latency: one
connection, 100 requests. The load generator runs on the same two cores as the
servers, so the figures are what this box can do, not the service alone.

Engine: `models.triage.triage` in this process on a single-occupant summary
notification and on the two-occupant EDR example, with OpenBLAS's default thread
count (before issue 24) and capped at one thread (what the service now does,
`service.context.limit_blas_threads`), side by side, interleaved in one run.

Batch: ``aacn-triage triage --batch`` on N notifications (the documented examples
at varied delta-V and PDOF), wall time including process start and model load,
with ``--workers 1`` and ``--workers 2``.
"""

from __future__ import annotations

import argparse
import copy
import http.client
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from results_md import RESULTS, write_section

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

#: Requests answered before timing starts (connection set-up, first-call costs).
WARM_REQUESTS = 10


def _pct(ms: list[float], q: float) -> float:
    s = sorted(ms)
    return s[min(len(s) - 1, round(q * (len(s) - 1)))]


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _body(template: dict[str, Any]) -> bytes:
    doc = copy.deepcopy(template)
    doc["event_id"] = f"load-{uuid.uuid4().hex}"
    return json.dumps(doc).encode()


class _Server:
    def __init__(self, exe: str, tmp: Path, workers: int) -> None:
        self.tmp = tmp / f"w{workers}"
        self.tmp.mkdir()
        self.env = {**os.environ, "AACN_DATABASE_URL": f"sqlite:///{self.tmp / 'load.db'}"}
        self.key = subprocess.run(
            [exe, "keys", "create", "--role", "admin", "--name", "load"],
            env=self.env,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        self.port = _free_port()
        self.log = (self.tmp / "server.log").open("w")
        self.proc = subprocess.Popen(
            [exe, "serve", "--port", str(self.port), "--workers", str(workers)],
            env=self.env,
            stdout=self.log,
            stderr=subprocess.STDOUT,
        )
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline:
            try:
                conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=2)
                conn.request("GET", "/readyz")
                if conn.getresponse().status == 200:
                    return
            except OSError:
                time.sleep(0.2)
        raise RuntimeError("server never became ready")

    def stop(self) -> None:
        self.proc.terminate()
        self.proc.wait(60)
        self.log.close()


def _post_loop(
    port: int, key: str, template: dict[str, Any], stop_at: float, n: int | None
) -> tuple[list[float], int]:
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
    headers = {"Authorization": f"Bearer {key}", "Content-Type": "application/json"}
    latencies: list[float] = []
    errors = 0
    done = 0
    while (n is None and time.perf_counter() < stop_at) or (n is not None and done < n):
        body = _body(template)
        t0 = time.perf_counter()
        try:
            conn.request("POST", "/v1/cases", body=body, headers=headers)
            response = conn.getresponse()
            response.read()
            ok = response.status == 201
        except OSError:
            conn.close()
            conn = http.client.HTTPConnection("127.0.0.1", port, timeout=60)
            ok = False
        latencies.append(1000.0 * (time.perf_counter() - t0))
        errors += not ok
        done += 1
    conn.close()
    return latencies, errors


def _load(server: _Server, template: dict[str, Any], connections: int, seconds: float) -> dict:
    _post_loop(server.port, server.key, template, 0.0, WARM_REQUESTS)
    results: list[tuple[list[float], int]] = []
    lock = threading.Lock()
    start = time.perf_counter()
    stop_at = start + seconds

    def run() -> None:
        out = _post_loop(server.port, server.key, template, stop_at, None)
        with lock:
            results.append(out)

    threads = [threading.Thread(target=run) for _ in range(connections)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    elapsed = time.perf_counter() - start
    ms = [x for lat, _ in results for x in lat]
    return {
        "requests": len(ms),
        "rps": len(ms) / elapsed,
        "p50": statistics.median(ms),
        "p99": _pct(ms, 0.99),
        "errors": sum(e for _, e in results),
    }


def _batch_input(path: Path, n: int) -> None:
    from service.schemas import EXAMPLE_NOTIFICATIONS

    kinds = sorted(EXAMPLE_NOTIFICATIONS)
    lines = []
    for i in range(n):
        doc = copy.deepcopy(EXAMPLE_NOTIFICATIONS[kinds[i % len(kinds)]]["value"])
        doc["event_id"] = f"batch-{i}"
        pulse = doc["crash"]["pulse"]
        if pulse["kind"] == "summary":
            pulse["delta_v_kmh"] = 10.0 + (i * 7) % 80
            pulse["pdof_deg"] = float((i * 37) % 360)
        lines.append(json.dumps(doc))
    path.write_text("\n".join(lines) + "\n")


def _batch(exe: str, src: Path, tmp: Path, workers: int, n: int) -> float:
    out = tmp / f"batch-{workers}.jsonl"
    t0 = time.perf_counter()
    subprocess.run(
        [exe, "triage", "--batch", str(src), "--out", str(out), "--workers", str(workers)],
        check=True,
        capture_output=True,
    )
    elapsed = time.perf_counter() - t0
    assert len(out.read_text().splitlines()) == n
    return n / elapsed


def _engine_side_by_side(repeats: int = 40) -> list[tuple[str, str, float, float]]:
    """Median and p95 ms per notification, BLAS threads default vs 1, interleaved."""
    from threadpoolctl import threadpool_info, threadpool_limits

    from models.triage import load_engine_models, triage
    from service.schemas import EXAMPLE_NOTIFICATIONS, CrashNotificationIn

    models = load_engine_models()
    default = max(
        (i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"), default=1
    )
    one = copy.deepcopy(EXAMPLE_NOTIFICATIONS["summary"]["value"])
    one["occupants"] = one["occupants"][:1]
    cases = {
        "summary, 1 occupant": one,
        "EDR delta-V, 2 occupants": EXAMPLE_NOTIFICATIONS["delta_v"]["value"],
    }
    rows = []
    for name, body in cases.items():
        engine_input, _ = CrashNotificationIn.model_validate(body).to_engine()
        samples: dict[int, list[float]] = {default: [], 1: []}
        for i in range(repeats + 3):
            for threads in (default, 1):
                with threadpool_limits(limits=threads, user_api="blas"):
                    t0 = time.perf_counter()
                    triage(engine_input, models)
                    if i >= 3:
                        samples[threads].append(1000.0 * (time.perf_counter() - t0))
        for threads, label in ((default, f"{default} (before)"), (1, "1 (now)")):
            ms = samples[threads]
            rows.append((name, label, statistics.median(ms), _pct(ms, 0.95)))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=20.0, help="load duration per run")
    parser.add_argument("--connections", type=int, default=8, help="concurrent connections")
    parser.add_argument("--batch", type=int, default=1000, help="notifications in the batch")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    from service.schemas import EXAMPLE_NOTIFICATIONS

    exe = shutil.which("aacn-triage")
    if exe is None:
        raise SystemExit("install the package first: pip install -e .")
    template = EXAMPLE_NOTIFICATIONS["delta_v"]["value"]
    assert len(template["occupants"]) == 2
    engine_rows = _engine_side_by_side()
    rows = []
    unloaded: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        for workers in (1, 2):
            server = _Server(exe, tmp, workers)
            try:
                if workers == 1:
                    lat, errors = _post_loop(server.port, server.key, template, 0.0, 100)
                    unloaded = {"p50": statistics.median(lat), "p99": _pct(lat, 0.99)}
                    assert errors == 0
                rows.append((workers, _load(server, template, args.connections, args.seconds)))
            finally:
                server.stop()
        src = tmp / "batch.jsonl"
        _batch_input(src, args.batch)
        batch = {w: _batch(exe, src, tmp, w, args.batch) for w in (1, 2)}

    one, two = rows[0][1], rows[1][1]
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg()
    lines = [
        "## Load",
        "",
        f"`python benchmarks/bench_load.py` ({now}, {platform.machine()}, {os.cpu_count()} "
        f"CPUs, Python {platform.python_version()}; load average {load[0]:.1f}, {load[1]:.1f}, "
        f"{load[2]:.1f}: other sessions share the machine; the load generator runs on the same "
        "cores). Real `aacn-triage serve` on a SQLite file, `POST /v1/cases` with the "
        "two-occupant EDR example, a fresh event each (engine and commit every time).",
        "",
        "Engine per notification in process (median and p95 of 40 calls each, the two "
        "settings interleaved):",
        "",
        "| notification | BLAS threads | median (ms) | p95 (ms) |",
        "|---|---|---:|---:|",
        *(f"| {n} | {t} | {a:.1f} | {b:.1f} |" for n, t, a, b in engine_rows),
        "",
        f"Unloaded, one connection, 100 requests, `--workers 1`: p50 {unloaded['p50']:.1f} ms, "
        f"p99 {unloaded['p99']:.1f} ms.",
        "",
        f"{args.connections} connections, {args.seconds:.0f} s closed loop:",
        "",
        "| serve | requests | requests/s | p50 (ms) | p99 (ms) | errors |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    lines += [
        f"| `--workers {w}` | {r['requests']} | {r['rps']:.1f} | {r['p50']:.0f} | "
        f"{r['p99']:.0f} | {r['errors']} |"
        for w, r in rows
    ]
    lines += [
        "",
        f"Throughput ratio, 2 workers / 1: {two['rps'] / one['rps']:.2f} (target >= 2, with "
        "p99 <= 250 ms).",
        "",
        f"`triage --batch`, {args.batch} notifications (wall time with start-up and model "
        f"load): {batch[1]:.0f}/s with `--workers 1`, {batch[2]:.0f}/s with `--workers 2` "
        f"(ratio {batch[2] / batch[1]:.2f}; the issue's figure on main: 66/s).",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("load", text)
        print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
