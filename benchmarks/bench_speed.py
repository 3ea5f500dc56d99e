"""Speed against a reference commit, both measured in the same run (issue 51).

Run: ``python benchmarks/bench_speed.py [--baseline de4ca7b] [--reference b74d608]
[--requests 200] [--vehicles 3000]``. Prints the figures and the ratios and
rewrites the "Speed" section of ``benchmarks/RESULTS.md``.

The baseline commit is checked out into a temporary git worktree and run from
its own tree (``PYTHONPATH`` pointing at it, this environment's packages); the
current tree is this checkout. Each tree, in turn, in fresh processes with the
image's settings (``NUMBA_CPU_NAME=generic``, a numba cache directory of its own
filled by the image's warm-up step):

* **start to ready**: ``serve --workers 1`` on a fresh SQLite file, process start
  to the first 200 of ``/readyz``, the numba cache filled (as in the image);
* **POST**: that server, one keep-alive connection, the README's notification
  with a second occupant (front passenger 160 cm, 55 kg, 38 years, female,
  belted, frontal airbag deployed), each request a new event; 20 warm-up
  requests, then the p50 and p99 of the next N;
* **in process**: ``models.triage.triage`` of the same notification, mean of 50
  calls after 10, per occupant, as a new user runs it (OpenBLAS's own thread
  count) and again with ``OPENBLAS_NUM_THREADS=1`` (what the service sets); and
  the profile of the first (cProfile, 50 calls, the top functions by own time);
* **batch**: ``triage --batch`` of a real-shaped file, process start included,
  two workers: the vehicles of the shipped NASS-CDS 1997-2014 occupant extract
  (``models/offline/data``), a seeded sample of those whose delta-V, PDOF, seats
  and belt use are coded, as summary notifications (the fields both trees read);
  and the current tree's ``--decision-only`` batch (the field model alone), apart.

The decision fields (``triage``, ``vehicle`` and every occupant's ``triage``) of
the current tree's batch answers are compared byte for byte with those of the
reference commit: the field model 3.4.0 as it landed (b74d608, before the speed-up's
later steps; 90e87cc, where the speed-up started, served 3.3.1, whose answers the
speed-up held byte for byte until 3.4.0 changed them). The baseline's field model
is an older version, whose answers differ by design.
"""

from __future__ import annotations

import argparse
import csv
import gzip
import json
import os
import platform
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from results_md import RESULTS, write_section

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the tests' notifications (tests/decision_pins.py)
from tests.decision_pins import readme_two_occupants  # noqa: E402

NASS = ROOT / "models" / "offline" / "data" / "nass-cds-1997-2014-occupants.csv.gz"

#: The README's "Try it" notification with issue 51's second occupant (the one the
#: decision pins hold too).
TWO_OCCUPANTS: dict[str, Any] = readme_two_occupants()

#: NASS-CDS seat position codes -> the wire's seats.
_SEATS = {
    "11": "driver",
    "12": "front_middle",
    "13": "front_passenger",
    "21": "rear_left",
    "22": "rear_middle",
    "23": "rear_right",
    "31": "third_row_left",
    "32": "third_row_middle",
    "33": "third_row_right",
}
_AIRBAG = {"deployed": "deployed", "not_deployed": "not_deployed", "none": "absent"}

#: In-process timing and profile of one tree (run with that tree on PYTHONPATH).
_ENGINE_SCRIPT = """
import cProfile, io, json, pstats, sys, time
from models.triage import load_engine_models, triage
from service.cases.notification import CrashNotificationIn
doc = json.loads(sys.argv[1])
models = load_engine_models()
n, _ = CrashNotificationIn.model_validate(doc).to_engine()
for _ in range(10):
    triage(n, models)
t0 = time.perf_counter()
for _ in range(50):
    triage(n, models)
mean_ms = (time.perf_counter() - t0) / 50 * 1000.0
prof = cProfile.Profile()
prof.enable()
for _ in range(50):
    triage(n, models)
prof.disable()
out = io.StringIO()
pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(14)
text = out.getvalue()
text = text[text.index("ncalls"):] if "ncalls" in text else text
print(json.dumps({"mean_ms": mean_ms, "profile": text.replace(sys.argv[2], "")}))
"""

