"""Load benchmark: the engine and the batch before and after issue 24, and served load.

Run: ``python benchmarks/bench_load.py [--seconds S] [--connections C] [--batch N]
[--before REV]``. Prints the figures and rewrites the "Load" section of
``benchmarks/RESULTS.md``.

Before / after, same machine, same run: the tree of ``--before`` (default
:data:`BEFORE`, the main on which issue 24 measured the engine at 12.5 ms and the
batch at 66/s) is exported with ``git archive`` next to this checkout, and both
are timed in fresh processes (their own numba caches, one BLAS thread each),
alternated twice:

* Engine: ``models.triage.triage`` in process on a single-occupant summary
  notification, the two-occupant EDR example and the single-occupant
  acceleration example (median and p95 of the calls);
* Batch: ``triage --batch`` on N notifications (the documented examples at varied
  delta-V and PDOF), wall time including process start and model load, each tree
  with its own defaults: the old tree in one process (it has no ``--workers``),
  this one with ``--workers 1`` and ``--workers 2``.

HTTP: the installed console script serves on a loopback port with ``--workers 1``,
then ``--workers 2`` (same run), on a fresh SQLite file each. A closed loop of C
connections (keep-alive, stdlib ``http.client``, one thread each) POSTs the
two-occupant EDR example with a fresh event id for S seconds; every answer must
be 201 (anything else counts as an error). Unloaded latency: one connection, 100
requests. The load generator runs on the same two cores as the servers, so the
figures are what this box can do, not the service alone.
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

#: The main on which issue 24 was measured (engine 12.5 ms per single-occupant
#: notification, ``triage --batch`` 66/s): the "before" of the side-by-side runs.
BEFORE = "7e01712"

#: Engine timing in a fresh process of one tree (PYTHONPATH): JSON of ms per call.
_ENGINE_SCRIPT = """
import copy, json, sys, time
from threadpoolctl import threadpool_limits
from models.triage import load_engine_models, triage
from service.cases.examples import EXAMPLE_NOTIFICATIONS
from service.cases.notification import CrashNotificationIn
repeats = int(sys.argv[1])
one = copy.deepcopy(EXAMPLE_NOTIFICATIONS["summary"]["value"])
one["occupants"] = one["occupants"][:1]
cases = {
    "summary, 1 occupant": one,
    "EDR delta-V, 2 occupants": EXAMPLE_NOTIFICATIONS["delta_v"]["value"],
    "acceleration, 1 occupant": EXAMPLE_NOTIFICATIONS["acceleration"]["value"],
}
models = load_engine_models()
out = {}
with threadpool_limits(limits=1, user_api="blas"):
    for name, body in cases.items():
        engine = CrashNotificationIn.model_validate(body).to_engine()
        engine = engine[0] if isinstance(engine, tuple) else engine
        occupants = len(engine.occupants)
        for _ in range(5):
            triage(engine, models)
        ms = []
        cpu = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            c0 = time.thread_time()
            triage(engine, models)
            cpu.append(1000.0 * (time.thread_time() - c0))
            ms.append(1000.0 * (time.perf_counter() - t0))
        out[name] = {"occupants": occupants, "ms": ms, "cpu_ms": cpu}
print(json.dumps(out))
"""

#: ``aacn-triage`` of one tree (PYTHONPATH), for the old tree without its console script.
_CLI = "import sys; from service.cli.main import main; sys.exit(main(sys.argv[1:]))"


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
    from service.cases.examples import EXAMPLE_NOTIFICATIONS

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


def _export(rev: str, dest: Path) -> Path:
    """The tree of `rev` (this repository's history) exported into `dest`."""
    dest.mkdir(parents=True)
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev], check=True, capture_output=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(dest)], input=archive, check=True)
    return dest


def _tree_env(tree: Path, cache: Path, one_blas_thread: bool = True) -> dict[str, str]:
    """Environment of a process running `tree`'s code, with its own numba cache.

    With `one_blas_thread`, OpenBLAS gets one thread (the engine comparison: the
    code alone); without, the tree runs with its own defaults (the old main let
    OpenBLAS start a thread per core, which issue 24 capped).
    """
    env = {
        **os.environ,
        "PYTHONPATH": str(tree),
        "NUMBA_CACHE_DIR": str(cache),
        "AACN_NUMBA_CACHE_DIR": str(cache),
    }
    env.pop("OPENBLAS_NUM_THREADS", None)
    if one_blas_thread:
        env["OPENBLAS_NUM_THREADS"] = "1"
    return env


