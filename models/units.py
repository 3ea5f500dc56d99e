"""Unit conversions, each explicit and named (units live in names: ``delta_v_kmh``).

Every conversion between unit systems in the engine and the offline tools goes
through a function here, so that a number never changes unit silently.
"""

from __future__ import annotations

from typing import Final

__all__ = ["KM_PER_MILE", "kmh_to_mph", "mph_to_kmh"]

#: Kilometres per international mile, exact by definition (international yard
#: and pound agreement, 1959: 1 mile = 1,609.344 m).
KM_PER_MILE: Final[float] = 1.609344


def mph_to_kmh(speed_mph: float) -> float:
    """Miles per hour to kilometres per hour (``x 1.609344``, exact by definition)."""
    return float(speed_mph) * KM_PER_MILE


def kmh_to_mph(speed_kmh: float) -> float:
    """Kilometres per hour to miles per hour (``/ 1.609344``, exact by definition)."""
    return float(speed_kmh) / KM_PER_MILE
