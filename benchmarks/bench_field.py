"""Field risk model benchmark: its cost per occupant, and the whole engine beside it.

Run: ``python benchmarks/bench_field.py [--n N] [--no-write]``. Prints the figures
and rewrites the "Field risk model" section of ``benchmarks/RESULTS.md``.

Inputs: N calibration rows (seeded draw) as the service builds them. Timed:
``FieldModel.predict`` alone (design row, 200 bootstrap refits, interval) and
the decision (``predict`` + the operating point's threshold); and, on the same
notifications, the whole ``models.triage.triage`` with its ``field_model``
timing, so that the field model's share of a request is measured in one run.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from datetime import UTC, datetime

import numpy as np
from results_md import RESULTS, write_section

from models.field.model import load_default
from models.offline.field.rows import load_calibration_rows, row_notification
from models.triage import load_engine_models, notification_field_inputs, triage


def _stats(samples_ms: list[float]) -> tuple[float, float]:
    s = sorted(samples_ms)
    return statistics.median(s), s[min(len(s) - 1, round(0.99 * (len(s) - 1)))]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=400, help="notifications")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    field = load_default()
    models = load_engine_models()
    rows = load_calibration_rows()
    pick = np.random.default_rng(0).choice(len(rows), size=args.n, replace=False)
    notes = [row_notification(rows[i]) for i in pick]
    inputs = [notification_field_inputs(n)[0] for n in notes]

    for f in inputs[:20]:
        field.predict(f)
    predict_ms = []
    decide_ms = []
    for f in inputs:
        t0 = time.perf_counter()
        pred = field.predict(f)
        t1 = time.perf_counter()
        _ = pred.probability >= field.threshold(pred.mode)
        t2 = time.perf_counter()
        predict_ms.append(1000.0 * (t1 - t0))
        decide_ms.append(1000.0 * (t2 - t0))

    for n in notes[:10]:
        triage(n, models)
    engine_ms, field_in_engine_ms = [], []
    for n in notes:
        result = triage(n, models)
        engine_ms.append(result.timings_ms["engine_total"])
        field_in_engine_ms.append(result.timings_ms["field_model"])

    rows_out = [
        ("`FieldModel.predict` (design row, 200 refits, interval)", *_stats(predict_ms)),
        ("decision (predict + operating-point threshold)", *_stats(decide_ms)),
        ("field model inside `triage` (its `timings_ms.field_model`)", *_stats(field_in_engine_ms)),
        ("whole engine per one-occupant notification (`engine_total`)", *_stats(engine_ms)),
    ]
    share = statistics.median(field_in_engine_ms) / statistics.median(engine_ms)
    load = os.getloadavg()
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        "## Field risk model",
        "",
        f"`python benchmarks/bench_field.py` ({now}, {platform.machine()}, "
        f"{os.cpu_count()} CPUs, Python {platform.python_version()}, numpy {np.__version__}). "
        f"{args.n} calibration rows as notifications (summary pulse, posture and seat not "
        f"sensed), seeded draw; median and 99th percentile. Load average at the end: "
        f"{load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}.",
        "",
        "| step | median (ms) | p99 (ms) |",
        "|---|---:|---:|",
        *(f"| {name} | {med:.3f} | {p99:.3f} |" for name, med, p99 in rows_out),
        "",
        f"Target (issue 21): the field model adds under 1 ms per occupant. It is "
        f"{100.0 * share:.1f} % of the engine's median time here; the rest is the occupant "
        "model and its surrogate (the physics explanation).",
    ]
    text = "\n".join(lines)
    print(text)
    if not args.no_write:
        write_section("field-model", text, RESULTS)


if __name__ == "__main__":
    main()
