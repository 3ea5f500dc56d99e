"""Benchmark of the occupant LPMs (issue 4): fixed-step numba kernel vs solve_ivp.

For each impact mode: one warm single simulation (median of repeats) and a
batch of 1,000 cases (varied delta-V, occupant, restraints), end to end
(pulse in, injury measures and assessment out) and kernel only, against the
``scipy.integrate.solve_ivp`` reference (DOP853, rtol 1e-8) on the same
equations. The reference batch is timed on ``--ref-sample`` cases and scaled
to 1,000 (``--ref-sample 1000`` runs it all).

Run from the repository root::

    python benchmarks/bench_lpm.py [--batch 1000] [--ref-sample 20] [--no-write]

Prints a table and rewrites the "Occupant LPMs" section of
``benchmarks/RESULTS.md``.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from results_md import write_section

from models.impact_mode import ImpactMode
from models.lpm.params import load_parameter_set
from models.lpm.pulses import haversine_pulse, side_pulse
from models.lpm.simulate import (
    BatchCase,
    _run_kernel,
    prepare,
    simulate,
    simulate_batch,
    simulate_reference,
)
from models.notification import AirbagState, Body, Occupant, Seat


def _pulse(mode: ImpactMode, dv_kmh: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if mode is ImpactMode.FRONTAL:
        return haversine_pulse(dv_kmh * 1.1, 0.09)
    if mode is ImpactMode.REAR:
        return haversine_pulse(dv_kmh * 0.6, 0.09, angle_deg=180.0)
    return side_pulse(dv_kmh * 1500.0 / 2600.0, 0.06)


def _cases(
    mode: ImpactMode, n: int, seed: int = 0
) -> list[tuple[tuple[np.ndarray, ...], Occupant]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        dv = float(rng.uniform(30.0, 60.0))
        occ = Occupant(
            seat=Seat.DRIVER,
            body=Body.MALE_50TH if rng.random() < 0.5 else Body.FEMALE_5TH,
            belted=bool(rng.random() < 0.8),
            frontal_airbag=AirbagState.DEPLOYED if rng.random() < 0.8 else AirbagState.ABSENT,
            age_years=float(rng.uniform(18, 80)),
            posture_lumbar_flexion_deg=float(rng.uniform(5.8, 25.0)),
            seat_track_mm=float(rng.uniform(-50, 50)),
        )
        out.append((_pulse(mode, dv), occ))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=1000)
    ap.add_argument("--ref-sample", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--no-write", action="store_true")
    args = ap.parse_args()

    ps = load_parameter_set()
    t0 = time.perf_counter()
    from models.lpm.simulate import warm_up

    warm_up()
    warm_s = time.perf_counter() - t0
    rows = []
    for mode in ImpactMode:
        pulse = _pulse(mode, 50.0)
        occ = Occupant(
            seat=Seat.DRIVER,
            body=Body.MALE_50TH,
            belted=True,
            frontal_airbag=AirbagState.DEPLOYED,
            age_years=35.0,
        )
        simulate(*pulse, mode, occ, ps)
        single = []
        kern = []
        pr = prepare(*pulse, mode, occ, ps)
        for _ in range(args.repeats):
            a = time.perf_counter()
            simulate(*pulse, mode, occ, ps)
            single.append(time.perf_counter() - a)
            a = time.perf_counter()
            _run_kernel(pr)
            kern.append(time.perf_counter() - a)
        ref_single = []
        for _ in range(3):
            a = time.perf_counter()
            r = simulate_reference(*pulse, mode, occ, ps)
            ref_single.append(time.perf_counter() - a)
        nfev = r.info.get("nfev")
        cases = _cases(mode, args.batch)
        a = time.perf_counter()
        for p, o in cases:
            simulate(*p, mode, o, ps)
        batch_s = time.perf_counter() - a
        a = time.perf_counter()
        simulate_batch([BatchCase(*p, mode, o) for p, o in cases], ps)
        batch_threads_s = time.perf_counter() - a
        prs = [prepare(*p, mode, o, ps) for p, o in cases]
        a = time.perf_counter()
        for pr_i in prs:
            _run_kernel(pr_i)
        batch_kernel_s = time.perf_counter() - a
        sample = cases[: args.ref_sample]
        a = time.perf_counter()
        for p, o in sample:
            simulate_reference(*p, mode, o, ps)
        ref_batch_s = (time.perf_counter() - a) * len(cases) / len(sample)
        rows.append(
            {
                "mode": mode.value,
                "single_ms": statistics.median(single) * 1e3,
                "kernel_ms": statistics.median(kern) * 1e3,
                "ref_single_ms": statistics.median(ref_single) * 1e3,
                "nfev": nfev,
                "batch_s": batch_s,
                "batch_threads_s": batch_threads_s,
                "batch_kernel_s": batch_kernel_s,
                "ref_batch_s": ref_batch_s,
            }
        )
        print(
            f"{mode.value:10s} single {rows[-1]['single_ms']:7.2f} ms (kernel "
            f"{rows[-1]['kernel_ms']:6.2f} ms) | solve_ivp {rows[-1]['ref_single_ms']:8.1f} ms "
            f"| batch {args.batch}: {batch_s:6.2f} s (threads {batch_threads_s:5.2f} s, "
            f"kernel {batch_kernel_s:5.2f} s) | "
            f"solve_ivp batch ~{ref_batch_s:7.1f} s",
            flush=True,
        )

    lines = [
        "## Occupant LPMs",
        "",
        f"`python benchmarks/bench_lpm.py` ({time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, Python "
        f"{platform.python_version()}, 1 thread). 200 ms simulated, 10 kHz output. "
        "Fixed step: numba semi-implicit Euler, dt = 1e-4 s. Reference: `solve_ivp` DOP853, "
        "rtol 1e-8, atol 1e-10, on the same compiled right-hand side. End to end = pulse in, "
        "CFC filters, HIC/Nij/chest/VC/CTI, AIS/ISS assessment out. Batch = "
        f"{args.batch} cases (delta-V 30-60 km/h, 50M/5F, belt/airbag, posture, seat track); "
        f"the solve_ivp batch is timed on {args.ref_sample} of them and scaled. "
        f"Warm-up (`warm_up()`, numba cache {'hit' if warm_s < 5 else 'miss'}): "
        f"{warm_s:.1f} s. Load average at the end: "
        f"{', '.join(f'{x:.1f}' for x in os.getloadavg())} (other sessions share the "
        "machine, so timings are upper bounds).",
        "",
        "| mode | single, end to end (ms) | single, kernel (ms) | solve_ivp single (ms) "
        "| speed-up | batch end to end (s) | batch, `simulate_batch` threads (s) "
        "| batch kernel (s) | solve_ivp batch (s, scaled) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['mode']} | {r['single_ms']:.2f} | {r['kernel_ms']:.2f} | "
            f"{r['ref_single_ms']:.0f} | {r['ref_single_ms'] / r['single_ms']:.0f}x | "
            f"{r['batch_s']:.2f} | {r['batch_threads_s']:.2f} | {r['batch_kernel_s']:.2f} | "
            f"{r['ref_batch_s']:.0f} |"
        )
    lines += [
        "",
        "Targets (issue 4): single < 5 ms warm, batch of 1,000 < 4 s, >= 10x faster than "
        "solve_ivp. The reference paper needed 3-9 s per simulation.",
        "",
        "The kernel and the Euler loop are compiled without numba reference counting "
        "(`models/lpm/kernel.py`, `_NO_NRT`): about 1 ms per 200 ms case instead of 5 ms. "
        "End to end, the rest is pulse preparation (~0.2 ms), histories (~0.2 ms), the CFC "
        "filters of one class in one call, HIC/Nij/chest criteria (~0.8 ms) and the "
        "assessment (~0.3 ms). `simulate_batch` pipelines the kernels (nogil) in worker "
        "threads with the preparation and post-processing in the calling thread; the "
        "post-processing holds the GIL about two thirds of the time, so on this 2-core "
        "machine shared with other sessions its gain over the plain loop varies from run "
        "to run (the GIL switch interval is 5 ms).",
    ]
    block = "\n".join(lines)
    print(block)
    if not args.no_write:
        write_section("occupant-lpms", block)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
