"""Field rows as notifications: the NASS-CDS files read the way the service reads a call.

Each row of ``data/nass-cds-mais-2000-2014-calibration.csv`` (PROVENANCE.md) becomes
the notification a call center would have sent for that occupant: a summary pulse
(delta-V and the PDOF from the clock direction), the belt, the age, stature and
mass, the multiple-impact and rollover flags, posture and seat position not
sensed. What the file does not hold is assumed, as named constants:

- seat: the file has no seat. Near- and far-side rows take the seat on the
  struck (near) or the other (far) side of a left-hand-drive car, so that the
  service's impact classification from PDOF and seat gives the file's side;
  every other row is the driver.
- frontal airbag: the file has no airbag column; the vehicles are under 10 years
  old in 2000-2014 and almost all have frontal airbags (mandatory from MY 1998,
  FMVSS 208). Taken as deployed in frontal rows at or above
  :data:`ASSUMED_DEPLOY_DELTA_V_KMH`, else not deployed. Side airbags are not
  reported (the engine then assumes none).

The frontal occupants of NASS-CDS 1997-2000 (police-reported outcome, shipped
with the statistical baseline) become notifications the same way
(:func:`police_notification`): delta-V at the band midpoint, PDOF 0, the seat,
belt, airbag state, sex and age of the row.

Only the offline fit, the evaluation and the tests read these rows; the request
path never does.
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from models.notification import (
    AirbagState,
    Body,
    CrashNotification,
    DriveSide,
    Occupant,
    Seat,
    SeatTrackSource,
    Sex,
    SummaryPulse,
    nearest_body,
)
from models.offline.field_check import FieldCase
from models.offline.paths import DATA_DIR
from models.units import KM_PER_MILE, mph_to_kmh

__all__ = [
    "ASSUMED_DEPLOY_DELTA_V_KMH",
    "DELTA_V_UNIT_TOLERANCE_KMH",
    "police_notification",
    "rows_by_mode",
    "CALIBRATION_CSV",
    "CRASH_MODES",
    "CalibrationRow",
    "clock_to_pdof_deg",
    "load_calibration_rows",
    "row_notification",
]

#: The shipped calibration file (PROVENANCE.md beside it).
CALIBRATION_CSV: Final[Path] = DATA_DIR / "nass-cds-mais-2000-2014-calibration.csv"

#: The file's crash modes.
CRASH_MODES: Final[tuple[str, ...]] = ("Frontal", "NS", "FS", "Rear", "roll")

#: Delta-V from which a frontal airbag is taken as deployed when the data do not
#: say, km/h. [R] between the FMVSS 208 "no fire" (about 13 km/h, 8 mph) and
#: "must fire" (about 26 km/h, 16 mph) speeds of frontal airbag sensing.
ASSUMED_DEPLOY_DELTA_V_KMH: Final[float] = 20.0

#: Largest accepted difference between the file's km/h delta-V and its mph
#: delta-V converted, km/h. [R] The source extract divided by a rounded factor
#: (1.6093: 20 km/h is 12.4278 mph) and kept 4 decimals, so the mph column
#: times 1.609344 runs up to 2.8e-5 high: 0.0032 km/h at the largest, 117 km/h.
#: 0.01 km/h allows that and refuses any other unit (mph read as km/h is 38 % off).
DELTA_V_UNIT_TOLERANCE_KMH: Final[float] = 0.01


@dataclass(frozen=True)
class CalibrationRow:
    """One occupant of the calibration file (the columns a notification can carry).

    Attributes
    ----------
    row : int
        Row number in the file.
    mais3 : bool
        Outcome: MAIS >= 3.
    mais : int
        Maximum AIS, 0-6.
    crash_mode : str
        One of :data:`CRASH_MODES`.
    delta_v_kmh : float
        Total delta-V, km/h (reconstructed).
    belted : bool
    age_years : float
    stature_cm, mass_kg : float
    multiple_impacts : bool
    pdof_clock : int
        Principal direction of force, clock (12 front, 3 right).
    """

    row: int
    mais3: bool
    mais: int
    crash_mode: str
    delta_v_kmh: float
    belted: bool
    age_years: float
    stature_cm: float
    mass_kg: float
    multiple_impacts: bool
    pdof_clock: int

    @property
    def rollover(self) -> bool:
        """The file's rollover mode."""
        return self.crash_mode == "roll"

    @property
    def pdof_deg(self) -> float:
        """PDOF, deg clockwise from straight ahead."""
        return clock_to_pdof_deg(self.pdof_clock)


def clock_to_pdof_deg(clock: int) -> float:
    """Clock direction (1-12) to degrees clockwise from straight ahead (12 -> 0, 3 -> 90)."""
    if not 1 <= clock <= 12:
        raise ValueError(f"clock direction must be 1-12, got {clock}")
    return float((clock % 12) * 30)


def _checked_delta_v_kmh(rec: dict[str, str]) -> float:
    """The row's delta-V in km/h, held against the file's mph column.

    The file carries both units (``delta_v_kmh``, NASS-CDS's integer km/h, and
    ``delta_v_mph`` = km/h / 1.609344, as the source extract stored it). An
    earlier copy had one mph column labelled km/h (``data/PROVENANCE-mais-2000-2014.md``,
    "Units correction"); a file without the named km/h column, or whose two
    columns disagree, is refused rather than read in the wrong unit.
    """
    if "delta_v_kmh" not in rec:
        raise ValueError(
            f"row {rec.get('row')}: no `delta_v_kmh` column (a file with an unlabelled "
            "`delta_v` is the mislabelled mph copy: use the corrected file)"
        )
    delta_v_kmh = float(rec["delta_v_kmh"])
    delta_v_mph = float(rec["delta_v_mph"])
    if abs(mph_to_kmh(delta_v_mph) - delta_v_kmh) > DELTA_V_UNIT_TOLERANCE_KMH:
        raise ValueError(
            f"row {rec['row']}: delta_v_kmh {delta_v_kmh} is not delta_v_mph "
            f"{delta_v_mph} x {KM_PER_MILE}"
        )
    return delta_v_kmh


