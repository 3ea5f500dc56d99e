"""Replicas behind nginx on one PostgreSQL, a replica killed mid-load.

The plain-host recipe of ``docs/deploy.md``, run for real: ``aacn-triage serve``
processes (one uvicorn worker each, their own spool, one numba cache) on free
loopback ports, Debian's nginx in front of them with the repository's site
(``deploy/nginx/aacn-triage.conf``) and an upstream block naming their ports, all
on one PostgreSQL database migrated once beforehand (``aacn-triage db upgrade``).

`run_load` sends a bounded, seeded plan of POSTs through nginx from several
threads: fresh notifications, replays of earlier ones (same body) and conflicts
(an earlier ``event_id`` with another delta-V). Once a set share of the plan is
under way it kills one replica with SIGKILL, starts it again, and holds the last
part of the plan until the restarted replica is ready and nginx has had time to try
it again. A client retries a request that got 502/503/504 or no answer at all (the
connection broke): every such answer means "not recorded, or recorded and
replayable", because the POST is idempotent on (client, event_id). A 500 or any
other answer is final. `LoadReport.check` then reads the store and states the
invariants: every acknowledged case stored exactly once, under the case id it was
answered with, no duplicate, replays and 409s consistent across replicas.

Used by ``tests/service/test_replicas.py`` (asserts the invariants) and
``benchmarks/bench_replicas.py`` (prints the figures).
"""

from __future__ import annotations

import os
import random
import shutil
import signal
import subprocess
import sys
import threading
import time
import uuid
from collections import Counter
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx2 as httpx
from sqlalchemy import create_engine, text

from tests.paths import ROOT
from tests.support import create_key, free_port, summary, wait_ready

__all__ = [
    "CLI",
    "REPLICAS",
    "LoadPlan",
    "LoadReport",
    "Nginx",
    "Replica",
    "deployment",
    "find_nginx",
    "prepare_database",
    "run_load",
]

#: Replicas behind nginx (the recipe's figure).
REPLICAS = 3
#: The command line of this checkout's interpreter (never a PATH lookup).
CLI = [sys.executable, "-m", "service.cli"]
#: The repository's nginx site (the server block shared with the compose recipe).
SITE_CONF = ROOT / "deploy" / "nginx" / "aacn-triage.conf"
#: The site's listen line, replaced by a loopback port of the test's own.
SITE_LISTEN = "listen 8080;"
#: nginx leaves a failed replica out this long before trying it again, s; the
#: recipe's figure (``deploy/nginx/upstream-host.conf``).
FAIL_TIMEOUT_S = 2.0
#: Shared by the replicas: browser sessions signed by one replica hold on another.
SESSION_SECRET = "replica-test-session-secret-0123456789abcdef"
#: Answers of nginx or a replica after which the client sends the same POST again:
#: nothing was recorded, or it was and the retry is answered as its replay.
RETRYABLE = frozenset({502, 503, 504})
#: Tries per planned request (the first and the retries).
MAX_TRIES = 6
#: Pause before a retry, s.
RETRY_PAUSE_S = 0.25
#: Bound on one HTTP exchange with nginx, s (its own bound on a request is 30 s).
CLIENT_TIMEOUT_S = 60.0
#: Bound on a replica's start (a cold numba compile on a busy 2-core box), s.
READY_TIMEOUT_S = 300.0
#: Bound on the whole load, s (the test stops by itself).
LOAD_TIMEOUT_S = 300.0


def find_nginx() -> str | None:
    """The nginx binary (Debian's package puts it in /usr/sbin), or None."""
    return shutil.which("nginx") or next(
        (p for p in ("/usr/sbin/nginx", "/usr/local/sbin/nginx") if os.access(p, os.X_OK)), None
    )


def prepare_database(url: str, work: Path) -> tuple[dict[str, str], str]:
    """Migrate `url` once and create a submitter key (the recipe's first steps).

    Returns the replicas' common environment and the key.
    """
    env = {
        **os.environ,
        "AACN_DATABASE_URL": url,
        "AACN_AUTO_MIGRATE": "false",
        "AACN_WORKERS": "1",
        "AACN_SESSION_SECRET": SESSION_SECRET,
    }
    subprocess.run(
        [*CLI, "db", "upgrade"], env=env, check=True, capture_output=True, timeout=300, cwd=work
    )
    key = create_key(CLI, env, "submitter", "call-center", timeout_s=300)
    return env, key


