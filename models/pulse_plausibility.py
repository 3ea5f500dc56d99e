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

A measured acceleration record is also checked as it came in, before the CFC 60
filter (:func:`nonphysical_acceleration`): the filter removes what lies above the
crash-pulse band, so content that is not a vehicle's motion at all (a channel that
changes sign at every sample, or energy far above the band) would otherwise leave
only the filter's edge ringing, read as a minor crash. Such a record looks corrupt;
it is not refused (it may be a real crash badly recorded) but decided conservatively
(``models.triage``: every occupant flagged, ``pulse_looks_corrupt``).
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
    "MAX_OUT_OF_BAND_ENERGY_RATIO",
    "MAX_SIGN_FLIP_SHARE",
    "SIGN_FLIP_FLOOR_SHARE",
    "check_implied_acceleration",
    "count_reversals",
    "nonphysical_acceleration",
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

#: Most energy (sum of squared samples, both channels) the CFC 60 filter may remove
#: from a measured acceleration record, as a multiple of the energy it keeps. [R] A
#: vehicle accelerometer rings above the crash-pulse band (its structure's modes, the
#: band of CFC 600), with energy of the order of the pulse's; 25 (an RMS 5 times the
#: pulse's) is far beyond that, and far below a record of noise or of alternating
#: samples (about 40 and 70 for 100 ms at 10 kHz).
MAX_OUT_OF_BAND_ENERGY_RATIO: Final[float] = 25.0

#: Most share of a channel's sample-to-sample steps that may change sign between two
#: samples both beyond :data:`SIGN_FLIP_FLOOR_SHARE` of the channel's largest
#: magnitude. [R] A sign change at every sample is content at the Nyquist frequency,
#: which a data channel's anti-aliasing filter (SAE J211-1) removes; zero-mean white
#: noise changes sign at about 3 steps in 10 by this count, a crash pulse far less.
MAX_SIGN_FLIP_SHARE: Final[float] = 0.5

#: Samples nearer zero than this share of the channel's largest magnitude do not count
#: for :data:`MAX_SIGN_FLIP_SHARE` (the quiet parts of a record dither about zero). [R]
SIGN_FLIP_FLOOR_SHARE: Final[float] = 0.1


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


def nonphysical_acceleration(
    raw_g: FloatArray, filtered_g: FloatArray, names: tuple[str, str], rate_hz: float
) -> str | None:
    """Why a measured acceleration record looks corrupt, or None when it does not.

    Parameters
    ----------
    raw_g : ndarray, shape (2, n)
        The record's channels as sent, g.
    filtered_g : ndarray, shape (2, n)
        The same channels after the CFC 60 filter, g.
    names : (str, str)
        The channels' field names (``longitudinal_g``, ``lateral_g``).
    rate_hz : float
        Their sampling rate, Hz.

    Returns
    -------
    str or None
        The reason, naming the field: a channel changing sign at more than
        :data:`MAX_SIGN_FLIP_SHARE` of its steps, or more than
        :data:`MAX_OUT_OF_BAND_ENERGY_RATIO` times the energy above the band than in it.
    """
    raw = np.asarray(raw_g, dtype=np.float64)
    for name, x in zip(names, raw, strict=True):
        if x.size < 2:
            continue
        floor = SIGN_FLIP_FLOOR_SHARE * float(np.max(np.abs(x)))
        beyond = np.abs(x) > floor
        flips = int(np.count_nonzero((x[1:] * x[:-1] < 0.0) & beyond[1:] & beyond[:-1]))
        share = flips / (x.size - 1)
        if share > MAX_SIGN_FLIP_SHARE:
            return (
                f"`{name}` changes sign at {share:.0%} of its samples (at {rate_hz:g} Hz): "
                "a vehicle's motion does not"
            )
    kept = float(np.sum(np.square(filtered_g)))
    removed = float(np.sum(np.square(raw - filtered_g)))
    if removed > MAX_OUT_OF_BAND_ENERGY_RATIO * kept:
        ratio = "without bound" if kept == 0.0 else f"{removed / kept:.3g} times"
        return (
            f"`{names[0]}`/`{names[1]}` hold {ratio} more energy above the CFC 60 band than "
            "in it: not a crash pulse"
        )
    return None


def warm_up() -> None:
    """Compile (or load from the numba cache) the turn counter."""
    _reversals(np.zeros(3), 1.0)
