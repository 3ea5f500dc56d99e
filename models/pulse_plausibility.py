"""Is a measured pulse a crash pulse? The one rule for records that are not physical.

A measured pulse (an acceleration history or a 49 CFR 563 delta-V record) is
refused with a :class:`~models.pulse.PulseError` naming the field when either

* **implied acceleration**: a delta-V record changes faster than the largest
  acceleration the service accepts as input, :data:`models.limits.MAX_ABS_ACCELERATION_G`
  (``|v[k+1] - v[k]| / interval``, resultant of both axes), or
* **oscillation**: an axis of the cumulative delta-V turns back more than
  :data:`MAX_DELTA_V_REVERSALS` times by more than the noise band
  (:func:`reversal_band_kmh`): a crash decelerates the vehicle, may rebound,
  and a second impact in the same record may do it once more; a delta-V that
  swings back and forth is a corrupted or mis-decoded record, whose delta-V
  means nothing.

There is no "answer it anyway" branch: a record refused here is a 422, so the
decision never reads a violent record as a minor crash. What remains (within
the limits) is decided on the record's *maximum* delta-V (``models.pulse``).
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numba import njit

from models.arrays import FloatArray
from models.constants import G_MS2
from models.limits import MAX_ABS_ACCELERATION_G

__all__ = [
    "EDR_DELTA_V_ACCURACY",
    "EDR_DELTA_V_RESOLUTION_KMH",
    "MAX_DELTA_V_REVERSALS",
    "check_implied_acceleration",
    "count_reversals",
    "reversal_band_kmh",
    "warm_up",
]

#: 49 CFR 563 Table III: delta-V resolution, km/h [V] (``crash-data-and-triage.md`` 2.5).
EDR_DELTA_V_RESOLUTION_KMH: Final[float] = 1.0

#: 49 CFR 563 Table III: delta-V accuracy, +/-10 % [V].
EDR_DELTA_V_ACCURACY: Final[float] = 0.10

#: Most turns of one axis of the cumulative delta-V beyond the noise band.
#: [R] One impact: the delta-V grows, then may rebound (one turn); a second
#: impact within the record may add a growth and a rebound (three turns). More
#: is not the rigid-body motion of a car.
MAX_DELTA_V_REVERSALS: Final[int] = 3

#: km/h per (m/s): exact.
_KMH_PER_MPS: Final[float] = 3.6


def reversal_band_kmh(max_delta_v_kmh: float) -> float:
    """Noise band of a turn of the delta-V, km/h.

    Two resolution steps (a sample and its neighbour each off by one step), or the
    563 accuracy of the record's maximum delta-V, whichever is larger.

    Parameters
    ----------
    max_delta_v_kmh : float
        Largest resultant delta-V of the record, km/h.

    Returns
    -------
    float
        A turn counts when the delta-V comes back by more than this, km/h.
    """
    return max(2.0 * EDR_DELTA_V_RESOLUTION_KMH, EDR_DELTA_V_ACCURACY * max_delta_v_kmh)


@njit(cache=True, nogil=True)
def _reversals(v: FloatArray, band: float) -> tuple[int, int]:
    """Turns of `v` by more than `band` (hysteresis), and the index of the first."""
    direction = 0
    hi = v[0]
    lo = v[0]
    extreme = v[0]
    count = 0
    first = -1
    for i in range(1, v.shape[0]):
        x = v[i]
        if direction == 0:
            hi = max(hi, x)
            lo = min(lo, x)
            if hi - lo > band:
                direction = 1 if x == hi else -1
                extreme = x
        elif direction > 0:
            if x > extreme:
                extreme = x
            elif extreme - x > band:
                count += 1
                first = i if first < 0 else first
                direction = -1
                extreme = x
        else:
            if x < extreme:
                extreme = x
            elif x - extreme > band:
                count += 1
                first = i if first < 0 else first
                direction = 1
                extreme = x
    return count, first


def count_reversals(delta_v_kmh: FloatArray, band_kmh: float) -> tuple[int, int]:
    """How often one axis of a cumulative delta-V turns back by more than a band.

    Parameters
    ----------
    delta_v_kmh : ndarray, shape (n,)
        Cumulative delta-V of one axis, km/h.
    band_kmh : float
        Hysteresis, km/h: a move counts only once it exceeds this, and a turn only
        once the delta-V has come back by more than this from its extreme.

    Returns
    -------
    count : int
        Number of turns.
    first : int
        Index of the sample at which the first turn is recognised; -1 if none.
    """
    v = np.ascontiguousarray(delta_v_kmh, dtype=np.float64)
    count, first = _reversals(v, float(band_kmh))
    return int(count), int(first)


def check_implied_acceleration(
    vx_kmh: FloatArray, vy_kmh: FloatArray, interval_s: float
) -> tuple[str, int, float] | None:
    """The first interval of a delta-V record that implies more than the accepted acceleration.

    Parameters
    ----------
    vx_kmh, vy_kmh : ndarray, shape (n,)
        The record's longitudinal and lateral cumulative delta-V, km/h.
    interval_s : float
        Sampling interval, s.

    Returns
    -------
    tuple of (str, int, float) or None
        The field with the larger change (``longitudinal_kmh`` or ``lateral_kmh``),
        the index of the sample ending the interval, and the implied resultant
        acceleration in g; None when every interval is within
        :data:`~models.limits.MAX_ABS_ACCELERATION_G`.
    """
    dx, dy = np.diff(vx_kmh), np.diff(vy_kmh)
    accel_g = np.hypot(dx, dy) / (_KMH_PER_MPS * G_MS2 * interval_s)
    over = np.flatnonzero(accel_g > MAX_ABS_ACCELERATION_G)
    if over.size == 0:
        return None
    k = int(over[0])
    name = "longitudinal_kmh" if abs(dx[k]) >= abs(dy[k]) else "lateral_kmh"
    return name, k + 1, float(accel_g[k])


def warm_up() -> None:
    """Compile (or load from the numba cache) the turn counter."""
    _reversals(np.zeros(3), 1.0)