@dataclass
class Replica:
    """One ``aacn-triage serve`` process on a loopback port, with its own spool."""

    index: int
    port: int
    work: Path
    env: Mapping[str, str]
    proc: subprocess.Popen[bytes] | None = None
    starts: int = 0

    @property
    def base(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    @property
    def address(self) -> str:
        """As nginx names it in ``$upstream_addr``."""
        return f"127.0.0.1:{self.port}"

    @property
    def log(self) -> Path:
        return self.work / f"replica{self.index}.log"

    def start(self) -> None:
        self.starts += 1
        env = {**self.env, "AACN_SPOOL_PATH": str(self.work / f"spool{self.index}.db")}
        with self.log.open("a") as sink:
            sink.write(f"--- start {self.starts}\n")
            sink.flush()
            self.proc = subprocess.Popen(
                [*CLI, "serve", "--host", "127.0.0.1", "--port", str(self.port), "--workers", "1"],
                env=env,
                stdout=sink,
                stderr=subprocess.STDOUT,
                cwd=self.work,
            )

    def wait_ready(self) -> None:
        assert self.proc is not None
        wait_ready(self.base, self.proc, self.log, timeout_s=READY_TIMEOUT_S)

    def kill9(self) -> None:
        """SIGKILL: no shutdown, no finishing of requests in flight."""
        assert self.proc is not None
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(timeout=30)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=30)


class Nginx:
    """Debian's nginx in the foreground with the repository's site, on a loopback port."""

    def __init__(self, binary: str, work: Path, upstreams: list[str]) -> None:
        self.binary = binary
        self.prefix = work / "nginx"
        self.port = free_port()
        self.proc: subprocess.Popen[bytes] | None = None
        for sub in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi"):
            (self.prefix / "temp" / sub).mkdir(parents=True, exist_ok=True)
        site = SITE_CONF.read_text(encoding="utf-8")
        assert SITE_LISTEN in site, f"{SITE_CONF} no longer has {SITE_LISTEN!r}"
        (self.prefix / "site.conf").write_text(
            site.replace(SITE_LISTEN, f"listen 127.0.0.1:{self.port};"), encoding="utf-8"
        )
        servers = "".join(
            f"    server {u} max_fails=1 fail_timeout={FAIL_TIMEOUT_S:g}s;\n" for u in upstreams
        )
        t = self.prefix / "temp"
        # as root, the workers run as root too: the prefix is the test's private dir
        user = "user root;\n" if os.geteuid() == 0 else ""
        (self.prefix / "nginx.conf").write_text(
            f"""{user}daemon off;
worker_processes 1;
pid {self.prefix}/nginx.pid;
error_log {self.prefix}/error.log warn;
events {{ worker_connections 512; }}
http {{
    access_log {self.prefix}/access.log;
    client_body_temp_path {t}/client_body;
    proxy_temp_path {t}/proxy;
    fastcgi_temp_path {t}/fastcgi;
    uwsgi_temp_path {t}/uwsgi;
    scgi_temp_path {t}/scgi;
    # which replica answered (the test's own header, not in the recipe)
    add_header X-Aacn-Upstream $upstream_addr always;
    upstream aacn_triage {{
{servers}        keepalive 16;
    }}
    include {self.prefix}/site.conf;
}}
""",
            encoding="utf-8",
        )

    @property
    def base(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def start(self) -> None:
        conf = str(self.prefix / "nginx.conf")
        check = subprocess.run(
            [self.binary, "-t", "-p", str(self.prefix), "-c", conf],
            capture_output=True,
            text=True,
            timeout=60,
        )
        if check.returncode != 0:
            raise RuntimeError(f"nginx -t failed: {check.stderr.strip()[-1000:]}")
        with (self.prefix / "stderr.log").open("w") as sink:
            self.proc = subprocess.Popen(
                [self.binary, "-p", str(self.prefix), "-c", conf], stdout=sink, stderr=sink
            )
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline:
            try:
                if httpx.get(self.base + "/livez", timeout=2.0).status_code == 200:
                    return
            except httpx.TransportError:
                pass
            if self.proc.poll() is not None:
                raise RuntimeError(f"nginx exited: {(self.prefix / 'error.log').read_text()}")
            time.sleep(0.1)
        raise RuntimeError("nginx never answered /livez")

    def passed_on(self) -> Counter[str]:
        """What nginx's error log says it met at a replica (each time it passed the
        request on to the next one, or gave up): refused, reset, closed mid-request."""
        kinds = {
            "Connection refused": "refused",
            "Connection reset": "reset",
            "prematurely closed": "closed_mid_request",
            "timed out": "timed_out",
            "no live upstreams": "no_live_upstream",
        }
        log = self.prefix / "error.log"
        lines = log.read_text(errors="replace").splitlines() if log.exists() else []
        return Counter(
            f"nginx_{kind}" for line in lines for text, kind in kinds.items() if text in line
        )

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(signal.SIGQUIT)  # graceful: the master and its workers
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=30)