def _engine_before_after(trees: dict[str, Path], tmp: Path, repeats: int = 40) -> list[tuple]:
    """Median and p95 ms per notification and per occupant, each tree, alternated twice."""
    samples: dict[tuple[str, str], list[float]] = {}
    cpu: dict[tuple[str, str], list[float]] = {}
    occupants: dict[str, int] = {}
    for _round in range(2):
        for label, tree in trees.items():
            out = subprocess.run(
                [sys.executable, "-c", _ENGINE_SCRIPT, str(repeats)],
                env=_tree_env(tree, tmp / f"numba-{label}"),
                cwd=tree,
                capture_output=True,
                text=True,
                check=True,
            ).stdout
            for name, rec in json.loads(out.strip().splitlines()[-1]).items():
                samples.setdefault((name, label), []).extend(rec["ms"])
                cpu.setdefault((name, label), []).extend(rec["cpu_ms"])
                occupants[name] = rec["occupants"]
    rows = []
    for (name, label), ms in samples.items():
        med = statistics.median(ms)
        cpu_med = statistics.median(cpu[(name, label)])
        rows.append(
            (name, label, med, _pct(ms, 0.95), med / occupants[name], cpu_med / occupants[name])
        )
    return rows


def _batch(tree: Path, tmp: Path, src: Path, label: str, workers: int | None, n: int) -> float:
    """Notifications per second of ``triage --batch`` (wall time with start-up)."""
    out = tmp / f"batch-{label}-{workers}.jsonl"
    argv = ["triage", "--batch", str(src), "--out", str(out)]
    if workers is not None:
        argv += ["--workers", str(workers)]
    t0 = time.perf_counter()
    subprocess.run(
        [sys.executable, "-c", _CLI, *argv],
        env=_tree_env(tree, tmp / f"numba-{label}", one_blas_thread=False),
        cwd=tree,
        check=True,
        capture_output=True,
    )
    elapsed = time.perf_counter() - t0
    assert len(out.read_text().splitlines()) == n
    return n / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--seconds", type=float, default=20.0, help="load duration per run")
    parser.add_argument("--connections", type=int, default=8, help="concurrent connections")
    parser.add_argument(
        "--batch", type=int, default=9713, help="notifications in the batch (the issue's 9,713)"
    )
    parser.add_argument("--before", default=BEFORE, help="git revision of the 'before' runs")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    from service.cases.examples import EXAMPLE_NOTIFICATIONS

    exe = shutil.which("aacn-triage")
    if exe is None:
        raise SystemExit("install the package first: pip install -e .")
    template = EXAMPLE_NOTIFICATIONS["delta_v"]["value"]
    assert len(template["occupants"]) == 2
    rows = []
    unloaded: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        trees = {"before": _export(args.before, tmp / "before"), "now": ROOT}
        engine_rows = _engine_before_after(trees, tmp)
        src = tmp / "batch.jsonl"
        _batch_input(src, args.batch)
        batch = {
            "before": _batch(trees["before"], tmp, src, "before", None, args.batch),
            "now 1": _batch(ROOT, tmp, src, "now", 1, args.batch),
            "now 2": _batch(ROOT, tmp, src, "now", 2, args.batch),
        }
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

    one, two = rows[0][1], rows[1][1]
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg()
    label = {"before": f"before (`{args.before}`)", "now": "now"}
    lines = [
        "## Load",
        "",
        f"`python benchmarks/bench_load.py` ({now}, {platform.machine()}, {os.cpu_count()} "
        f"CPUs, Python {platform.python_version()}; load average {load[0]:.1f}, {load[1]:.1f}, "
        f"{load[2]:.1f}: other sessions share the machine; the load generator runs on the same "
        f"cores). Before: the tree of `{args.before}` (the main issue 24 measured), exported "
        "and run side by side with this one in fresh processes, one BLAS thread each, "
        "alternated twice.",
        "",
        "Engine per notification in process (`models.triage.triage`; median and p95 of 80 "
        "calls each, wall time; and the median of the calling thread's CPU time, which the "
        "other sessions on the machine do not inflate):",
        "",
        "| notification | code | median (ms) | p95 (ms) | median per occupant (ms) "
        "| CPU per occupant (ms) |",
        "|---|---|---:|---:|---:|---:|",
        *(
            f"| {n} | {label[c]} | {a:.1f} | {b:.1f} | {p:.1f} | {u:.1f} |"
            for n, c, a, b, p, u in sorted(engine_rows, key=lambda r: (r[0], r[1] != "before"))
        ),
        "",
        "Target (issue 24): per occupant <= 5 ms in process (the wall-time median).",
        "",
        f"`triage --batch`, {args.batch} notifications (the documented examples at varied "
        "delta-V and PDOF; wall time with start-up and model load; each tree with its own "
        "defaults, so before with OpenBLAS's thread per core):",
        "",
        "| code | processes | notifications/s | ratio to before |",
        "|---|---:|---:|---:|",
        f"| {label['before']} | 1 (no `--workers`) | {batch['before']:.0f} | 1.00 |",
        f"| now | `--workers 1` | {batch['now 1']:.0f} | {batch['now 1'] / batch['before']:.2f} |",
        f"| now | `--workers 2` | {batch['now 2']:.0f} | {batch['now 2'] / batch['before']:.2f} |",
        "",
        "Target (issue 24): `--workers 2` at 3x the rate before.",
        "",
        "HTTP: real `aacn-triage serve` on a SQLite file, `POST /v1/cases` with the "
        "two-occupant EDR example, a fresh event each (engine and commit every time).",
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
        f"p99 <= 250 ms: p99 {two['p99']:.0f} ms).",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("load", text)
        print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
