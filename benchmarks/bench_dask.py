"""Batch on Dask against the built-in pool, same machine, same run (issue 33).

Run: ``python benchmarks/bench_dask.py [--n N] [--rounds R]``. Prints the figures
and rewrites the "Dask" section of ``benchmarks/RESULTS.md``.

``triage --batch`` on N notifications (the documented examples at varied delta-V
and PDOF), with 1 and then 2 worker processes: the built-in pool (the models
loaded once in this process, the pool forked from it: ``service.jobs.batch.run_batch``)
against a ``dask.distributed`` `LocalCluster` on loopback (a scheduler and that many
single-threaded worker processes, the models loaded once per worker by a warm-up
run before timing; ``service.jobs.dask``). Steady throughput: model loading is
outside both timings. The two engines alternate, R rounds; the median is kept.
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import platform
import statistics
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from results_md import write_section

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

#: Worker counts compared (this machine has 2 cores).
WORKERS = (1, 2)


def _inputs(n: int) -> list[str]:
    from service.cases.examples import EXAMPLE_NOTIFICATIONS

    kinds = list(EXAMPLE_NOTIFICATIONS)
    out = []
    for i in range(n):
        body: dict[str, Any] = copy.deepcopy(EXAMPLE_NOTIFICATIONS[kinds[i % 3]]["value"])
        body["event_id"] = f"bench-{i}"
        pulse = body["crash"]["pulse"]
        if pulse["kind"] == "summary":
            pulse["delta_v_kmh"] = 15.0 + (i * 7) % 55
            pulse["pdof_deg"] = (i * 30) % 360
        out.append(json.dumps(body))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=600, help="notifications per run")
    parser.add_argument("--rounds", type=int, default=2, help="alternated rounds")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    from distributed import LocalCluster

    from service.jobs.batch import batch_record, run_batch
    from service.jobs.dask import triage_batch_on_dask
    from service.settings import get_settings

    settings = get_settings()
    work = Path(tempfile.mkdtemp(prefix="bench-dask-"))
    src = work / "in.jsonl"
    src.write_text("".join(t + "\n" for t in _inputs(args.n)), encoding="utf-8")
    warm = work / "warm.jsonl"
    warm.write_text("".join(t + "\n" for t in _inputs(24)), encoding="utf-8")
    rates: dict[tuple[str, int], list[float]] = {}
    for workers in WORKERS:
        with LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address=":0",
        ) as cluster:
            address = cluster.scheduler_address

            def on_dask(src_path: Path, out: Path, address: str = address) -> None:
                triage_batch_on_dask(
                    src_path, out, scheduler=address, settings=settings,
                    record=batch_record, resume=False,
                )  # fmt: skip

            on_dask(warm, work / "warm-out.jsonl")  # every worker loads its models
            for _ in range(args.rounds):
                for engine in ("pool", "dask"):
                    out = work / f"{engine}-{workers}.jsonl"
                    t0 = time.perf_counter()
                    if engine == "pool":
                        run_batch(src, out, settings, resume=False, workers=workers)
                    else:
                        on_dask(src, out)
                    elapsed = time.perf_counter() - t0
                    rates.setdefault((engine, workers), []).append(args.n / elapsed)
                    print(f"{engine} x{workers}: {args.n / elapsed:.0f}/s", file=sys.stderr)
    load = os.getloadavg()
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    rows = []
    for workers in WORKERS:
        pool = statistics.median(rates[("pool", workers)])
        dask = statistics.median(rates[("dask", workers)])
        rows.append(f"| {workers} | {pool:.0f} | {dask:.0f} | {dask / pool:.2f} |")
    scale_pool = statistics.median(rates[("pool", 2)]) / statistics.median(rates[("pool", 1)])
    scale_dask = statistics.median(rates[("dask", 2)]) / statistics.median(rates[("dask", 1)])
    text = f"""## Batch on Dask

`python benchmarks/bench_dask.py` ({now}, {platform.machine()}, {os.cpu_count()} CPUs, Python \
{platform.python_version()}; load average {load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}: other \
sessions share the machine). `triage --batch` on {args.n} notifications (the three documented \
examples, summary pulses at varied delta-V and PDOF), steady throughput (models loaded before \
timing), median of {args.rounds} alternated rounds: the built-in pool (forked from the loaded \
models) against a `LocalCluster` on loopback (scheduler plus single-threaded worker processes; \
chunks of 64, ordered, written as they come back).

| workers | built-in pool (notifications/s) | Dask LocalCluster (notifications/s) | Dask / pool |
|---:|---:|---:|---:|
{chr(10).join(rows)}

2 workers / 1: pool {scale_pool:.2f}, Dask {scale_dask:.2f}. The answers are the same \
(`tests/service/jobs/test_batch_dask.py`). How this grows on more machines: `docs/deploy.md`.
"""
    print(text)
    if not args.no_write:
        write_section("dask", text)


if __name__ == "__main__":
    main()