@contextmanager
def deployment(
    url: str, work: Path, nginx_binary: str, replicas: int = REPLICAS
) -> Iterator[tuple[Nginx, list[Replica], str]]:
    """The plain-host recipe on `url`: migrated, a submitter key, the replicas ready
    (the first alone, as it fills a cold numba cache), nginx in front of them.

    Yields ``(nginx, replicas, key)``; everything is stopped afterwards.
    """
    env, key = prepare_database(url, work)
    started = [Replica(i, free_port(), work, env) for i in range(replicas)]
    nginx = Nginx(nginx_binary, work, [r.address for r in started])
    try:
        started[0].start()
        started[0].wait_ready()
        for r in started[1:]:
            r.start()
        for r in started[1:]:
            r.wait_ready()
        nginx.start()
        yield nginx, started, key
    finally:
        nginx.stop()
        for r in started:
            r.stop()


# ----------------------------------------------------------------------- load


@dataclass(frozen=True)
class Planned:
    """One POST of the plan: the event, which body variant of it, the body."""

    number: int
    event_id: str
    variant: int
    body: dict[str, Any]


@dataclass(frozen=True)
class LoadPlan:
    """A seeded plan: fresh events, replays of earlier ones, conflicts with them.

    Attributes
    ----------
    requests : int
        POSTs in the plan.
    threads : int
        Client threads sending them.
    replay_share, conflict_share : float
        Shares of the requests that repeat an earlier event with the same body, or
        with another delta-V.
    kill_at : float
        Share of the plan issued when the replica is killed.
    rejoin_at : float
        Share of the plan after which the rest waits for the restarted replica.
    seed : int
    """

    requests: int = 360
    threads: int = 6
    replay_share: float = 0.2
    conflict_share: float = 0.1
    kill_at: float = 0.35
    rejoin_at: float = 0.7
    seed: int = 33

    def build(self) -> list[Planned]:
        rng = random.Random(self.seed)
        tag = uuid.uuid4().hex[:8]
        events: list[tuple[str, float]] = []
        out: list[Planned] = []
        for n in range(self.requests):
            draw = rng.random()
            if events and draw < self.replay_share:
                event_id, dv = rng.choice(events)
                variant = 0
            elif events and draw < self.replay_share + self.conflict_share:
                event_id, dv = rng.choice(events)
                variant = 1
            else:
                event_id, dv = f"lb-{tag}-{len(events):04d}", round(rng.uniform(15.0, 70.0), 1)
                events.append((event_id, dv))
                variant = 0
            # the conflicting variant: the same event id with 5 km/h more delta-V
            body = summary(dv + 5.0 * variant, pdof_deg=0.0, event_id=event_id)
            out.append(Planned(n, event_id, variant, body))
        return out


@dataclass
class Answer:
    """What the client finally got for one planned POST, and what it went through."""

    planned: Planned
    status: int | None
    case_id: str | None
    upstream: str
    replayed: bool
    tries: int
    retried: Counter[str]
    issued_after_kill: bool


