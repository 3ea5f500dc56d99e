"""The input domain the occupant models (and their surrogates) are built for.

Sensor readings outside it are clamped by the orchestrator, which says so in
the result's assumptions.
"""

from __future__ import annotations

__all__ = ["POSTURE_RANGE_DEG", "SEAT_TRACK_RANGE_MM", "clamp"]

#: Lumbar flexion the models cover, deg: neutral 5.8, forward leaning up to 25
#: (reference paper section 2.4). Reclined postures below 0 are not modelled.
POSTURE_RANGE_DEG = (0.0, 25.0)
#: Seat track travel the models cover relative to mid track, mm. [R] Compact-car
#: front seats travel about 240 mm fore-aft (occupant-lpm-notes.md section 2).
SEAT_TRACK_RANGE_MM = (-120.0, 120.0)


def clamp(value: float, bounds: tuple[float, float]) -> float:
    """`value` limited to the closed interval `bounds`."""
    lo, hi = bounds
    return min(max(value, lo), hi)