#: The Dockerfile's warm-up step (fills the numba cache).
_WARM_UP = (
    "from service.context import engine_models_for; from service.settings import get_settings; "
    "engine_models_for(get_settings())"
)


def real_shaped(n: int, seed: int = 51) -> list[str]:
    """`n` NASS-CDS vehicles as summary notifications (JSON texts), a seeded sample."""
    vehicles: dict[tuple[str, str, str, str], list[dict[str, str]]] = {}
    with gzip.open(NASS, "rt", newline="") as f:
        row: dict[str, str]
        for row in csv.DictReader(f):
            key = (row["year"], row["psu"], row["caseno"], row["vehno"])
            vehicles.setdefault(key, []).append(row)
    docs = []
    for (year, psu, caseno, vehno), rows in sorted(vehicles.items()):
        first = rows[0]
        if not first["delta_v_kmh"] or not first["pdof1_deg"]:
            continue
        dv, pdof = float(first["delta_v_kmh"]), float(first["pdof1_deg"]) % 360.0
        seats = [_SEATS.get(r["seat_code"]) for r in rows]
        belts = [r["belt"] for r in rows]
        if not 0 < dv <= 160 or None in seats or len(set(seats)) != len(seats):
            continue
        if any(b not in ("belted", "none") for b in belts) or len(rows) > 9:
            continue
        occupants = []
        for r, seat in zip(rows, seats, strict=True):
            occ: dict[str, Any] = {
                "seat": seat,
                "belted": r["belt"] == "belted",
                "frontal_airbag": _AIRBAG.get(r["frontal_airbag"], "not_deployed"),
            }
            for column in ("age_years", "stature_cm", "mass_kg"):
                if r[column]:
                    occ[column] = float(r[column])
            if r["female"] in ("0", "1"):
                occ["sex"] = "female" if r["female"] == "1" else "male"
            occupants.append(occ)
        turns = first["rollover_quarter_turns"]
        docs.append(
            {
                "event_id": f"nass-{year}-{psu}-{caseno}-{vehno}",
                "occurred_at": f"{year}-06-15T12:00:00Z",
                "crash": {
                    "pulse": {"kind": "summary", "delta_v_kmh": dv, "pdof_deg": pdof},
                    "rollover": bool(turns) and int(turns) > 0,
                },
                "occupants": occupants,
            }
        )
    random.Random(seed).shuffle(docs)
    return [json.dumps(d) for d in docs[:n]]


def _env(tree: Path, cache: Path, db: Path) -> dict[str, str]:
    return {
        **os.environ,
        "PYTHONPATH": str(tree),
        "NUMBA_CPU_NAME": "generic",
        "NUMBA_CACHE_DIR": str(cache),
        "AACN_NUMBA_CACHE_DIR": str(cache),
        "AACN_DATABASE_URL": f"sqlite:///{db}",
        "AACN_SPOOL_PATH": str(db.with_suffix(".spool")),
    }


def _post_figures(port: int, key: str, requests: int) -> tuple[float, float]:
    import http.client

    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=120)
    headers = {"Authorization": f"Bearer {key}", "Content-Type": "application/json"}
    latencies = []
    for i in range(20 + requests):
        body = json.dumps({**TWO_OCCUPANTS, "event_id": f"speed-{i}-{time.time_ns()}"})
        t0 = time.perf_counter()
        conn.request("POST", "/v1/cases", body=body, headers=headers)
        response = conn.getresponse()
        response.read()
        if response.status != 201:
            raise SystemExit(f"POST answered {response.status}")
        if i >= 20:
            latencies.append(1000.0 * (time.perf_counter() - t0))
    conn.close()
    latencies.sort()
    p99 = latencies[min(len(latencies) - 1, int(0.99 * len(latencies)))]
    return statistics.median(latencies), p99


