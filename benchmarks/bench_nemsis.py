"""NEMSIS record benchmark: the cost of building and validating a case's EMSDataSet.

Run: ``python benchmarks/bench_nemsis.py [--n N]``. Prints the figures and rewrites
the "nemsis" section of ``benchmarks/RESULTS.md``.

Cases: the documented stored case (one occupant, with the documented notification of
its event) and the same crash with five
occupants (every seat of the contract). Measures, median and p99 over N runs:

- build: ``service.nemsis.mapping.build_record`` (stored case -> XML bytes);
- validate: ``service.nemsis.validate.validate`` against the shipped XSDs (what
  every answer and export pays at run time);
- the schema's compilation, once per process (cold, N times).
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import platform
import statistics
import time
from datetime import UTC, datetime
from typing import Any

from results_md import write_section


def _stats(samples_ms: list[float]) -> tuple[float, float]:
    ms = sorted(samples_ms)
    p99 = ms[min(len(ms) - 1, math.ceil(0.99 * len(ms)) - 1)]
    return statistics.median(ms), p99


def _five_occupants(stored: dict[str, Any]) -> dict[str, Any]:
    case = copy.deepcopy(stored)
    seats = ["driver", "front_passenger", "rear_left", "rear_middle", "rear_right"]
    occupant, result = case["notification"]["occupants"][0], case["result"]["occupants"][0]
    case["notification"]["occupants"] = [{**occupant, "seat": s} for s in seats]
    case["result"]["occupants"] = [{**result, "seat": s} for s in seats]
    return case


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--n", type=int, default=200, help="runs per measure")
    args = parser.parse_args(argv)

    from service.cases.examples import EXAMPLE_STORED_CASE
    from service.cases.notification import EXAMPLE_NOTIFICATIONS
    from service.cases.result import StoredCase
    from service.nemsis import validate as validation
    from service.nemsis.mapping import Agency, build_record

    agency = Agency("C034", "351-C034P2", "09")
    # the example's notification is abridged: the documented one of the same event
    stored = {**EXAMPLE_STORED_CASE, "notification": EXAMPLE_NOTIFICATIONS["summary"]["value"]}
    compile_ms = []
    for _ in range(max(3, args.n // 20)):
        validation.schema.cache_clear()
        start = time.perf_counter()
        validation.schema()
        compile_ms.append(1000.0 * (time.perf_counter() - start))
    rows = []
    for name, doc in (
        ("example stored case", stored),
        ("five occupants", _five_occupants(stored)),
    ):
        case = StoredCase.model_validate(doc)
        build_ms, validate_ms = [], []
        for _ in range(args.n):
            start = time.perf_counter()
            record = build_record(case, agency)
            build_ms.append(1000.0 * (time.perf_counter() - start))
            start = time.perf_counter()
            errors = validation.validate(record.document)
            validate_ms.append(1000.0 * (time.perf_counter() - start))
            if errors:
                raise SystemExit(f"{name}: the record does not validate: {errors}")
        reports = len(case.result.occupants)
        rows.append(
            (name, reports, len(record.document) / 1024, *_stats(build_ms), *_stats(validate_ms))
        )

    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    when = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    compile_median, compile_p99 = _stats(compile_ms)
    lines = [
        "## NEMSIS records",
        "",
        f"`python benchmarks/bench_nemsis.py` ({when}, {platform.machine()}, {os.cpu_count()} "
        f"CPUs, Python {platform.python_version()}; load average {load}: other sessions share "
        f"the machine). Median and p99 over {args.n} runs: *build* "
        "(`service.nemsis.mapping.build_record`, stored case to XML bytes) and *validate* "
        "(`service.nemsis.validate.validate` against the shipped NEMSIS v3.5.1 XSDs, paid by "
        "every answer of `GET /v1/cases/{id}/nemsis` and every exported record).",
        "",
        "| case | reports | XML (KiB) | build median | build p99 | validate median "
        "| validate p99 |",
        "|---|---:|---:|---:|---:|---:|---:|",
        *(
            f"| {n} | {r} | {kib:.0f} | {bm:.1f} | {bp:.1f} | {vm:.1f} | {vp:.1f} |"
            for n, r, kib, bm, bp, vm, vp in rows
        ),
        "",
        f"All times in ms. Compiling the schema, once per process: median {compile_median:.0f} "
        f"ms, p99 {compile_p99:.0f} ms ({len(compile_ms)} compilations).",
    ]
    text = "\n".join(lines)
    print(text)
    write_section("nemsis", text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
