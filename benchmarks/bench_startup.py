"""A replica's start-up with and without the numba cache the image builds (issue 33).

Run: ``python benchmarks/bench_startup.py [--rounds R]``. Prints the figures and
rewrites the "Start-up" section of ``benchmarks/RESULTS.md``.

As in the container image (``Dockerfile``): ``NUMBA_CPU_NAME=generic``, one cache
directory. Cold: ``aacn-triage serve --workers 1`` on a fresh SQLite file with an
empty cache (it compiles every kernel); warm: the build's warm-up step first (the
models loaded as ``serve`` loads them, which fills the cache), then ``serve`` with
that cache. Time from the process start to the first 200 of ``/readyz``; R
alternated rounds, the median kept.

``--checksums``: the warm start alone, with the numba cache filled, alternating
between the code checksums kept in it (``models.codehash``: the warm-up step
wrote them) and their entries removed (every source parsed, as before they were
kept); prints the figures, writes nothing.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from datetime import UTC, datetime
from pathlib import Path

from results_md import write_section

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

#: The Dockerfile's warm-up step.
WARM_UP = (
    "from service.context import engine_models_for; from service.settings import get_settings; "
    "engine_models_for(get_settings())"
)
#: Bound on one start, s.
START_TIMEOUT_S = 600.0


def _ready_after(env: dict[str, str], work: Path) -> float:
    from tests.support import free_port

    port = free_port()
    db = work / "start.db"
    db.unlink(missing_ok=True)
    cmd = [sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--workers", "1"]
    t0 = time.perf_counter()
    proc = subprocess.Popen(
        cmd,
        env={**env, "AACN_DATABASE_URL": f"sqlite:///{db}"},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        while time.perf_counter() - t0 < START_TIMEOUT_S:
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/readyz", timeout=1) as r:
                    if r.status == 200:
                        return time.perf_counter() - t0
            except (urllib.error.URLError, OSError):
                pass
            if proc.poll() is not None:
                raise SystemExit("serve exited")
            time.sleep(0.1)
        raise SystemExit("serve never became ready")
    finally:
        proc.terminate()
        proc.wait(timeout=60)


def _checksums(env: dict[str, str], work: Path, cache: Path, rounds: int) -> None:
    """Warm starts with the code checksums kept and with them removed, alternated."""
    subprocess.run([sys.executable, "-c", WARM_UP], env=env, check=True, timeout=600)
    kept = sorted((cache / "codehash").glob("*.sha256"))
    if not kept:
        raise SystemExit("the warm-up step kept no code checksum")
    saved = {p.name: p.read_bytes() for p in kept}
    times: dict[str, list[float]] = {"kept": [], "removed": []}
    loads = []
    for _ in range(rounds):
        shutil.rmtree(cache / "codehash")
        times["removed"].append(_ready_after(env, work))
        (cache / "codehash").mkdir(exist_ok=True)  # the start above wrote them again:
        for name, data in saved.items():  # the same entries as the warm-up step's
            (cache / "codehash" / name).write_bytes(data)
        times["kept"].append(_ready_after(env, work))
        loads.append(os.getloadavg()[0])
        print({k: [round(x, 2) for x in v] for k, v in times.items()}, file=sys.stderr)
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    removed, kept_s = statistics.median(times["removed"]), statistics.median(times["kept"])
    print(
        f"{now}, {platform.machine()}, {os.cpu_count()} CPUs, Python "
        f"{platform.python_version()}; load average {min(loads):.1f}-{max(loads):.1f}; "
        f"{rounds} alternated rounds, median start to ready: {len(saved)} code checksums "
        f"removed {removed:.2f} s, kept {kept_s:.2f} s ({removed - kept_s:+.2f} s)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rounds", type=int, default=2, help="alternated rounds")
    parser.add_argument("--no-write", action="store_true", help="print only")
    parser.add_argument(
        "--checksums", action="store_true", help="warm starts, code checksums kept or not"
    )
    args = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="bench-startup-"))
    cache = work / "numba"
    env = {
        **os.environ,
        "NUMBA_CPU_NAME": "generic",
        "NUMBA_CACHE_DIR": str(cache),
        "AACN_NUMBA_CACHE_DIR": str(cache),
        "AACN_SPOOL_PATH": str(work / "spool.db"),
    }
    if args.checksums:
        try:
            _checksums(env, work, cache, args.rounds)
        finally:
            shutil.rmtree(work, ignore_errors=True)
        return
    times: dict[str, list[float]] = {"cold": [], "warm": [], "warm-up step": []}
    loads = []
    try:
        for _ in range(args.rounds):
            shutil.rmtree(cache, ignore_errors=True)
            times["cold"].append(_ready_after(env, work))
            shutil.rmtree(cache, ignore_errors=True)
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", WARM_UP], env=env, check=True, timeout=600)
            times["warm-up step"].append(time.perf_counter() - t0)
            times["warm"].append(_ready_after(env, work))
            loads.append(os.getloadavg()[0])
            print({k: [round(x, 1) for x in v] for k, v in times.items()}, file=sys.stderr)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    cold, warm = statistics.median(times["cold"]), statistics.median(times["warm"])
    text = f"""## Start-up of a replica

`python benchmarks/bench_startup.py` ({now}, {platform.machine()}, {os.cpu_count()} CPUs, \
Python {platform.python_version()}; load average {min(loads):.1f}-{max(loads):.1f} during the \
runs: other sessions share the machine). `aacn-triage serve --workers 1` on a fresh SQLite file, \
`NUMBA_CPU_NAME=generic` as in the image; process start to the first 200 of `/readyz`, median \
of {args.rounds} alternated rounds.

| numba cache | ready after (s) |
|---|---:|
| empty: the kernels are compiled at start | {cold:.1f} |
| filled by the image's warm-up step (it took {statistics.median(times["warm-up step"]):.1f} s) \
| {warm:.1f} |

The image compiles at build time, so a new replica starts as in the second row \
({cold / warm:.1f}x sooner here).
"""
    print(text)
    if not args.no_write:
        write_section("startup", text)


if __name__ == "__main__":
    main()
