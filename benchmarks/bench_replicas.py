"""Replicas behind nginx, one killed mid-load: the figures (issue 33).

Run: ``python benchmarks/bench_replicas.py [--requests N] [--threads T]``. Starts a
throwaway PostgreSQL cluster (the tests' fixture code), three ``aacn-triage serve``
replicas and Debian's nginx with the repository's site, sends the seeded plan of
``tests/replicas.py`` (fresh notifications, replays, conflicts), kills one replica
with SIGKILL once 35 % of the plan is under way and starts it again; prints the
counts and rewrites the "Replicas" section of ``benchmarks/RESULTS.md``. The test
(``tests/service/test_replicas.py``) asserts the same invariants on the same plan.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path

from results_md import write_section

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--requests", type=int, default=360, help="POSTs in the plan")
    parser.add_argument("--threads", type=int, default=6, help="client threads")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    from sqlalchemy import create_engine, text

    from tests.conftest import _start_cluster
    from tests.replicas import REPLICAS, LoadPlan, deployment, find_nginx, run_load

    binary = find_nginx()
    if binary is None:
        raise SystemExit("no nginx binary: apt-get install nginx")
    work = Path(tempfile.mkdtemp(prefix="bench-replicas-"))
    cluster = _start_cluster()
    try:
        admin = create_engine(cluster.admin_url, isolation_level="AUTOCOMMIT")
        with admin.connect() as conn:
            conn.execute(text('CREATE DATABASE "aacn_bench"'))
        admin.dispose()
        url = cluster.admin_url.rsplit("/", 1)[0] + "/aacn_bench"
        plan = LoadPlan(requests=args.requests, threads=args.threads)
        with deployment(url, work, binary) as (nginx, replicas, key):
            t0 = time.perf_counter()
            report = run_load(nginx, replicas, key, plan, url, victim=1)
            elapsed = time.perf_counter() - t0
    finally:
        cluster.stop()
        shutil.rmtree(work, ignore_errors=True)
    figures = report.figures()
    problems = report.problems()
    load = os.getloadavg()
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    rows = "\n".join(f"| {name.replace('_', ' ')} | {value} |" for name, value in figures.items())
    text_md = f"""## Replicas behind nginx, one killed mid-load

`python benchmarks/bench_replicas.py` ({now}, {platform.machine()}, {os.cpu_count()} CPUs, \
Python {platform.python_version()}; load average {load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}). \
{REPLICAS} `aacn-triage serve --workers 1` replicas on one PostgreSQL database behind Debian's \
nginx with `deploy/nginx/aacn-triage.conf`; {plan.requests} POSTs from {plan.threads} threads \
(seeded: {plan.replay_share:.0%} replays of an earlier event with the same body, \
{plan.conflict_share:.0%} with another delta-V); replica 2 killed with SIGKILL once \
{plan.kill_at:.0%} of the plan was under way, started again at once; the last \
{1 - plan.rejoin_at:.0%} held until it was ready. A client retries (same body) only after \
502/503/504 or a broken connection. {elapsed:.0f} s in all; the killed replica answered \
`/readyz` {report.restart_ready_s:.1f} s after its restart (the kernels from the shared numba \
cache, under this load).

| figure | count |
|---|---:|
{rows}

Invariants (`tests/service/test_replicas.py`): {"all hold" if not problems else problems}. \
"stored" counts the rows of `cases`; "lost" the acknowledged answers whose case id is not \
stored for that event; "duplicates" the extra rows of an event. Retries are those the \
clients made after a 5xx or a broken connection (none is needed when nginx passes the POST \
on to the next replica itself, `proxy_next_upstream ... non_idempotent`).
"""
    print(text_md)
    if not args.no_write:
        write_section("replicas", text_md)


if __name__ == "__main__":
    main()
