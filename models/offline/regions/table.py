"""The occupant models on every usable NASS-CDS 1997-2014 occupant: a cached physics table.

Each usable occupant (:mod:`models.offline.regions.rows`) is sent through the
engine's occupant-model path as the service would run it for a summary
notification: the pulse processed (:func:`models.pulse.process_pulse`), the
impact classified from PDOF and seat, the unsensed posture and seat track
resolved (:func:`models.sensor_evidence.resolve_sensor_evidence`: the neutral
posture and the centre of the seat track, inside the models' domain), and the
occupant model run directly (:func:`models.lpm.simulate.simulate_batch`, the
compiled kernels in threads). Occupants with the same physics inputs (delta-V,
PDOF, seat, body, belt, airbags) share one run; each is then assessed at its
own age: region AIS, ISS, P(ISS >= 15) and its zero-load-corrected value
(:mod:`models.risk_calibration`), exactly as the service's direct run.

Runs are cached in a JSON-lines file named by a key over everything that can
change them (engine version, occupant-model code and parameters, the
orchestration code, this module and the rows module), so an interrupted run
resumes and a rerun costs nothing; a progress bar shows the work. The table
itself (one row per occupant, keyed by ``year, psu, caseno, vehno, occno``)
is written beside the cache as ``physics-<key>.csv.gz``.

Run::

    python -m models.offline.regions.table [--out DIR] [--workers N] [--side-airbag deployed]

``--out`` defaults to ``build/regions`` (git-ignored). In Python::

    from models.offline.regions.table import physics_table
    table = physics_table()  # pandas DataFrame, one row per usable occupant

Occupants out of every occupant model's coverage (between the modes' PDOF
ranges) have ``in_lpm`` 0 and empty measures.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Final

import numpy as np
import pandas as pd
from tqdm import tqdm

from models import ENGINE_VERSION
from models.assumptions import Assumption
from models.impact_mode import ImpactMode, classify_impact
from models.injury.assessment import assess
from models.injury.measures import InjuryMeasures
from models.injury.reported import reported_levels
from models.injury.scores import ISS_REGIONS
from models.lpm.fingerprint import lpm_code_sha256, sources_sha256
from models.lpm.params import DEFAULT_SET, ParameterSet, load_parameter_set
from models.lpm.simulate import BatchCase, simulate_batch
from models.notification import AirbagState, Occupant
from models.offline.regions.rows import (
    KEY_COLUMNS,
    OccupantRow,
    load_occupant_rows,
    occupant_notification,
)
from models.pulse import process_pulse
from models.risk_calibration import corrected_probability, zero_load_probability
from models.sensor_evidence import resolve_sensor_evidence

__all__ = [
    "MEASURE_COLUMNS",
    "PhysicsInput",
    "default_out_dir",
    "physics_input",
    "physics_key",
    "physics_table",
    "run_physics",
]

#: Injury measures cached per run (names with units, as InjuryMeasures).
MEASURE_COLUMNS: Final[tuple[str, ...]] = tuple(f.name for f in fields(InjuryMeasures))
#: Source files (under models/) whose content changes the runs, beside the
#: occupant-model code (:data:`models.lpm.fingerprint.MODEL_SOURCES`).
RUN_SOURCES: Final[tuple[str, ...]] = (
    "pulse.py",
    "impact_mode.py",
    "notification.py",
    "sensor_evidence.py",
    "offline/regions/rows.py",
)
#: ... and those that change only the table made from the runs.
TABLE_SOURCES: Final[tuple[str, ...]] = (
    *RUN_SOURCES,
    "risk_calibration.py",
    "injury/reported.py",
    "offline/regions/table.py",
)
#: Runs handed to the batch at once (the cache is appended after each chunk).
CHUNK: Final[int] = 256


def default_out_dir() -> Path:
    """``build/regions`` of the repository (git-ignored)."""
    return Path(__file__).resolve().parents[3] / "build" / "regions"


@dataclass(frozen=True)
class PhysicsInput:
    """What determines one occupant-model run (occupants sharing it share the run)."""

    delta_v_kmh: float
    pdof_deg: float
    seat: str
    body: str
    belted: bool
    frontal_airbag: str
    side_airbag: str | None

    def text(self) -> str:
        """A stable text key."""
        return json.dumps([getattr(self, f.name) for f in fields(self)])


def physics_input(row: OccupantRow, side_airbag: AirbagState | None = None) -> PhysicsInput:
    """The run an occupant needs."""
    return PhysicsInput(
        delta_v_kmh=row.delta_v_kmh,
        pdof_deg=row.pdof_deg,
        seat=row.seat.value,
        body=row.body.value,
        belted=row.belted,
        frontal_airbag=row.frontal_airbag.value,
        side_airbag=None if side_airbag is None else side_airbag.value,
    )


def physics_key(params: ParameterSet, label: str, *, table: bool = False) -> str:
    """Cache key: the variant label and every checksum that can change a run (or the table)."""
    parts = [
        label,
        ENGINE_VERSION,
        lpm_code_sha256(),
        sources_sha256(TABLE_SOURCES if table else RUN_SOURCES),
        params.name,
        params.sha256,
    ]
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()[:16]


@dataclass(frozen=True)
class _Prepared:
    occupant: Occupant
    mode: ImpactMode
    in_lpm: bool
    angle_deg: float
    case: BatchCase | None


def _prepare(row: OccupantRow, side_airbag: AirbagState | None) -> _Prepared:
    """The service's path from notification to occupant-model inputs (direct run)."""
    notification = occupant_notification(row, side_airbag=side_airbag)
    pulse = process_pulse(notification.pulse)
    occupant = notification.occupants[0]
    impact = classify_impact(pulse.pdof_deg, occupant.seat, notification.drive_side)
    assumptions: list[Assumption] = []
    occupant = resolve_sensor_evidence(occupant, 0, assumptions)
    case = None
    if impact.in_lpm_coverage:
        case = BatchCase(
            time_s=pulse.time_s,
            accel_x_g=pulse.longitudinal_g,
            accel_y_g=pulse.lateral_g,
            mode=impact.mode,
            occupant=occupant,
            angle_deg=impact.angle_from_axis_deg,
        )
    return _Prepared(
        occupant, impact.mode, impact.in_lpm_coverage, impact.angle_from_axis_deg, case
    )