@dataclass
class LoadReport:
    """The answers of a load and the store after it."""

    answers: list[Answer]
    killed: str
    restarted_ready_at: int
    stored: dict[tuple[str, str], list[str]] = field(default_factory=dict)
    #: What nginx met at the replicas (`Nginx.passed_on`).
    nginx: Counter[str] = field(default_factory=Counter)
    #: From the killed replica's restart to its first ready answer, s (not asserted).
    restart_ready_s: float = 0.0

    def figures(self) -> dict[str, int]:
        """Counts for the results table (see the module docstring)."""
        acked = [a for a in self.answers if a.status in (200, 201, 202)]
        retried: Counter[str] = Counter()
        for a in self.answers:
            retried.update(a.retried)
        by_event: dict[str, list[Answer]] = {}
        for a in acked:
            by_event.setdefault(a.planned.event_id, []).append(a)
        created_by = {
            e: next((a.upstream for a in ans if a.status == 201), "") for e, ans in by_event.items()
        }
        return {
            "requests": len(self.answers),
            "acknowledged": len(acked),
            "created_201": sum(a.status == 201 for a in self.answers),
            "replayed_200": sum(a.status == 200 for a in self.answers),
            "spooled_202": sum(a.status == 202 for a in self.answers),
            "conflict_409": sum(a.status == 409 for a in self.answers),
            "replays_on_another_replica": sum(
                a.status == 200 and a.upstream != created_by.get(a.planned.event_id, a.upstream)
                for a in acked
            ),
            "events_acknowledged": len(by_event),
            "stored": sum(len(v) for v in self.stored.values()),
            "duplicates": sum(len(v) - 1 for v in self.stored.values() if len(v) > 1),
            "lost": sum(
                a.case_id not in self.stored.get(("call-center", a.planned.event_id), [])
                for a in acked
            ),
            "final_5xx": sum(a.status is not None and a.status >= 500 for a in self.answers),
            "no_answer": sum(a.status is None for a in self.answers),
            "other_final": sum(
                a.status is not None and a.status not in (200, 201, 202, 409) and a.status < 500
                for a in self.answers
            ),
            "client_retries": sum(a.tries - 1 for a in self.answers),
            **{f"client_retried_{k}": v for k, v in sorted(retried.items())},
            **dict(sorted(self.nginx.items())),
            "served_by_killed_after_restart": sum(
                a.upstream.endswith(self.killed) and a.planned.number >= self.restarted_ready_at
                for a in self.answers
            ),
        }

    def problems(self) -> list[str]:
        """Every broken invariant, in words (empty when all hold)."""
        out: list[str] = []
        figures = self.figures()
        for name in ("duplicates", "lost", "final_5xx", "no_answer", "other_final"):
            if figures[name]:
                out.append(f"{name}: {figures[name]}")
        by_event: dict[str, list[Answer]] = {}
        for a in self.answers:
            by_event.setdefault(a.planned.event_id, []).append(a)
        for event_id, answers in by_event.items():
            acked = [a for a in answers if a.status in (200, 201, 202)]
            stored = self.stored.get(("call-center", event_id), [])
            if not acked:
                out.append(f"{event_id}: no request acknowledged")
                continue
            if len(stored) != 1 or {a.case_id for a in acked} != set(stored):
                out.append(f"{event_id}: answered {[a.case_id for a in acked]}, stored {stored}")
            # none when the killed replica stored it and died before answering: the
            # retry on another replica is then answered as its replay
            if sum(a.status in (201, 202) for a in acked) > 1:
                out.append(f"{event_id}: {[a.status for a in acked]} (created twice)")
            variants = {a.planned.variant for a in acked}
            refused = {a.planned.variant for a in answers if a.status == 409}
            if len(variants) != 1 or variants & refused:
                out.append(f"{event_id}: acknowledged variants {variants}, 409 for {refused}")
        extra = set(self.stored) - {("call-center", e) for e in by_event}
        if extra:
            out.append(f"stored events never sent: {sorted(extra)[:5]}")
        if not any(a.issued_after_kill and a.status in (200, 201) for a in self.answers):
            out.append("nothing acknowledged after the kill: nginx did not route around it")
        return out