def _serve(tree: Path, env: dict[str, str], requests: int) -> dict[str, float]:
    """Start to ready, then the POST figures, of `tree`'s server."""
    import urllib.error
    import urllib.request

    from tests.support import free_port

    py = sys.executable
    key = subprocess.run(
        [py, "-m", "service.cli", "keys", "create", "--role", "admin", "--name", "speed"],
        env=env,
        cwd=tree,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    port = free_port()
    cmd = [py, "-m", "service.cli", "serve", "--port", str(port), "--workers", "1"]
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        cmd, env=env, cwd=tree, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        ready = None
        while ready is None and time.perf_counter() - t0 < 600:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/readyz", timeout=1) as r:
                    if r.status == 200:
                        ready = time.perf_counter() - t0
            except (urllib.error.URLError, OSError):
                time.sleep(0.05)
            if proc.poll() is not None:
                raise SystemExit(f"serve of {tree} exited")
        if ready is None:
            raise SystemExit(f"serve of {tree} never became ready")
        p50, p99 = _post_figures(port, key, requests)
    finally:
        proc.terminate()
        proc.wait(timeout=60)
    return {"ready_s": ready, "post_p50_ms": p50, "post_p99_ms": p99}


def _batch(tree: Path, env: dict[str, str], src: Path, out: Path, *extra: str) -> float:
    cmd = [sys.executable, "-m", "service.cli", "triage", "--batch", str(src)]
    cmd += ["--out", str(out), "--workers", "2", *extra]
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, cwd=tree, check=True, capture_output=True)
    return time.perf_counter() - t0


def decision_bytes(path: Path) -> list[bytes]:
    """The decision fields of each answer line, as canonical JSON bytes."""
    out = []
    for line in path.read_text().splitlines():
        record = json.loads(line)
        result = record.get("result")
        if result is None:
            out.append(json.dumps(record.get("error"), sort_keys=True).encode())
            continue
        picked = {
            "triage": result["triage"],
            "vehicle": result.get("vehicle"),
            "occupants": [o["triage"] for o in result["occupants"]],
        }
        out.append(json.dumps(picked, sort_keys=True).encode())
    return out


def measure(tree: Path, work: Path, src: Path, requests: int) -> dict[str, Any]:
    """Every figure of one tree (see the module docstring)."""
    name = tree.name
    cache = work / f"numba-{name}"
    db = work / f"{name}.db"
    env = _env(tree, cache, db)
    subprocess.run([sys.executable, "-c", _WARM_UP], env=env, cwd=tree, check=True)
    figures: dict[str, Any] = _serve(tree, env, requests)
    n_occ = len(TWO_OCCUPANTS["occupants"])
    for key, extra in (("", {}), ("_blas1", {"OPENBLAS_NUM_THREADS": "1"})):
        engine = subprocess.run(
            [sys.executable, "-c", _ENGINE_SCRIPT, json.dumps(TWO_OCCUPANTS), str(tree) + "/"],
            env={**env, **extra},
            cwd=tree,
            capture_output=True,
            text=True,
            check=True,
        )
        result = json.loads(engine.stdout.strip().splitlines()[-1])
        figures[f"engine_per_occupant_ms{key}"] = result["mean_ms"] / n_occ
        figures[f"profile{key}"] = result["profile"]
    out = work / f"{name}.out.jsonl"
    figures["batch_s"] = _batch(tree, env, src, out)
    figures["batch_out"] = out
    if tree == ROOT:  # the decision-only mode (the baseline has none)
        fast = work / f"{name}.decision-only.jsonl"
        figures["batch_decision_only_s"] = _batch(tree, env, src, fast, "--decision-only")
        figures["batch_decision_only_out"] = fast
    return figures


def _checkout(commit: str, work: Path) -> Path:
    tree = work / commit
    subprocess.run(
        ["git", "worktree", "add", "--detach", str(tree), commit],
        cwd=ROOT,
        check=True,
        capture_output=True,
    )
    return tree