def _read_cache(path: Path) -> dict[str, dict[str, Any]]:
    done: dict[str, dict[str, Any]] = {}
    if path.is_file():
        for line in path.read_text(encoding="utf-8").splitlines():
            try:
                rec = json.loads(line)
                done[rec["input"]] = rec
            except (ValueError, KeyError, TypeError):
                continue  # a line cut short by an interrupted run
    return done


def _chunks(items: Sequence[Any], n: int) -> Iterator[Sequence[Any]]:
    for i in range(0, len(items), n):
        yield items[i : i + n]


def run_physics(
    rows: Sequence[OccupantRow],
    *,
    out_dir: Path | None = None,
    side_airbag: AirbagState | None = None,
    workers: int | None = None,
    progress: bool = True,
    params: ParameterSet | None = None,
) -> dict[str, dict[str, Any]]:
    """The occupant-model runs the rows need, cached and resumable.

    Parameters
    ----------
    rows : sequence of OccupantRow
    out_dir : Path, optional
        Cache directory, default :func:`default_out_dir`.
    side_airbag : AirbagState, optional
        Side airbag state reported for every occupant (None: not reported).
    workers : int, optional
        Threads of the compiled kernels (default: the CPU count).
    progress : bool
    params : ParameterSet, optional
        Default: the default vehicle's set.

    Returns
    -------
    dict of str to dict
        Per :meth:`PhysicsInput.text`: ``mode``, ``in_lpm``, ``status`` and the
        measures (None where absent).
    """
    ps = params or load_parameter_set(DEFAULT_SET)
    root = out_dir or default_out_dir()
    root.mkdir(parents=True, exist_ok=True)
    label = f"side_airbag={side_airbag}"
    path = root / f"runs-{physics_key(ps, label)}.jsonl"
    done = _read_cache(path)
    todo: dict[str, OccupantRow] = {}
    for row in rows:
        text = physics_input(row, side_airbag).text()
        if text not in done and text not in todo:
            todo[text] = row
    if not todo:
        return done
    items = list(todo.items())
    if path.is_file() and path.stat().st_size > 0:
        with path.open("rb") as fh:
            fh.seek(-1, 2)
            cut = fh.read(1) != b"\n"
        if cut:  # a line cut short by an interrupted run: end it before appending
            with path.open("a", encoding="utf-8") as fh:
                fh.write("\n")
    with (
        path.open("a", encoding="utf-8") as out,
        tqdm(total=len(items), desc="occupant-model runs", disable=not progress) as bar,
    ):
        for chunk in _chunks(items, CHUNK):
            prepared = [_prepare(row, side_airbag) for _, row in chunk]
            cases = [p.case for p in prepared if p.case is not None]
            results = iter(simulate_batch(cases, ps, workers=workers))
            for (text, _), p in zip(chunk, prepared, strict=True):
                rec: dict[str, Any] = {"input": text, "mode": p.mode.value, "in_lpm": p.in_lpm}
                rec["angle_deg"] = p.angle_deg
                if p.case is not None:
                    r = next(results)
                    rec["status"] = r.status
                    ok = r.assessment is not None
                    for name in MEASURE_COLUMNS:
                        v = getattr(r.measures, name)
                        rec[name] = float(v) if ok and v is not None else None
                out.write(json.dumps(rec) + "\n")
                done[text] = rec
            out.flush()
            bar.update(len(chunk))
    return done


