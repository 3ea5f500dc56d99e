"""The occupants of one notification on one thread or on several: wall time of a triage.

Run: ``python benchmarks/bench_occupant_threads.py [--calls 200] [--threads 2]``.
Prints the figures (for the speed notes of ``benchmarks/RESULTS.md``, written by
hand); writes nothing.

In one process, the engine models loaded once as the service loads them (one
BLAS thread), ``models.triage.triage`` of two notifications: the two-occupant one
of ``bench_speed.py`` and a five-occupant one (the same crash, the front row full:
three occupant-model runs, and two rear occupants with the field model alone).
Each call alternates between ``occupant_threads=1`` (one occupant after the
other) and ``--threads`` (the same models, the occupants shared with a helper
pool), after 10 warm-up calls of each; the wall time of each call, the median and
quartiles per setting. Every answer is compared with the first one-thread
answer of its notification (every field but ``timings_ms``, as
``TriageResult`` compares): equal, or the script stops. The load average
before and after is printed: the box is shared.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import statistics
import sys
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
from tests.decision_pins import FRONT_PASSENGER, readme_two_occupants  # noqa: E402

#: The front middle and rear occupants added to the two-occupant notification.
_MORE_OCCUPANTS: list[dict[str, Any]] = [
    {
        "seat": "front_middle",
        "stature_cm": 178,
        "mass_kg": 80,
        "age_years": 51,
        "sex": "male",
        "belted": True,
        "frontal_airbag": "not_deployed",
    },
    {"seat": "rear_left", "belted": True, "frontal_airbag": "not_deployed", "age_years": 12},
    {**FRONT_PASSENGER, "seat": "rear_right", "frontal_airbag": "not_deployed"},
]


def five_occupants() -> dict[str, Any]:
    """The two-occupant notification with the front middle seat and two rear seats."""
    doc = readme_two_occupants()
    return {**doc, "event_id": "tsp-five", "occupants": [*doc["occupants"], *_MORE_OCCUPANTS]}


def _quartiles(values: list[float]) -> tuple[float, float, float]:
    q = statistics.quantiles(values, n=4)
    return q[0], statistics.median(values), q[2]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--calls", type=int, default=200, help="timed calls per setting")
    parser.add_argument("--threads", type=int, default=2, help="occupant threads against 1")
    args = parser.parse_args()

    from models.triage import load_engine_models, triage
    from service.cases.notification import CrashNotificationIn

    models = load_engine_models()
    settings = {
        1: dataclasses.replace(models, occupant_threads=1),
        args.threads: dataclasses.replace(models, occupant_threads=args.threads),
    }
    load_before = os.getloadavg()
    print(
        f"{platform.machine()}, {os.cpu_count()} CPUs, Python {platform.python_version()}; "
        f"load average before {load_before[0]:.2f} {load_before[1]:.2f} {load_before[2]:.2f}"
    )
    for name, doc in (("two occupants", readme_two_occupants()), ("five", five_occupants())):
        notification, _ = CrashNotificationIn.model_validate(doc).to_engine()
        reference = triage(notification, settings[1])
        walls: dict[int, list[float]] = {k: [] for k in settings}
        cpu: dict[int, list[float]] = {k: [] for k in settings}
        for call in range(10 + args.calls):
            for threads, engine in settings.items():
                t0, c0 = time.perf_counter(), time.process_time()
                result = triage(notification, engine)
                wall, used = time.perf_counter() - t0, time.process_time() - c0
                if result != reference:  # every field but timings_ms (TriageResult's equality)
                    raise SystemExit(f"{name}: {threads} threads answered other bits")
                if call >= 10:
                    walls[threads].append(1000.0 * wall)
                    cpu[threads].append(1000.0 * used)
        base = statistics.median(walls[1])
        for threads in settings:
            q1, med, q3 = _quartiles(walls[threads])
            print(
                f"{name}: occupant_threads={threads}: wall median {med:.2f} ms "
                f"(quartiles {q1:.2f}-{q3:.2f}), {med / base:.2f} of one thread; "
                f"process CPU median {statistics.median(cpu[threads]):.2f} ms"
            )
    load_after = os.getloadavg()
    print(f"load average after {load_after[0]:.2f} {load_after[1]:.2f} {load_after[2]:.2f}")


if __name__ == "__main__":
    main()
