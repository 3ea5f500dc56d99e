"""Impact mode of each occupant from the principal direction of force.

The occupant models cover the ranges of the reference paper
(occupant-injury-framework-paper.txt, section 2.3): frontal
340-30 deg, rear 140-210 deg, near side 80-110 deg toward the occupant's side
(250-280 deg for an occupant on the left), far side the mirror of near side.
PDOF is in degrees clockwise from straight ahead (0 frontal, 90 right side,
180 rear, 270 left side). Between the ranges no occupant model applies and the
triage falls back to the statistical baseline; the nearest mode is still
reported so that cases can be filtered by mode. Second-row occupants get their
mode (the rear middle one sees a side impact as far side) but no occupant model.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

from models.notification import DriveSide, Seat

__all__ = [
    "COVERAGE_DEG",
    "FRONTAL_HALF_ANGLE_DEG",
    "ImpactClassification",
    "ImpactMode",
    "classify_impact",
    "occupant_side",
]


class ImpactMode(StrEnum):
    """The four occupant models of the reference paper."""

    FRONTAL = "frontal"
    REAR = "rear"
    NEAR_SIDE = "near_side"
    FAR_SIDE = "far_side"


#: Coverage of each mode as (start, end) deg clockwise, for an occupant seated
#: on the right of the vehicle; the side ranges swap for an occupant on the
#: left. Source: the reference paper's LPM coverage.
COVERAGE_DEG: dict[ImpactMode, tuple[float, float]] = {
    ImpactMode.FRONTAL: (340.0, 30.0),
    ImpactMode.NEAR_SIDE: (80.0, 110.0),
    ImpactMode.REAR: (140.0, 210.0),
    ImpactMode.FAR_SIDE: (250.0, 280.0),
}

#: Half-angle of the "frontal" category of the NASS-CDS variable used by the
#: statistical baseline, deg. [R] NASS general area of damage "front" spans
#: roughly 10 to 2 o'clock; the data set does not state the rule.
FRONTAL_HALF_ANGLE_DEG = 45.0

#: Axis of each mode (deg clockwise) for an occupant on the right.
_AXIS_RIGHT: dict[ImpactMode, float] = {
    ImpactMode.FRONTAL: 0.0,
    ImpactMode.NEAR_SIDE: 90.0,
    ImpactMode.REAR: 180.0,
    ImpactMode.FAR_SIDE: 270.0,
}


@dataclass(frozen=True)
class ImpactClassification:
    """Which occupant model applies to an occupant.

    Attributes
    ----------
    mode : ImpactMode
        The mode whose axis is nearest the PDOF (reported even out of coverage).
    in_lpm_coverage : bool
        True when the PDOF lies inside that mode's coverage range and the
        occupant sits in the front row (the occupant models are of the front row).
    pdof_deg : float
        PDOF normalised to [0, 360), deg.
    axis_deg : float
        The mode's axis for this occupant, deg clockwise.
    angle_from_axis_deg : float
        Signed PDOF - axis in (-180, 180], deg: the obliquity the model sees.
    frontal_nass : bool
        The baseline's NASS-CDS "frontal" flag (|PDOF| <= 45 deg).
    """

    mode: ImpactMode
    in_lpm_coverage: bool
    pdof_deg: float
    axis_deg: float
    angle_from_axis_deg: float
    frontal_nass: bool


def occupant_side(seat: Seat, drive_side: DriveSide) -> DriveSide | None:
    """Side of the vehicle the occupant sits on (the driver sits on `drive_side`).

    None for a middle seat (front, second or third row), on neither side.
    """
    if seat is Seat.DRIVER:
        return drive_side
    if seat is Seat.FRONT_PASSENGER:
        return DriveSide.RIGHT if drive_side is DriveSide.LEFT else DriveSide.LEFT
    if seat.middle:
        return None
    return DriveSide.LEFT if seat in (Seat.REAR_LEFT, Seat.THIRD_ROW_LEFT) else DriveSide.RIGHT


def _signed_difference(a_deg: float, b_deg: float) -> float:
    """a - b wrapped to (-180, 180], deg."""
    d = (a_deg - b_deg) % 360.0
    return d - 360.0 if d > 180.0 else d


def _in_range(pdof: float, start: float, end: float) -> bool:
    """Whether `pdof` lies on the clockwise arc from `start` to `end` (inclusive)."""
    return (pdof - start) % 360.0 <= (end - start) % 360.0


def classify_impact(pdof_deg: float, seat: Seat, drive_side: DriveSide) -> ImpactClassification:
    """Classify the impact for one occupant.

    Parameters
    ----------
    pdof_deg : float
        Principal direction of force, deg clockwise from straight ahead.
    seat : Seat
    drive_side : DriveSide
        Left-hand drive puts the driver on the left.

    Returns
    -------
    ImpactClassification
    """
    pdof = float(pdof_deg) % 360.0
    side = occupant_side(seat, drive_side)
    # the rear middle occupant is away from both doors: a side impact is a far-side
    # impact for them (taken as sitting opposite the struck side)
    on_left = side is DriveSide.LEFT if side is not None else pdof < 180.0
    best: tuple[float, ImpactMode, float, bool] | None = None
    for mode, (start, end) in COVERAGE_DEG.items():
        axis = _AXIS_RIGHT[mode]
        if on_left and mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE):
            # Mirror the side ranges about the x axis for an occupant on the left.
            start, end, axis = (360.0 - end) % 360.0, (360.0 - start) % 360.0, (360.0 - axis)
        covered = _in_range(pdof, start, end)
        distance = abs(_signed_difference(pdof, axis))
        key = (0.0 if covered else 1.0, mode, distance, covered)
        if best is None or (key[0], key[2]) < (best[0], best[2]):
            best = key
    assert best is not None
    _, mode, _, covered = best
    axis = _AXIS_RIGHT[mode]
    if on_left and mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE):
        axis = 360.0 - axis
    return ImpactClassification(
        mode=mode,
        # the occupant models are of the front row
        in_lpm_coverage=covered and seat.front_row,
        pdof_deg=pdof,
        axis_deg=axis % 360.0,
        angle_from_axis_deg=_signed_difference(pdof, axis),
        frontal_nass=abs(_signed_difference(pdof, 0.0)) <= FRONTAL_HALF_ANGLE_DEG,
    )
