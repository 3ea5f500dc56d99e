"""Calibration of LPM parameters against target dummy results.

Fits chosen parameters of a parameter set with
``scipy.optimize.differential_evolution`` (seeded, so a run is reproducible),
saving its population after every generation so that an interrupted run
resumes where it stopped, and reporting progress. The objective is the smooth
surrogate of occupant-lpm-notes.md section 6: the sum over cases and measures
of ``log(simulated / target)^2`` (a failed run costs 100 per case).

Run::

    python -m models.offline.lpm.calibrate --out DIR [--targets FILE.json]
        [--param KEY[=LO:HI] ...] [--seed 0] [--maxiter 30] [--popsize 6] [--resume]

Writes ``DIR/state.npz`` (resume state), ``DIR/<name>.json`` (the fitted
parameter set, every changed value's source noting the calibration) and
``DIR/report.md``.

Targets file: a JSON list of cases::

    [{"name": "ncap_50m", "mode": "frontal",
      "pulse": {"delta_v_kmh": 61.6, "duration_ms": 90, "pdof_deg": 0},
      "occupant": {"body": "male_50th", "belted": true, "frontal_airbag": "deployed"},
      "targets": {"hic15": 250, "chest_deflection_mm": 33, "nij": 0.35}}]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from models.impact_mode import ImpactMode
from models.lpm.params import ParameterSet, load_parameter_set
from models.lpm.pulses import haversine_pulse
from models.lpm.simulate import simulate
from models.notification import AirbagState, Body, Occupant, Seat

__all__ = ["DEFAULT_TARGETS", "CalibrationCase", "calibrate", "load_cases", "objective"]

#: Default targets [R]: mid-range NCAP-type values for the belted 50M with
#: airbag (inside the FMVSS 208 envelope, tests/lpm/test_published.py).
DEFAULT_TARGETS: list[dict[str, Any]] = [
    {
        "name": "ncap_frontal_50m",
        "mode": "frontal",
        "pulse": {"delta_v_kmh": 61.6, "duration_ms": 90.0, "pdof_deg": 0.0},
        "occupant": {"body": "male_50th", "belted": True, "frontal_airbag": "deployed"},
        "targets": {"hic15": 250.0, "chest_deflection_mm": 33.0, "nij": 0.35},
    },
    {
        "name": "ncap_frontal_5f",
        "mode": "frontal",
        "pulse": {"delta_v_kmh": 61.6, "duration_ms": 90.0, "pdof_deg": 0.0},
        "occupant": {"body": "female_5th", "belted": True, "frontal_airbag": "deployed"},
        "targets": {"hic15": 250.0, "chest_deflection_mm": 28.0, "nij": 0.45},
    },
]
DEFAULT_PARAMS = ("frontal.airbag.head_force", "frontal.airbag.chest_force")


@dataclass(frozen=True)
class CalibrationCase:
    """One target case: pulse, occupant, mode and target measures."""

    name: str
    mode: ImpactMode
    pulse: tuple[np.ndarray, np.ndarray, np.ndarray]
    occupant: Occupant
    targets: dict[str, float]


def load_cases(spec: Sequence[dict[str, Any]]) -> list[CalibrationCase]:
    """Cases from their JSON description (see the module docstring)."""
    out = []
    for c in spec:
        p = c["pulse"]
        pulse = haversine_pulse(
            float(p["delta_v_kmh"]),
            float(p["duration_ms"]) / 1000.0,
            angle_deg=float(p.get("pdof_deg", 0.0)),
        )
        o = c["occupant"]
        occ = Occupant(
            seat=Seat(o.get("seat", "driver")),
            body=Body(o["body"]),
            belted=bool(o["belted"]),
            frontal_airbag=AirbagState(o.get("frontal_airbag", "deployed")),
            age_years=o.get("age_years"),
            posture_lumbar_flexion_deg=float(o.get("posture_lumbar_flexion_deg", 5.8)),
            seat_track_mm=float(o.get("seat_track_mm", 0.0)),
        )
        out.append(
            CalibrationCase(
                str(c["name"]),
                ImpactMode(c["mode"]),
                pulse,
                occ,
                {k: float(v) for k, v in c["targets"].items()},
            )
        )
    return out


def objective(
    x: np.ndarray, keys: Sequence[str], base: ParameterSet, cases: Sequence[CalibrationCase]
) -> float:
    """Sum of squared log errors of the measures over the cases (dimensionless)."""
    try:
        ps = base.with_values(dict(zip(keys, (float(v) for v in x), strict=True)))
    except ValueError:
        return 1e3
    cost = 0.0
    for c in cases:
        r = simulate(*c.pulse, c.mode, c.occupant, ps)
        if r.status < 0:
            cost += 100.0
            continue
        for k, target in c.targets.items():
            v = getattr(r.measures, k)
            if v is None or not math.isfinite(v) or v <= 0.0:
                cost += 100.0
            else:
                cost += math.log(v / target) ** 2
    return cost


def _bounds(
    base: ParameterSet, specs: Sequence[str]
) -> tuple[list[str], list[tuple[float, float]]]:
    keys, bounds = [], []
    for s in specs:
        key, _, rng = s.partition("=")
        e = base.entries[key]
        if rng:
            lo, hi = (float(v) for v in rng.split(":"))
        else:
            if e.minimum is None or e.maximum is None:
                raise ValueError(f"{key} has no bounds in the file; give KEY=LO:HI")
            lo, hi = e.minimum, e.maximum
        keys.append(key)
        bounds.append((lo, hi))
    return keys, bounds


def calibrate(
    out: Path,
    *,
    cases: Sequence[CalibrationCase],
    params: Sequence[str],
    base: ParameterSet | None = None,
    seed: int = 0,
    maxiter: int = 30,
    popsize: int = 6,
    resume: bool = False,
    progress: bool = True,
) -> tuple[ParameterSet, float]:
    """Fit ``params`` of ``base`` to the cases; returns the fitted set and its cost.

    Parameters
    ----------
    out : Path
        Output folder (state, fitted set, report).
    cases : sequence of CalibrationCase
    params : sequence of str
        ``KEY`` (bounds from the file) or ``KEY=LO:HI``.
    base : ParameterSet, optional
        Start set (default: the shipped default set).
    seed : int
        Seed of differential evolution (reproducible runs).
    maxiter : int
        Total number of generations (a resumed run does the remainder).
    popsize : int
        Population multiplier of ``differential_evolution``.
    resume : bool
        Continue from ``out/state.npz`` when present.
    progress : bool
        Show a progress bar (tqdm, on stderr).
    """
    from scipy.optimize import differential_evolution
    from tqdm import tqdm

    base = base or load_parameter_set()
    keys, bounds = _bounds(base, params)
    out.mkdir(parents=True, exist_ok=True)
    state_path = out / "state.npz"
    done = 0
    init: np.ndarray | str = "latinhypercube"
    if resume and state_path.exists():
        st = np.load(state_path, allow_pickle=False)
        if list(st["keys"]) != keys or int(st["seed"]) != seed:
            raise ValueError("state.npz was written for other parameters or another seed")
        init = np.asarray(st["population"], dtype=np.float64)
        done = int(st["nit"])
    remaining = max(maxiter - done, 0)
    bar = tqdm(total=maxiter, initial=done, disable=not progress, desc="calibrate", file=sys.stderr)

    def callback(intermediate_result: Any) -> None:
        nonlocal done
        done += 1
        np.savez(
            state_path,
            keys=np.array(keys),
            seed=np.array(seed),
            nit=np.array(done),
            population=np.asarray(intermediate_result.population),
            energies=np.asarray(intermediate_result.population_energies),
            x=np.asarray(intermediate_result.x),
            fun=np.array(intermediate_result.fun),
        )
        bar.update(1)
        bar.set_postfix(cost=f"{float(intermediate_result.fun):.4g}")

    if remaining > 0:
        res = differential_evolution(
            objective,
            bounds,
            args=(keys, base, list(cases)),
            seed=seed + done,
            maxiter=remaining,
            popsize=popsize,
            init=init,
            polish=False,
            tol=0.0,
            updating="deferred",
            callback=callback,
        )
        x, fun = np.asarray(res.x), float(res.fun)
    else:
        st = np.load(state_path, allow_pickle=False)
        x, fun = np.asarray(st["x"]), float(st["fun"])
    bar.close()
    fitted = base.with_values(
        dict(zip(keys, (float(v) for v in x), strict=True)),
        name=f"{base.name}_calibrated",
        note=f"calibrated by models.offline.lpm.calibrate (seed {seed})",
    )
    (out / f"{fitted.name}.json").write_text(json.dumps(fitted.to_document(), indent=1) + "\n")
    lines = [
        f"# LPM calibration ({fitted.name})",
        "",
        f"cost {fun:.6g}, {done} generations, "
        f"seed {seed}, base set {base.name} ({base.sha256[:12]})",
        "",
        "| parameter | start | fitted | bounds |",
        "|---|---|---|---|",
    ]
    for k, v, b in zip(keys, x, bounds, strict=True):
        lines.append(f"| {k} | {base[k]:.6g} | {float(v):.6g} | {b[0]:.4g}-{b[1]:.4g} |")
    lines += ["", "| case | measure | target | fitted |", "|---|---|---|---|"]
    for c in cases:
        r = simulate(*c.pulse, c.mode, c.occupant, fitted)
        for k, tv in c.targets.items():
            v = getattr(r.measures, k)
            lines.append(
                f"| {c.name} | {k} | {tv:.4g} | {'n/a' if v is None else format(v, '.4g')} |"
            )
    (out / "report.md").write_text("\n".join(lines) + "\n")
    return fitted, fun


def main(argv: list[str] | None = None) -> int:
    """Command line entry point."""
    ap = argparse.ArgumentParser(description="Calibrate LPM parameters (differential evolution).")
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--targets", type=Path)
    ap.add_argument(
        "--param",
        action="append",
        default=None,
        help="KEY or KEY=LO:HI (repeatable); default: airbag head/chest force",
    )
    ap.add_argument("--base", default="compact_sedan")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--maxiter", type=int, default=30)
    ap.add_argument("--popsize", type=int, default=6)
    ap.add_argument("--resume", action="store_true")
    args = ap.parse_args(argv)
    spec = json.loads(args.targets.read_text()) if args.targets else DEFAULT_TARGETS
    fitted, fun = calibrate(
        args.out,
        cases=load_cases(spec),
        params=args.param or list(DEFAULT_PARAMS),
        base=load_parameter_set(args.base),
        seed=args.seed,
        maxiter=args.maxiter,
        popsize=args.popsize,
        resume=args.resume,
    )
    sys.stdout.write(f"cost {fun:.6g}; wrote {args.out / (fitted.name + '.json')}\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