def _post(client: httpx.Client, base: str, key: str, planned: Planned, after_kill: bool) -> Answer:
    retried: Counter[str] = Counter()
    headers = {"Authorization": f"Bearer {key}"}
    for tries in range(1, MAX_TRIES + 1):
        try:
            r = client.post(base + "/v1/cases", json=planned.body, headers=headers)
        except httpx.TransportError as exc:
            retried[f"transport_{type(exc).__name__}"] += 1
        else:
            if r.status_code not in RETRYABLE or tries == MAX_TRIES:
                ok = r.status_code in (200, 201, 202)
                return Answer(
                    planned=planned,
                    status=r.status_code,
                    case_id=r.json()["case_id"] if ok else None,
                    upstream=r.headers.get("x-aacn-upstream", ""),
                    replayed=r.headers.get("idempotent-replayed") == "true",
                    tries=tries,
                    retried=retried,
                    issued_after_kill=after_kill,
                )
            retried[f"http_{r.status_code}"] += 1
        time.sleep(RETRY_PAUSE_S)
    return Answer(planned, None, None, "", False, MAX_TRIES, retried, after_kill)


def run_load(
    nginx: Nginx, replicas: list[Replica], key: str, plan: LoadPlan, url: str, victim: int = 1
) -> LoadReport:
    """Send `plan` through `nginx`; kill ``replicas[victim]`` mid-load and restart it.

    Returns the report with the store's cases read back (`LoadReport.stored`).
    """
    planned = plan.build()
    kill_at = int(plan.kill_at * len(planned))
    rejoin_at = int(plan.rejoin_at * len(planned))
    lock = threading.Lock()
    rejoined = threading.Event()
    killed = threading.Event()
    next_index = 0
    answers: list[Answer | None] = [None] * len(planned)
    deadline = time.monotonic() + LOAD_TIMEOUT_S

    def worker() -> None:
        nonlocal next_index
        with httpx.Client(timeout=CLIENT_TIMEOUT_S) as client:
            while time.monotonic() < deadline:
                with lock:
                    i = next_index
                    if i >= len(planned):
                        return
                    next_index += 1
                if i >= rejoin_at:
                    rejoined.wait(max(0.0, deadline - time.monotonic()))
                answers[i] = _post(client, nginx.base, key, planned[i], killed.is_set())

    threads = [threading.Thread(target=worker, daemon=True) for _ in range(plan.threads)]
    for t in threads:
        t.start()
    victim_replica = replicas[victim]
    restart_ready_s = float("nan")
    try:
        while time.monotonic() < deadline:  # kill once that much of the plan is under way
            with lock:
                if next_index >= kill_at:
                    break
            time.sleep(0.01)
        victim_replica.kill9()
        killed.set()
        restarted = time.monotonic()
        victim_replica.start()
        victim_replica.wait_ready()
        restart_ready_s = time.monotonic() - restarted
        time.sleep(FAIL_TIMEOUT_S + 0.5)  # nginx tries a failed replica again after this
    finally:
        rejoined.set()
        for t in threads:
            t.join(max(1.0, deadline - time.monotonic()))
    done = [a for a in answers if a is not None]
    assert len(done) == len(planned), f"{len(planned) - len(done)} requests never finished"
    report = LoadReport(
        answers=done,
        killed=victim_replica.address,
        restarted_ready_at=rejoin_at,
        restart_ready_s=restart_ready_s,
    )
    report.nginx = nginx.passed_on()
    report.stored = read_store(url, {a.case_id for a in done if a.case_id})
    return report


def read_store(
    url: str, expected: set[str], drain_timeout_s: float = 60.0
) -> dict[tuple[str, str], list[str]]:
    """The stored case ids by (client, event_id), once every `expected` case id is in
    the store (a case answered 202 from a spool is stored when its replica replays it)
    or `drain_timeout_s` has passed."""
    engine = create_engine(url)
    try:
        deadline = time.monotonic() + drain_timeout_s
        while True:
            with engine.connect() as conn:
                rows = conn.execute(text("SELECT client_name, event_id, id FROM cases")).all()
            if expected <= {r[2] for r in rows} or time.monotonic() > deadline:
                break
            time.sleep(0.5)
    finally:
        engine.dispose()
    out: dict[tuple[str, str], list[str]] = {}
    for client, event_id, case_id in rows:
        out.setdefault((client, event_id), []).append(case_id)
    return out
