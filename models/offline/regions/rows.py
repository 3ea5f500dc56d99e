"""NASS-CDS 1997-2014 occupants as the notifications a call center would have sent.

The shipped copy of ``nass-cds-1997-2014-occupants.csv.gz`` (PROVENANCE beside it)
holds every occupant record, with each occupant's highest AIS per body region.
:func:`load_occupant_rows` keeps the occupants an occupant model can be asked
about and whose outcome is known (:data:`USABLE_RULES`), and
:func:`occupant_notification` turns one into a one-occupant notification read
the way the service reads a call. What the file does not hold is assumed, as
named here:

- seat: NASS seat 11 is the driver, 13 the front right passenger of a
  left-hand-drive car (the US fleet); rows 2 and 3 (left, middle, right) are
  the rear seats of that side (no occupant model answers for them: they are
  kept so that the table covers the field model's population, which names
  them); the front middle seat (NASS 12, no seat of a notification) is left out;
- body: the Hybrid III dummy nearer the occupant's stature and mass
  (:func:`models.notification.nearest_body`), else by sex (female -> 5th
  female), else the 50th male;
- frontal airbag: the file's state (``deployed``, ``not_deployed``, ``none``
  -> absent); unknown is taken as not deployed (for the occupant models the
  same as absent: no bag acts);
- side airbag: not in the file, so not reported (the engine then assumes none,
  as it does for a notification that does not say);
- PDOF: ``pdof1_deg``; where it is empty (every crash of 2005 and some others)
  the direction of the delta-V components, rounded to a whole degree;
- posture and seat position not sensed; multiple impacts when the vehicle had
  more than one harmful event; rollover when it rolled a quarter turn or more.

Only offline tools and tests read these rows; the request path never does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Final

import numpy as np
import pandas as pd

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
from models.offline.paths import DATA_DIR
from models.pulse import pdof_from_delta_v

__all__ = [
    "AIS_REGIONS",
    "KEY_COLUMNS",
    "MIN_AGE_YEARS",
    "OCCUPANTS_CSV",
    "USABLE_RULES",
    "OccupantRow",
    "load_occupant_frame",
    "load_occupant_rows",
    "occupant_key",
    "occupant_notification",
    "usable_mask",
]

#: The shipped occupant file (PROVENANCE-nass-cds-1997-2014-occupants.md beside it).
OCCUPANTS_CSV: Final[Path] = DATA_DIR / "nass-cds-1997-2014-occupants.csv.gz"

#: An occupant's key in the file: a crash is (year, psu, caseno), a vehicle adds
#: vehno, an occupant occno.
KEY_COLUMNS: Final[tuple[str, ...]] = ("year", "psu", "caseno", "vehno", "occno")

#: The file's AIS 1990 body regions (``max_ais_<region>``).
AIS_REGIONS: Final[tuple[str, ...]] = (
    "head",
    "face",
    "neck",
    "thorax",
    "abdomen",
    "spine",
    "upper_extremity",
    "lower_extremity",
)

#: Youngest occupant kept, years. [R] The occupant models are of adults (Hybrid III
#: 50th male and 5th female); 16 is the adult cut of the project's MAIS file.
MIN_AGE_YEARS: Final[float] = 16.0

#: NASS seat codes of the front outboard seats of a left-hand-drive car.
SEAT_CODES: Final[dict[int, Seat]] = {11: Seat.DRIVER, 13: Seat.FRONT_PASSENGER}
#: Rear seats (NASS rows 2 and 3) by side.
REAR_SEATS: Final[dict[str, Seat]] = {
    "left": Seat.REAR_LEFT,
    "middle": Seat.REAR_MIDDLE,
    "right": Seat.REAR_RIGHT,
}

#: What makes an occupant usable, in words (the same rules as :func:`usable_mask`).
USABLE_RULES: Final[tuple[str, ...]] = (
    f"age {MIN_AGE_YEARS:g} years or more",
    "front outboard seat (NASS 11 driver, 13 right front passenger) or a seat of rows 2-3"
    " with a side (no occupant model answers there)",
    "delta-V reconstructed",
    "ISS and every region's AIS known (not 'injured, severity unknown')",
    "manual belt use known (belted or none; a child seat excluded)",
    "a direction of force (PDOF, or delta-V components)",
)

_FRONTAL_AIRBAG: Final[dict[str, AirbagState]] = {
    "deployed": AirbagState.DEPLOYED,
    "not_deployed": AirbagState.NOT_DEPLOYED,
    "none": AirbagState.ABSENT,
}


def load_occupant_frame(path: Path | None = None) -> pd.DataFrame:
    """The whole occupant file as a data frame (gzip detected)."""
    return pd.read_csv(path or OCCUPANTS_CSV)


def _pdof(frame: pd.DataFrame) -> pd.Series:
    """PDOF, deg: ``pdof1_deg``, else the direction of the delta-V components."""
    comp = [
        float(round(pdof_from_delta_v(lo, la))) % 360.0
        if math.isfinite(lo) and math.isfinite(la) and (lo != 0.0 or la != 0.0)
        else math.nan
        for lo, la in zip(frame["delta_v_long_kmh"], frame["delta_v_lat_kmh"], strict=True)
    ]
    return frame["pdof1_deg"].where(frame["pdof1_deg"].notna(), pd.Series(comp, index=frame.index))


def usable_mask(frame: pd.DataFrame) -> pd.Series:
    """Boolean mask of the rows :data:`USABLE_RULES` keep."""
    regions = [f"max_ais_{r}" for r in AIS_REGIONS]
    return (
        (frame["age_years"] >= MIN_AGE_YEARS)
        & (
            frame["seat_code"].isin(list(SEAT_CODES))
            | (frame["seat_row"].isin([2, 3]) & frame["seat_side"].isin(list(REAR_SEATS)))
        )
        & frame["delta_v_kmh"].notna()
        & (frame["delta_v_kmh"] > 0)
        & frame["iss"].notna()
        & (frame["injured_severity_unknown"] != 1)
        & frame[regions].notna().all(axis=1)
        & frame["belt"].isin(["belted", "none"])
        & _pdof(frame).notna()
    )


@dataclass(frozen=True)
class OccupantRow:
    """One usable occupant: what a notification carries, and the key."""

    year: int
    psu: int
    caseno: int
    vehno: int
    occno: int
    seat: Seat
    body: Body
    belted: bool
    frontal_airbag: AirbagState
    frontal_airbag_known: bool
    age_years: float
    sex: Sex | None
    stature_cm: float | None
    mass_kg: float | None
    delta_v_kmh: float
    pdof_deg: float
    multiple_impacts: bool
    rollover: bool

    @property
    def key(self) -> tuple[int, int, int, int, int]:
        """(year, psu, caseno, vehno, occno)."""
        return (self.year, self.psu, self.caseno, self.vehno, self.occno)


def occupant_key(key: tuple[int, int, int, int, int]) -> str:
    """The key as text, ``year:psu:caseno:vehno:occno`` (an event id)."""
    return ":".join(str(k) for k in key)


def _opt(x: object) -> float | None:
    v = float(x)  # type: ignore[arg-type]
    return v if math.isfinite(v) else None


def _seat(code: object, side: object) -> Seat:
    c = int(code)  # type: ignore[call-overload]
    return SEAT_CODES[c] if c in SEAT_CODES else REAR_SEATS[str(side)]


def _body(stature: float | None, mass: float | None, sex: Sex | None) -> Body:
    body = nearest_body(stature, mass)
    if body is not None:
        return body
    return Body.FEMALE_5TH if sex is Sex.FEMALE else Body.MALE_50TH


def load_occupant_rows(path: Path | None = None) -> tuple[OccupantRow, ...]:
    """The usable occupants of the file, in file order.

    Parameters
    ----------
    path : Path, optional
        Default :data:`OCCUPANTS_CSV`.

    Returns
    -------
    tuple of OccupantRow
    """
    frame = load_occupant_frame(path)
    pdof = _pdof(frame)
    keep = usable_mask(frame)
    sub = frame[keep]
    out = []
    for i, rec in zip(sub.index, sub.itertuples(index=False), strict=True):
        female = _opt(rec.female)
        sex = None if female is None else (Sex.FEMALE if female == 1.0 else Sex.MALE)
        stature, mass = _opt(rec.stature_cm), _opt(rec.mass_kg)
        bag = _FRONTAL_AIRBAG.get(str(rec.frontal_airbag))
        quarter_turns = _opt(rec.rollover_quarter_turns)
        out.append(
            OccupantRow(
                year=int(rec.year),
                psu=int(rec.psu),
                caseno=int(rec.caseno),
                vehno=int(rec.vehno),
                occno=int(rec.occno),
                seat=_seat(rec.seat_code, rec.seat_side),
                body=_body(stature, mass, sex),
                belted=rec.belt == "belted",
                frontal_airbag=AirbagState.NOT_DEPLOYED if bag is None else bag,
                frontal_airbag_known=bag is not None,
                age_years=float(rec.age_years),
                sex=sex,
                stature_cm=stature,
                mass_kg=mass,
                delta_v_kmh=float(rec.delta_v_kmh),
                pdof_deg=float(pdof[i]) % 360.0,
                multiple_impacts=int(rec.n_events) > 1,
                rollover=quarter_turns is not None and quarter_turns > 0,
            )
        )
    return tuple(out)


def occupant_notification(
    row: OccupantRow, *, side_airbag: AirbagState | None = None
) -> CrashNotification:
    """The one-occupant notification a call center would have sent for the row.

    Parameters
    ----------
    row : OccupantRow
    side_airbag : AirbagState, optional
        The occupant's side airbag state to report; None (the file does not
        say) leaves it unreported.

    Returns
    -------
    CrashNotification
        Summary pulse (delta-V and PDOF), posture and seat position not sensed.
    """
    occupant = Occupant(
        seat=row.seat,
        body=row.body,
        belted=row.belted,
        frontal_airbag=row.frontal_airbag,
        side_airbag=side_airbag,
        age_years=row.age_years,
        sex=row.sex,
        posture_sensed=False,
        seat_track_source=SeatTrackSource.NOT_SENSED,
        stature_cm=row.stature_cm,
        mass_kg=row.mass_kg,
    )
    return CrashNotification(
        event_id=occupant_key(row.key),
        vehicle_model="compact_sedan",
        drive_side=DriveSide.LEFT,
        pulse=SummaryPulse(delta_v_kmh=row.delta_v_kmh, pdof_deg=row.pdof_deg),
        multiple_impacts=row.multiple_impacts,
        rollover=row.rollover,
        occupants=(occupant,),
    )


def outcome_frame(path: Path | None = None) -> pd.DataFrame:
    """The usable occupants' keys, survey design and outcomes (region AIS, ISS, death).

    Returns
    -------
    DataFrame
        Columns :data:`KEY_COLUMNS`, ``stratum``, ``ratwgt``, ``female``, ``iss``, ``mais``,
        ``died``, ``ejection``, ``model_year`` and ``max_ais_<region>``.
    """
    frame = load_occupant_frame(path)
    cols = [
        *KEY_COLUMNS,
        "stratum",
        "ratwgt",
        "female",
        "iss",
        "mais",
        "died",
        "ejection",
        "model_year",
        *(f"max_ais_{r}" for r in AIS_REGIONS),
    ]
    out = frame.loc[usable_mask(frame), cols].reset_index(drop=True)
    for c in KEY_COLUMNS:
        out[c] = out[c].astype(np.int64)
    return out
