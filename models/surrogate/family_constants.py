"""Sensor samples and interval constants shared by a family and its pieces."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Final

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray
from models.constants import Z_95

#: z of a two-sided 95% Gaussian interval.
_Z95: Final[float] = Z_95


#: Default posture sensor standard deviation, deg: error within 5 deg 95% of the
#: time, Gaussian (reference paper section 2.5).
DEFAULT_POSTURE_SD_DEG: Final[float] = 5.0 / _Z95


#: Default seat track sensor standard deviation, mm: within 5 cm 95% of the time.
DEFAULT_SEAT_TRACK_SD_MM: Final[float] = 50.0 / _Z95


#: Size of the fixed sensor sample set (a 2-D Fibonacci lattice). [R] Chosen
#: for the 5 ms budget per occupant (benchmarks/bench_surrogate.py); the
#: coverage checks compare with LPM runs at the same points.
N_SENSOR_SAMPLES: Final[int] = 96


#: Percentiles of a 95% interval.
_PCT: Final[tuple[float, float]] = (2.5, 97.5)


#: Floor of the bootstrap standard deviation of logit P(ISS >= 15) in the held-out
#: calibration (logit units): where every replicate agrees (saturated P, the
#: smallest delta-V) a residual is measured against this instead of zero. [R]
_P_SD_FLOOR: Final[float] = 0.01


#: Fewest held-out points for the calibration (a 95 % quantile of fewer is the
#: sample maximum or worse); fewer: no widening. [R]
_MIN_CALIBRATION_POINTS: Final[int] = 20


#: Floor of the bootstrap standard deviation of a measure (fitted scale log(x +
#: floor): 0.01 is 1 % of the value) and of ISS (points) in the interval
#: calibration: where every replicate agrees a residual is measured against
#: this instead of zero. [R] as :data:`_P_SD_FLOOR`.
_FITTED_SD_FLOOR: Final[Mapping[str, float]] = MappingProxyType({"iss": 0.1})


_FITTED_SD_FLOOR_MEASURE: Final[float] = 0.01


def _sd_floor(name: str) -> float:
    """Floor of the replicates' standard deviation of output `name` (fitted scale)."""
    return _FITTED_SD_FLOOR.get(name, _FITTED_SD_FLOOR_MEASURE)


def _bootstrap_sd(replicates: FloatArray, name: str) -> FloatArray:
    """Standard deviation over the last axis (the replicates), floored for `name`."""
    return np.maximum(np.std(replicates, axis=-1, ddof=1), _sd_floor(name))


def _sensor_normals(n: int) -> FloatArray:
    """Deterministic standard-normal pairs: Fibonacci lattice + Box-Muller, shape (n, 2)."""
    i = np.arange(n, dtype=np.float64)
    u1 = (i + 0.5) / n
    u2 = np.mod(i * (math.sqrt(5.0) - 1.0) / 2.0 + 0.5 / n, 1.0)
    r = np.sqrt(-2.0 * np.log(u1))
    return np.stack([r * np.cos(2.0 * np.pi * u2), r * np.sin(2.0 * np.pi * u2)], axis=1)


_NORMALS: Final[FloatArray] = _sensor_normals(N_SENSOR_SAMPLES)


#: Sensor samples at which the bootstrap replicates' P(ISS >= 15) is computed:
#: every 4th point of the lattice (24; still a lattice over both inputs). [R]
#: P comes from the measures through the risk curves, about 0.35 us per sample
#: and replicate on the benchmark machine; all 96 x 150 cost 5 ms, past the
#: 5 ms budget of the whole evaluation. The replicate spread is measured as the
#: deviation of each replicate from the point PCEs on the same subset, so the
#: subset's quadrature error, common to both, cancels; the point value uses
#: every sample.
_P_SUBSET: Final[npt.NDArray[np.intp]] = np.arange(0, N_SENSOR_SAMPLES, 4)


@dataclass(frozen=True)
class UncertaintyResult:
    """Surrogate answer for one occupant with 95% intervals.

    Attributes
    ----------
    p_iss15 : float
        P(ISS >= 15) averaged over the sensor errors.
    p_iss15_ci95 : (float, float)
        95% interval of that probability: the bootstrap interval widened by the
        family's held-out calibration factor (:attr:`p_interval_inflation`).
    iss : float
        ISS of the point PCE at the readings (continuous surrogate of an integer score).
    iss_ci95 : (float, float)
    measures : Mapping[str, float]
        Each measure the mode computes at the readings (units in the names;
        HIC15 and Nij dimensionless).
    measures_ci95 : Mapping[str, (float, float)]
        95% interval of each measure: sensor and bootstrap percentiles extended
        by the held-out calibrated margin (:attr:`SurrogateFamily.interval_factors`).
    n_samples : int
        Sensor samples per replicate.
    n_bootstrap : int
        Bootstrap replicates used.
    clamped_inputs : tuple of str
        Inputs that were outside the design range and clamped to it
        (delta-V above 120 km/h: the result is a lower bound).
    """

    p_iss15: float
    p_iss15_ci95: tuple[float, float]
    iss: float
    iss_ci95: tuple[float, float]
    measures: Mapping[str, float]
    measures_ci95: Mapping[str, tuple[float, float]]
    n_samples: int
    n_bootstrap: int
    clamped_inputs: tuple[str, ...] = field(default=())
    #: factor (>= 1) by which the bootstrap interval of P(ISS >= 15) was widened on
    #: the logit scale for the surrogate's own error (:attr:`SurrogateFamily.p_interval_inflation`)
    p_interval_inflation: float = 1.0


#: Columns of the sensor inputs in INPUT_NAMES.
_POSTURE, _SEAT = 2, 3

_NORMALS.flags.writeable = False
_P_SUBSET.flags.writeable = False
