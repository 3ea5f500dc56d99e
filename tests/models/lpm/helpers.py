"""Helpers of the occupant LPM tests."""

from __future__ import annotations

from models.lpm.params import ParameterSet
from models.notification import AirbagState, Body, Occupant, Seat

#: Largest load an occupant segment of these models develops against a contact
#: in the checked cases, N: the travel it produces in the bottoming spring is
#: the margin allowed beyond a contact's give (40 mm at 1e6 N/m).
BOTTOMING_MARGIN_N = 40e3


def bottoming_margin_m(params: ParameterSet) -> float:
    """Travel of :data:`BOTTOMING_MARGIN_N` into the bottoming spring, m."""
    return BOTTOMING_MARGIN_N / params["seat.bottoming_stiffness"]


def occupant(
    body: Body = Body.MALE_50TH,
    *,
    belted: bool = True,
    airbag: bool = True,
    lean_deg: float = 5.8,
    track_mm: float = 0.0,
    age: float | None = 35.0,
    fire_ms: float | None = None,
    pretensioner: bool | None = None,
) -> Occupant:
    """A driver with the given restraints and posture."""
    return Occupant(
        seat=Seat.DRIVER,
        body=body,
        belted=belted,
        frontal_airbag=AirbagState.DEPLOYED if airbag else AirbagState.ABSENT,
        age_years=age,
        airbag_fire_time_ms=fire_ms,
        pretensioner_fired=pretensioner,
        posture_lumbar_flexion_deg=lean_deg,
        seat_track_mm=track_mm,
    )