def load_calibration_rows(path: Path | None = None) -> tuple[CalibrationRow, ...]:
    """Read the calibration CSV.

    Parameters
    ----------
    path : Path, optional
        Default: :data:`CALIBRATION_CSV`.

    Returns
    -------
    tuple of CalibrationRow
        In file order.

    Raises
    ------
    ValueError
        A row with an unknown crash mode or a missing column, or whose km/h
        and mph delta-V disagree.
    """
    rows = []
    with (path or CALIBRATION_CSV).open(newline="", encoding="utf-8") as fh:
        for rec in csv.DictReader(fh):
            mode = rec["crash_mode"]
            if mode not in CRASH_MODES:
                raise ValueError(f"row {rec['row']}: unknown crash_mode {mode!r}")
            rows.append(
                CalibrationRow(
                    row=int(rec["row"]),
                    mais3=rec["mais3pl"] == "1",
                    mais=int(rec["mais"]),
                    crash_mode=mode,
                    delta_v_kmh=_checked_delta_v_kmh(rec),
                    belted=rec["belt_use"] == "1",
                    age_years=float(rec["age"]),
                    stature_cm=float(rec["height"]),
                    mass_kg=float(rec["weight"]),
                    multiple_impacts=rec["multi"] == "1",
                    pdof_clock=int(rec["pri_dir_force"]),
                )
            )
    return tuple(rows)


def _seat(row: CalibrationRow) -> Seat:
    """The seat that makes a left-hand-drive car's classification give the row's side."""
    struck_left = 7 <= row.pdof_clock <= 11
    if row.crash_mode == "NS":
        return Seat.DRIVER if struck_left else Seat.FRONT_PASSENGER
    if row.crash_mode == "FS":
        return Seat.FRONT_PASSENGER if struck_left else Seat.DRIVER
    return Seat.DRIVER


def row_notification(row: CalibrationRow, *, event_id: str | None = None) -> CrashNotification:
    """The notification a call center would have sent for this occupant.

    Parameters
    ----------
    row : CalibrationRow
    event_id : str, optional
        Default ``calibration-<row>``.

    Returns
    -------
    CrashNotification
        One occupant, summary pulse, posture and seat position not sensed.
    """
    deployed = row.crash_mode == "Frontal" and row.delta_v_kmh >= ASSUMED_DEPLOY_DELTA_V_KMH
    body = nearest_body(row.stature_cm, row.mass_kg) or Body.MALE_50TH
    occupant = Occupant(
        seat=_seat(row),
        body=body,
        belted=row.belted,
        frontal_airbag=AirbagState.DEPLOYED if deployed else AirbagState.NOT_DEPLOYED,
        side_airbag=None,
        age_years=row.age_years,
        sex=None,
        posture_sensed=False,
        seat_track_source=SeatTrackSource.NOT_SENSED,
        stature_cm=row.stature_cm,
        mass_kg=row.mass_kg,
    )
    return CrashNotification(
        event_id=event_id or f"calibration-{row.row}",
        vehicle_model="compact_sedan",
        drive_side=DriveSide.LEFT,
        pulse=SummaryPulse(delta_v_kmh=row.delta_v_kmh, pdof_deg=row.pdof_deg),
        multiple_impacts=row.multiple_impacts,
        rollover=row.rollover,
        occupants=(occupant,),
    )


def rows_by_mode(rows: Sequence[CalibrationRow]) -> dict[str, int]:
    """Count of rows per crash mode (a check of the file against its README)."""
    out = dict.fromkeys(CRASH_MODES, 0)
    for r in rows:
        out[r.crash_mode] += 1
    return out


def police_notification(case: FieldCase, index: int) -> CrashNotification:
    """The notification of a NASS-CDS 1997-2000 frontal occupant (a police-outcome row).

    Parameters
    ----------
    case : FieldCase
    index : int
        Position of the case (gives the event id ``police-<index>``).

    Returns
    -------
    CrashNotification
        One occupant, summary pulse at the band midpoint and PDOF 0, posture and
        seat position not sensed; body from sex (no stature or mass in the file).
    """
    occupant = Occupant(
        seat=case.seat,
        body=Body.MALE_50TH if case.male else Body.FEMALE_5TH,
        belted=case.belted,
        frontal_airbag=case.frontal_airbag,
        side_airbag=None,
        age_years=case.age_years,
        sex=Sex.MALE if case.male else Sex.FEMALE,
        posture_sensed=False,
        seat_track_source=SeatTrackSource.NOT_SENSED,
    )
    return CrashNotification(
        event_id=f"police-{index}",
        vehicle_model="compact_sedan",
        drive_side=DriveSide.LEFT,
        pulse=SummaryPulse(delta_v_kmh=case.delta_v_kmh, pdof_deg=0.0),
        multiple_impacts=False,
        rollover=False,
        occupants=(occupant,),
    )