def _report(args: argparse.Namespace, base: dict[str, Any], cur: dict[str, Any], same: str) -> str:
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    load = os.getloadavg()
    n = args.vehicles
    rows = [
        ("POST p50 (ms)", base["post_p50_ms"], cur["post_p50_ms"], "<= 0.40"),
        ("POST p99 (ms)", base["post_p99_ms"], cur["post_p99_ms"], "<= 0.50"),
        (
            "in-process triage per occupant (ms)",
            base["engine_per_occupant_ms"],
            cur["engine_per_occupant_ms"],
            "<= 0.33",
        ),
        (
            "... with OPENBLAS_NUM_THREADS=1 (ms)",
            base["engine_per_occupant_ms_blas1"],
            cur["engine_per_occupant_ms_blas1"],
            "",
        ),
        ("batch (s, start-up included)", base["batch_s"], cur["batch_s"], ""),
        ("start to ready, numba cache filled (s)", base["ready_s"], cur["ready_s"], "<= 5 s"),
    ]
    lines = [
        "## Speed (issue 51)",
        "",
        f"`python benchmarks/bench_speed.py` ({now}, {platform.machine()}, {os.cpu_count()} "
        f"CPUs, Python {platform.python_version()}; load average {load[0]:.1f}, {load[1]:.1f}, "
        f"{load[2]:.1f}: other sessions share the machine). Baseline `{args.baseline}` and "
        "the current tree measured in the same run (the module docstring says how). POST: "
        f"{args.requests} sequential requests after 20 warm-up; batch: {n} NASS-CDS vehicles.",
        "",
        f"| figure | {args.baseline} | current | current / {args.baseline} | target |",
        "|---|---:|---:|---:|---|",
    ]
    for label, b, c, target in rows:
        lines.append(f"| {label} | {b:.2f} | {c:.2f} | {c / b:.2f} | {target} |")
    vb, vc = n / base["batch_s"], n / cur["batch_s"]
    lines.append(f"| batch (vehicles/s) | {vb:.0f} | {vc:.0f} | {vc / vb:.2f} | >= 3 |")
    if "batch_decision_only_s" in cur:
        vd = n / cur["batch_decision_only_s"]
        lines.append(
            f"| batch `--decision-only` (vehicles/s; against {args.baseline}'s full batch) "
            f"| {vb:.0f} | {vd:.0f} | {vd / vb:.2f} | measured apart |"
        )
    lines += ["", same, ""]
    for label, figures in ((args.baseline, base), ("current", cur)):
        lines += [
            f"Profile of `models.triage.triage`, {label} (50 calls, top by own time):",
            "",
            "```",
            figures["profile"].strip("\n"),
            "```",
            "",
        ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--baseline", default="de4ca7b", help="commit to compare with")
    parser.add_argument("--reference", default="b74d608", help="commit of the same answers")
    parser.add_argument("--requests", type=int, default=200, help="POSTs after 20 warm-up")
    parser.add_argument("--vehicles", type=int, default=3000, help="vehicles of the batch")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="bench-speed-"))
    trees: list[Path] = []
    try:
        src = work / "vehicles.jsonl"
        src.write_text("\n".join(real_shaped(args.vehicles)) + "\n")
        trees = [_checkout(args.baseline, work), _checkout(args.reference, work)]
        base = measure(trees[0], work, src, args.requests)
        print({k: v for k, v in base.items() if "profile" not in k}, file=sys.stderr)
        cur = measure(ROOT, work, src, args.requests)
        print({k: v for k, v in cur.items() if "profile" not in k}, file=sys.stderr)
        ref_out = work / "reference.out.jsonl"
        ref_env = _env(trees[1], work / "numba-reference", work / "reference.db")
        subprocess.run([sys.executable, "-c", _WARM_UP], env=ref_env, cwd=trees[1], check=True)
        _batch(trees[1], ref_env, src, ref_out)
        a, b = decision_bytes(cur["batch_out"]), decision_bytes(ref_out)
        differ = sum(x != y for x, y in zip(a, b, strict=True))
        same = f"Decision fields of the {len(a)} batch answers against `{args.reference}`'s: " + (
            "the same bytes." if differ == 0 else f"{differ} differ."
        )
        d = decision_bytes(cur["batch_decision_only_out"])
        differ = sum(x != y for x, y in zip(d, a, strict=True))
        same += " The `--decision-only` batch's against the full batch's: " + (
            "the same bytes." if differ == 0 else f"{differ} differ."
        )
        text = _report(args, base, cur, same)
    finally:
        for tree in trees:
            subprocess.run(
                ["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT, check=False
            )
        shutil.rmtree(work, ignore_errors=True)
    print(text)
    if not args.no_write:
        write_section("speed", text)
        print(f"\nwrote {RESULTS}")


if __name__ == "__main__":
    main()