def _assessed(row: OccupantRow, run: dict[str, Any]) -> dict[str, Any]:
    """One occupant's table row from its run, assessed at its age."""
    out: dict[str, Any] = dict(zip(KEY_COLUMNS, row.key, strict=True))
    out.update(
        seat=row.seat.value,
        body=row.body.value,
        belted=int(row.belted),
        frontal_airbag=row.frontal_airbag.value,
        frontal_airbag_known=int(row.frontal_airbag_known),
        age_years=row.age_years,
        delta_v_kmh=row.delta_v_kmh,
        pdof_deg=row.pdof_deg,
        rollover=int(row.rollover),
        multiple_impacts=int(row.multiple_impacts),
        mode=run["mode"],
        angle_deg=run["angle_deg"],
        in_lpm=int(run["in_lpm"]),
    )
    values = {name: run.get(name) for name in MEASURE_COLUMNS}
    out.update({name: np.nan if v is None else v for name, v in values.items()})
    ok = run["in_lpm"] and run.get("status", -1) >= 0
    out["lpm_ok"] = int(ok)
    if ok:
        measures = InjuryMeasures(**values)
        mode = ImpactMode(run["mode"])
        a = assess(measures, row.body, row.age_years, mode.value)
        p0 = zero_load_probability(measures, row.body, row.age_years, mode)
        shown = reported_levels(a.region_ais)
        for region in ISS_REGIONS:
            out[f"lpm_ais_{region}"] = a.region_ais[region]
            out[f"reported_ais_{region}"] = shown.region_ais[region]
        out["reported_iss"] = shown.iss
        for region in ("head_neck", "chest", "abdomen"):
            dist = a.region_ais_probability[region]
            out[f"lpm_p_ais3_{region}"] = float(sum(dist[3:]))
        out.update(
            lpm_iss=a.iss,
            lpm_p_iss15=a.p_iss15,
            lpm_p_iss15_zero_load=p0,
            lpm_p_iss15_corrected=corrected_probability(a.p_iss15, p0),
        )
    return out


def physics_table(
    rows: Sequence[OccupantRow] | None = None,
    *,
    out_dir: Path | None = None,
    side_airbag: AirbagState | None = None,
    workers: int | None = None,
    progress: bool = True,
    params: ParameterSet | None = None,
) -> pd.DataFrame:
    """One row per usable occupant: inputs, the occupant model's measures and scores.

    Parameters
    ----------
    rows : sequence of OccupantRow, optional
        Default: every usable occupant of the shipped file.
    out_dir, side_airbag, workers, progress, params
        As :func:`run_physics`.

    Returns
    -------
    DataFrame
        Keys :data:`KEY_COLUMNS`; the occupant's inputs (seat, body, belt,
        frontal airbag, age, delta-V km/h, PDOF deg, rollover, multiple
        impacts); ``mode``, ``angle_deg``, ``in_lpm``, ``lpm_ok``; the measures
        :data:`MEASURE_COLUMNS`; ``lpm_ais_<ISS region>`` (the assessment's
        level), ``reported_ais_<ISS region>`` and ``reported_iss`` (as the service
        reports them: :mod:`models.injury.reported`), ``lpm_p_ais3_<region>``
        (P(AIS >= 3) of head_neck, chest, abdomen from the risk curves),
        ``lpm_iss``, ``lpm_p_iss15`` (the risk curves'),
        ``lpm_p_iss15_zero_load`` and ``lpm_p_iss15_corrected`` (the
        zero-load-corrected P the service reports).
    """
    rows = load_occupant_rows() if rows is None else rows
    runs = run_physics(
        rows,
        out_dir=out_dir,
        side_airbag=side_airbag,
        workers=workers,
        progress=progress,
        params=params,
    )
    records = [
        _assessed(row, runs[physics_input(row, side_airbag).text()])
        for row in tqdm(rows, desc="assessing occupants", disable=not progress)
    ]
    return pd.DataFrame.from_records(records)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line entry point."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=None, help="cache and table directory")
    ap.add_argument("--workers", type=int, default=None, help="kernel threads")
    ap.add_argument(
        "--side-airbag",
        choices=("unreported", "deployed"),
        default="unreported",
        help="side airbag state reported for every occupant (the file has none)",
    )
    ap.add_argument("--limit", type=int, default=None, help="first N usable occupants only")
    ap.add_argument("--no-progress", action="store_true")
    args = ap.parse_args(list(argv) if argv is not None else None)
    side = AirbagState.DEPLOYED if args.side_airbag == "deployed" else None
    rows = load_occupant_rows()
    if args.limit is not None:
        rows = rows[: args.limit]
    out_dir = args.out or default_out_dir()
    ps = load_parameter_set(DEFAULT_SET)
    table = physics_table(
        rows,
        out_dir=out_dir,
        side_airbag=side,
        workers=args.workers,
        progress=not args.no_progress,
        params=ps,
    )
    suffix = "" if args.limit is None else f"-first{args.limit}"
    key = physics_key(ps, f"side_airbag={side}", table=True)
    path = out_dir / f"physics-{key}{suffix}.csv.gz"
    table.to_csv(path, index=False)
    n_lpm = int(table["lpm_ok"].sum())
    sys.stdout.write(
        f"{len(table):,} usable occupants, {n_lpm:,} answered by an occupant model; table: {path}\n"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
