"""Field model benchmark: its cost per occupant across versions, and the engine beside it.

Run: ``python benchmarks/bench_field.py [--n N] [--no-write]``. Prints the figures
and rewrites the "Field risk model" section of ``benchmarks/RESULTS.md``.

Inputs: N calibration rows (seeded draw) as the service builds them. Timed, one
occupant at a time: ``FieldModel.predict`` of 2.0.0 (MAIS 3+: design row, 200
bootstrap refits, interval), ``RiskModel.predict`` of 3.0.0 (ISS 15+ and eight
region risks, regressions with their bootstrap refits), of 3.1.0 (bags of
boosted trees where the fit chose them, feature set 1; before) and of the
shipped version (3.2.0: feature set 2, the trees may also split on the PDOF seen
from the seat and the impact count; after),
each with the decision at the default operating point; batch throughput of
each (occupants per second, all N at once: ``RiskModel.predict_many`` is
vectorised over occupants); and, on the same notifications, the whole
``models.triage.triage`` with its ``field_model`` timing (the shipped version
with the vehicle answer), so that the field model's share of a request is
measured in one run.
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

from models.field.model import FieldModel
from models.field.risk_model import RiskModel, load_default
from models.field.versions import artifact_for_version
from models.offline.field.rows import load_calibration_rows, row_notification
from models.triage import load_engine_models, notification_field_inputs, triage
from models.triage.field_evidence import notification_risk_inputs


def _stats(samples_ms: list[float]) -> tuple[float, float]:
    s = sorted(samples_ms)
    return statistics.median(s), s[min(len(s) - 1, round(0.99 * (len(s) - 1)))]


def _kinds(model: RiskModel) -> str:
    """Which outcomes are bags of boosted trees, and which blends of a bag and a regression."""
    outs = model.document["outcomes"]

    def of(kind: str) -> str:
        names = [n.removeprefix("region_") for n, o in outs.items() if o.get("kind") == kind]
        return ", ".join(names) or "none"

    text = f"ISS 15+ and 8 regions; boosted: {of('boosted')}"
    return text + (f"; blends: {of('blend')}" if of("blend") != "none" else "")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=400, help="notifications")
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    old = FieldModel.from_artifact(artifact_for_version("2.0.0"))
    first = RiskModel.from_artifact(artifact_for_version("3.0.0"))
    prev = RiskModel.from_artifact(artifact_for_version("3.1.0"))
    new = load_default()
    models = load_engine_models()
    rows = load_calibration_rows()
    pick = np.random.default_rng(0).choice(len(rows), size=args.n, replace=False)
    notes = [row_notification(rows[i]) for i in pick]
    old_inputs = [notification_field_inputs(n)[0] for n in notes]
    new_inputs = [notification_risk_inputs(n)[0] for n in notes]

    def timed(call: object, items: list[object]) -> list[float]:
        assert callable(call)
        for item in items[:20]:
            call(item)
        out = []
        for item in items:
            t0 = time.perf_counter()
            call(item)
            out.append(1000.0 * (time.perf_counter() - t0))
        return out

    old_ms = timed(
        lambda f: old.predict(f).probability >= old.threshold(old.predict(f).mode), old_inputs
    )
    first_ms = timed(lambda f: first.predict(f).probability >= first.threshold(), new_inputs)
    prev_ms = timed(lambda f: prev.predict(f).probability >= prev.threshold(), new_inputs)
    new_ms = timed(lambda f: new.predict(f).probability >= new.threshold(), new_inputs)

    def batch_rate(call: object, items: list[object]) -> float:
        assert callable(call)
        call(items)
        t0 = time.perf_counter()
        call(items)
        return len(items) / (time.perf_counter() - t0)

    old_rate = batch_rate(lambda xs: [old.predict(f) for f in xs], old_inputs)
    first_rate = batch_rate(first.predict_many, new_inputs)
    prev_rate = batch_rate(prev.predict_many, new_inputs)
    new_rate = batch_rate(new.predict_many, new_inputs)

    for n in notes[:10]:
        triage(n, models)
    engine_ms, field_in_engine_ms = [], []
    for n in notes:
        result = triage(n, models)
        engine_ms.append(result.timings_ms["engine_total"])
        field_in_engine_ms.append(result.timings_ms["field_model"])

    rows_out = [
        ("2.0.0 `FieldModel.predict` + decision (MAIS 3+)", *_stats(old_ms)),
        (
            "3.0.0 `RiskModel.predict` + decision (ISS 15+ and 8 regions, regressions)",
            *_stats(first_ms),
        ),
        (
            f"before: 3.1.0 `RiskModel.predict` + decision ({_kinds(prev)}; feature set 1)",
            *_stats(prev_ms),
        ),
        (
            f"after: {new.version} `RiskModel.predict` + decision ({_kinds(new)})",
            *_stats(new_ms),
        ),
        (
            f"{new.version} inside `triage` (its `timings_ms.field_model`, with the vehicle "
            "answer)",
            *_stats(field_in_engine_ms),
        ),
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
        f"Batch throughput, {args.n} occupants at once: 2.0.0 {old_rate:,.0f} occupants/s "
        f"(one `predict` each), 3.0.0 {first_rate:,.0f}, 3.1.0 {prev_rate:,.0f} and {new.version} "
        f"{new_rate:,.0f} occupants/s (`predict_many`, vectorised).",
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
