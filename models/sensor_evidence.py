"""Posture and seat position from what the notification knows, as a reading and an SD.

The occupant models and their surrogates take a posture (lumbar flexion) and a
seat track position with Gaussian sensor errors (reference paper section 2.5;
service default 5 deg and 5 cm at 95 %). Many notifications carry no such
reading: a car without a seat position sensor may still report its seat
track position switch (49 CFR 563 Table II "seat track position switch,
foremost, status"), and few cars sense posture at all. An absent reading is
not a reading at the nominal position with a sensor's error: the position is
anywhere the evidence allows. :func:`resolve_sensor_evidence` turns the
evidence into the range it allows, then into a reading and the standard
deviation of a uniform distribution over that range (width / sqrt(12)), which
the engine propagates like a sensor error; the reading is the range's centre
for the seat track and the neutral posture (``NEUTRAL_LUMBAR_FLEXION_DEG``,
5.8 deg, not the 12.5 deg centre of 0-25 deg) for an unsensed posture. An
explicit SD in the notification is kept. Each replacement is reported as an
assumption.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Final

from models.assumptions import Assumption, AssumptionCode
from models.lpm.domain import POSTURE_RANGE_DEG, SEAT_TRACK_RANGE_MM
from models.notification import NEUTRAL_LUMBAR_FLEXION_DEG, Occupant, SeatTrackSource

__all__ = [
    "FOREMOST_SWITCH_POINT_MM",
    "UNSENSED_POSTURE_SD_DEG",
    "seat_track_range_mm",
    "resolve_sensor_evidence",
    "uniform_sd",
]

#: Seat track position (mm forward of mid track) at which the seat track
#: position switch changes state. [R] The switch is vehicle-specific and its
#: point is not published; its purpose is to tell a seat "too close to the
#: airbag" (TRW seat track position sensor product page; Ford and Mazda service
#: descriptions: "front and back positions", "programmed limits"). Taken at the
#: start of the forward third of the default set's +-120 mm track, between the
#: 50th male's mid-track and the 5th female's full-forward seating (FMVSS 208).
FOREMOST_SWITCH_POINT_MM: Final[float] = 40.0


def uniform_sd(low: float, high: float) -> float:
    """Standard deviation of a uniform distribution on [low, high] (in their unit)."""
    return (high - low) / math.sqrt(12.0)


#: Posture SD when no posture is sensed, deg: the spread of a posture anywhere in
#: the occupant models' lumbar-flexion range (models.lpm.domain.POSTURE_RANGE_DEG,
#: 0-25 deg: 7.2 deg), about the neutral posture.
UNSENSED_POSTURE_SD_DEG: Final[float] = uniform_sd(*POSTURE_RANGE_DEG)


def seat_track_range_mm(source: SeatTrackSource) -> tuple[float, float]:
    """Fore-aft range (mm forward of mid track) that the seat position evidence allows.

    Raises
    ------
    ValueError
        For ``SENSOR`` (a reading is a point with a sensor error, not a range).
    """
    lo, hi = SEAT_TRACK_RANGE_MM
    if source is SeatTrackSource.FOREMOST_SWITCH_ON:
        return (FOREMOST_SWITCH_POINT_MM, hi)
    if source is SeatTrackSource.FOREMOST_SWITCH_OFF:
        return (lo, FOREMOST_SWITCH_POINT_MM)
    if source is SeatTrackSource.NOT_SENSED:
        return (lo, hi)
    raise ValueError(f"seat track source {source.value!r} is a reading, not a range")


def resolve_sensor_evidence(
    occupant: Occupant, index: int, assumptions: list[Assumption]
) -> Occupant:
    """The occupant with a posture and seat track reading and SD for every kind of evidence.

    Parameters
    ----------
    occupant : Occupant
    index : int
        The occupant's index in the notification (for the assumption text).
    assumptions : list of Assumption
        Appended with one line per replaced reading.

    Returns
    -------
    Occupant
        ``posture_sensed`` True and ``seat_track_source`` SENSOR; unchanged
        when both were already so.
    """
    out = occupant
    if not occupant.posture_sensed:
        sd = occupant.posture_sd_deg or UNSENSED_POSTURE_SD_DEG
        out = dataclasses.replace(
            out,
            posture_lumbar_flexion_deg=NEUTRAL_LUMBAR_FLEXION_DEG,
            posture_sd_deg=sd,
            posture_sensed=True,
        )
        spread = (
            "as given"
            if occupant.posture_sd_deg
            else f"anywhere in {POSTURE_RANGE_DEG[0]:g}-{POSTURE_RANGE_DEG[1]:g} deg"
        )
        assumptions.append(
            Assumption(
                AssumptionCode.POSTURE_NOT_SENSED,
                f"occupants[{index}]: posture not sensed: neutral lumbar flexion "
                f"{NEUTRAL_LUMBAR_FLEXION_DEG:g} deg with SD {sd:.1f} deg in the intervals "
                f"({spread})",
                index,
            )
        )
    if occupant.seat_track_source is not SeatTrackSource.SENSOR:
        lo, hi = seat_track_range_mm(occupant.seat_track_source)
        sd = occupant.seat_track_sd_mm or uniform_sd(lo, hi)
        centre = 0.5 * (lo + hi)
        out = dataclasses.replace(
            out,
            seat_track_mm=centre,
            seat_track_sd_mm=sd,
            seat_track_source=SeatTrackSource.SENSOR,
        )
        why = {
            SeatTrackSource.FOREMOST_SWITCH_ON: "seat track switch says foremost",
            SeatTrackSource.FOREMOST_SWITCH_OFF: "seat track switch says not foremost",
            SeatTrackSource.NOT_SENSED: "seat position not sensed",
        }[occupant.seat_track_source]
        assumptions.append(
            Assumption(
                AssumptionCode.SEAT_POSITION_NOT_SENSED
                if occupant.seat_track_source is SeatTrackSource.NOT_SENSED
                else AssumptionCode.SEAT_TRACK_SWITCH,
                f"occupants[{index}]: {why}: seat track anywhere in {lo:g} to {hi:g} mm "
                f"(mid track 0, + forward): {centre:g} mm with SD {sd:.0f} mm in the intervals"
                + (" (SD as given)" if occupant.seat_track_sd_mm else ""),
                index,
            )
        )
    return out
