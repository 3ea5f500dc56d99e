"""Helpers of the occupant LPM tests."""

from __future__ import annotations

from models.notification import AirbagState, Body, Occupant, Seat


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
