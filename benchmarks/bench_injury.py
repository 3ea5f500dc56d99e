"""Benchmark of the injury criteria library (issue 3).

Times HIC15 alone and the whole criteria pass on 250 ms of synthetic dummy
channels at 10 kHz (median of many repeats after warm-up), prints the figures
and writes the "Injury criteria" section of ``benchmarks/RESULTS.md``
(replacing an earlier version of that section, leaving the others alone).

Run from the repository root::

    python benchmarks/bench_injury.py [--repeats N]
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numba
import numpy as np
import scipy

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from results_md import RESULTS, write_section

from models.injury import (
    InjuryMeasures,
    assess,
    cfc_filter,
    chest_deflection,
    clip_3ms,
    cti,
    hic,
    nij,
    viscous_criterion,
)
from models.notification import Body

FS_HZ = 10_000.0
DURATION_S = 0.250


def _channels(seed: int = 3) -> dict[str, np.ndarray]:
    """Synthetic 250 ms frontal-crash dummy channels, shape (2500,) each."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, DURATION_S, 1.0 / FS_HZ)

    def bump(peak: float, centre: float, width: float) -> np.ndarray:
        return peak * np.exp(-(((t - centre) / width) ** 2))

    def noise(scale: float) -> np.ndarray:
        return rng.normal(0.0, scale, t.size)

    return {
        "head_x": -bump(55.0, 0.085, 0.012) - bump(30.0, 0.095, 0.002) + noise(1.0),
        "head_y": bump(5.0, 0.09, 0.01) + noise(1.0),
        "head_z": bump(20.0, 0.088, 0.01) + noise(1.0),
        "neck_fx": bump(600.0, 0.08, 0.015) + noise(20.0),
        "neck_fz": bump(1800.0, 0.085, 0.015) - bump(400.0, 0.12, 0.01) + noise(30.0),
        "neck_my": bump(40.0, 0.09, 0.015) - bump(25.0, 0.13, 0.01) + noise(1.0),
        "chest_defl_mm": bump(38.0, 0.075, 0.02) + noise(0.2),
        "chest_ax": -bump(45.0, 0.07, 0.02) + noise(1.0),
        "chest_ay": noise(1.0),
        "chest_az": bump(10.0, 0.07, 0.02) + noise(1.0),
        "abd_defl_mm": bump(30.0, 0.08, 0.02) + noise(0.2),
    }


def _criteria_pass(ch: dict[str, np.ndarray], body: Body) -> float:
    """Filter every channel at its class, compute every criterion, assess."""
    hx, hy, hz = (cfc_filter(ch[k], FS_HZ, 1000) for k in ("head_x", "head_y", "head_z"))
    head = np.sqrt(hx * hx + hy * hy + hz * hz)
    h15 = hic(head, FS_HZ, 15.0)
    hic(head, FS_HZ, 36.0)
    fx, fz, my = (cfc_filter(ch[k], FS_HZ, 600) for k in ("neck_fx", "neck_fz", "neck_my"))
    n = nij(fx, fz, my, body)
    defl = cfc_filter(ch["chest_defl_mm"], FS_HZ, 180)
    cd = chest_deflection(defl, body)
    vc = viscous_criterion(defl * 1e-3, FS_HZ, body)
    ax, ay, az = (cfc_filter(ch[k], FS_HZ, 180) for k in ("chest_ax", "chest_ay", "chest_az"))
    a3 = clip_3ms(np.sqrt(ax * ax + ay * ay + az * az), FS_HZ)
    c = cti(a3, cd.peak_mm, body)
    abd = cfc_filter(ch["abd_defl_mm"], FS_HZ, 180)
    vc_abd = viscous_criterion(abd * 1e-3, FS_HZ, body)
    result = assess(
        InjuryMeasures(
            hic15=h15.value,
            nij=n.value,
            chest_deflection_mm=cd.peak_mm,
            chest_vc_m_s=vc,
            chest_a3ms_g=a3,
            chest_cti=c,
            abdomen_vc_m_s=vc_abd,
        ),
        body,
        age_years=45.0,
    )
    return result.p_iss15


def _median_ms(fn: Callable[[], object], repeats: int, warmup: int = 20) -> tuple[float, float]:
    """Median and 90th percentile wall time of `fn`, ms."""
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1e3)
    times.sort()
    return statistics.median(times), times[int(0.9 * (len(times) - 1))]


def main() -> None:
    """Run the benchmark, print the figures and update RESULTS.md."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeats", type=int, default=500)
    parser.add_argument("--no-write", action="store_true", help="print only")
    args = parser.parse_args()

    ch = _channels()
    head = np.sqrt(sum(cfc_filter(ch[k], FS_HZ, 1000) ** 2 for k in ("head_x", "head_y", "head_z")))
    measures = InjuryMeasures(
        hic15=650.0, nij=0.6, chest_deflection_mm=38.0, chest_vc_m_s=0.5, abdomen_vc_m_s=0.4
    )
    rows = [
        ("HIC15 (exact, all windows <= 15 ms)", lambda: hic(head, FS_HZ, 15.0)),
        ("HIC36 (exact, all windows <= 36 ms)", lambda: hic(head, FS_HZ, 36.0)),
        ("CFC filter, one channel (CFC 1000)", lambda: cfc_filter(ch["head_x"], FS_HZ, 1000)),
        ("assess() on scalar measures", lambda: assess(measures, Body.MALE_50TH, 45.0)),
        ("whole criteria pass (11 channels)", lambda: _criteria_pass(ch, Body.MALE_50TH)),
    ]
    results = []
    for name, fn in rows:
        med, p90 = _median_ms(fn, args.repeats)
        results.append((name, med, p90))
        print(f"{name:40s} median {med:8.3f} ms   p90 {p90:8.3f} ms")

    n = int(round(DURATION_S * FS_HZ))
    lines = [
        "## Injury criteria",
        "",
        f"`python benchmarks/bench_injury.py` ({dt.datetime.now(dt.UTC):%Y-%m-%d %H:%M} UTC). "
        f"Input: {DURATION_S * 1e3:.0f} ms at {FS_HZ / 1e3:.0f} kHz ({n} samples per channel), "
        f"synthetic frontal-crash channels; median and 90th percentile of {args.repeats} "
        "repeats after 20 warm-up calls (numba compiled and cached before timing).",
        "",
        f"Machine: {os.cpu_count()} cores, {platform.processor() or platform.machine()}; "
        f"Python {platform.python_version()}, numpy {np.__version__}, scipy {scipy.__version__}, "
        f"numba {numba.__version__}.",
        "",
        "| Operation | Median (ms) | p90 (ms) |",
        "|---|---:|---:|",
        *(f"| {name} | {med:.3f} | {p90:.3f} |" for name, med, p90 in results),
        "",
        "The whole pass filters 11 channels (CFC 1000 head, CFC 600 neck, CFC 180 chest and "
        "abdomen), computes HIC15, HIC36, Nij, chest deflection, chest and abdominal VC, the "
        "3 ms clip and CTI, and runs `assess()` (exact P(ISS >= 15)). Target for HIC15: "
        "under 2 ms (issue 3).",
    ]
    if not args.no_write:
        write_section("injury-criteria", "\n".join(lines))
        print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
