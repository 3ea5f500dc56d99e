"""Crash pulse processing: from any pulse kind to one uniform description.

Every pulse kind of the notification (:class:`~models.notification.AccelerationPulse`,
:class:`~models.notification.DeltaVPulse`, :class:`~models.notification.SummaryPulse`)
is turned into a :class:`ProcessedPulse`: acceleration histories on a uniform
time grid, the delta-V vector and its magnitude, the principal direction of
force (PDOF), the peak resultant acceleration, the pulse duration and a
haversine fit ``a(t) = A sin^2(pi t / T)`` (``0 <= t <= T``; 0 after ``T``).

Conventions (``crash-data-and-triage.md`` section 3)
----------------------------------------------------
* Axes: SAE J211 vehicle axes, x forward, y right. A frontal crash decelerates
  the vehicle (``longitudinal_g < 0``); an impact on the right side pushes it to
  the left (``lateral_g < 0``).
* PDOF: degrees clockwise from straight ahead, the direction the force comes
  *from*: 0 frontal, 90 right side, 180 rear, 270 left side. It is the
  direction opposite to the delta-V vector,
  ``pdof = atan2(-dv_y, -dv_x)`` in degrees, wrapped to ``[0, 360)``.
* Time: the record starts at the first sample (``time_s[0] == 0``), which is
  taken as the start of the pulse (the 49 CFR 563 records start at time zero;
  senders of measured accelerations must cut pre-trigger samples).

Duration rule
-------------
The pulse ends at the 49 CFR 563.5 *end of event*: the first moment after
time zero at which the resultant cumulative delta-V over the preceding 20 ms
is 0.8 km/h or less. Time zero is the first moment at which the resultant
cumulative delta-V over the preceding 20 ms exceeds 0.8 km/h (563.5 "time
zero"; the 5 ms lateral window of 563.5 is not used: one resultant criterion).
``duration_ms`` is the end of event measured from the start of the record; if
the record ends before the event does, the record's end. Because the criterion
looks back 20 ms, the measured duration of a haversine of length ``T`` is a few
ms longer than ``T``; the haversine fit gives ``T`` itself. A summary pulse is
a haversine by definition and its duration is its ``T``.

Delta-V is the *maximum* delta-V of 49 CFR 563: the largest resultant
cumulative delta-V over the whole record (for a pulse without rebound, the one
at the end of event; with a rebound or a second impact, the largest). Its
components and the PDOF are those of the delta-V vector at that moment.

Plausibility
------------
A measured pulse that is not physical (a delta-V record implying more than the
accepted acceleration, or a delta-V that swings back and forth beyond the noise)
is refused, naming the field: :mod:`models.pulse_plausibility` holds the rule. An
acceleration record whose raw samples are not a vehicle's motion (a sign change at
every sample, energy far above the CFC 60 band) is processed, and marked as looking
corrupt (``ProcessedPulse.nonphysical``): the triage then decides conservatively.

Processing per kind
-------------------
* ``acceleration``: each channel is filtered at CFC 60 (SAE J211-1, the class
  for vehicle crash pulses; :func:`models.injury.filters.cfc_filter`), then
  linearly interpolated onto the output grid; delta-V is its cumulative
  trapezoidal integral on that grid.
* ``delta_v`` (49 CFR 563 EDR): the record is taken as piecewise linear in time,
  so the acceleration is piecewise constant, ``(v[k+1] - v[k]) / interval`` on
  each interval, and integrates back exactly to the record at every record
  sample. Not filtered: at 100 Hz there is nothing above CFC 60 to remove.
  Delta-V comes from the record itself (``max |v(t) - v(0)|``; ``v(0)`` is 0
  in a 563 record).
* ``summary``: a haversine along the PDOF with ``A = 2 delta-V / (g T)``
  (from ``delta-V = A g T / 2``, ``occupant-lpm-notes.md`` section 3). ``T`` is the
  given ``duration_ms`` or, if absent, :data:`DEFAULT_HAVERSINE_DURATION_MS`.
  Its haversine "fit" is exact: ``(A, T, r^2 = 1)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np
import numpy.typing as npt
from numba import njit
from scipy.optimize import least_squares, leastsq

from models.arrays import FloatArray
from models.constants import G_MS2
from models.injury.filters import cfc_filter_rows
from models.limits import (
    MAX_ABS_ACCELERATION_G,
    MAX_DELTA_V_KMH,
    MAX_EDR_INTERVAL_MS,
    MAX_RECORD_DURATION_MS,
    MIN_ACCELERATION_SAMPLE_RATE_HZ,
    MIN_SAMPLES,
    PULSE_CFC,
)
from models.notification import AccelerationPulse, DeltaVPulse, Pulse, SummaryPulse
from models.pulse_plausibility import (
    MAX_DELTA_V_REVERSALS,
    check_implied_acceleration,
    count_reversals,
    nonphysical_acceleration,
    reversal_band_kmh,
)
from models.pulse_plausibility import warm_up as _warm_up_plausibility

__all__ = [
    "PulseError",
    "warm_up",
    "DEFAULT_HAVERSINE_DURATION_MS",
    "DEFAULT_OUTPUT_RATE_HZ",
    "EOE_DELTA_V_KMH",
    "EOE_WINDOW_S",
    "KMH_PER_MPS",
    "MAX_ABS_ACCELERATION_G",
    "MAX_DELTA_V_KMH",
    "MAX_EDR_INTERVAL_MS",
    "MAX_RECORD_DURATION_S",
    "MIN_ACCELERATION_SAMPLE_RATE_HZ",
    "MAX_OUTPUT_RATE_HZ",
    "MIN_OUTPUT_RATE_HZ",
    "MIN_SAMPLES",
    "PULSE_CFC",
    "STANDARD_GRAVITY",
    "HaversineFit",
    "ProcessedPulse",
    "haversine",
    "haversine_amplitude_g",
    "haversine_delta_v_kmh",
    "pdof_from_delta_v",
    "process_pulse",
]


class PulseError(ValueError):
    """A pulse the engine cannot use, with the reason naming the field.

    An input problem (the answer is a 422 naming ``crash.pulse``), unlike any
    other exception of the engine, which is a failure of the engine itself.
    """


#: Standard acceleration of gravity, m/s^2 (CGPM 1901; ISO 80000-3).
STANDARD_GRAVITY: Final[float] = G_MS2

#: km/h per m/s (exact: 3600 s/h / 1000 m/km).
KMH_PER_MPS: Final[float] = 3.6

#: 49 CFR 563.5 definitions: "time zero" and "end of event" use the resultant
#: cumulative delta-V within a 20 ms period (``crash-data-and-triage.md`` 2.5) [V].
EOE_WINDOW_S: Final[float] = 0.020

#: 49 CFR 563.5: time zero when the cumulative delta-V within 20 ms exceeds
#: 0.8 km/h; end of event when it becomes 0.8 km/h or less [V].
EOE_DELTA_V_KMH: Final[float] = 0.8

#: Default haversine duration of a summary pulse without ``duration_ms``, ms.
#: [R] The reference paper finds collision duration "not highly correlated with
#: delta-v" (occupant-injury-framework-paper.txt, section 3.1), so the rule is
#: a constant: ``occupant-lpm-notes.md`` section 3 gives haversine durations of
#: 80-100 ms for the 56 km/h NCAP barrier pulse and ~90 ms for the rear sled.
DEFAULT_HAVERSINE_DURATION_MS: Final[float] = 100.0

#: Default output sampling rate, Hz.
DEFAULT_OUTPUT_RATE_HZ: Final[float] = 10_000.0

#: Lowest output rate, Hz. [R] 1 ms steps: 20 samples per 563 window and about
#: 8 samples per period of the CFC 60 design frequency (124.65 Hz).
MIN_OUTPUT_RATE_HZ: Final[float] = 1_000.0

#: Highest output rate, Hz. [R] Guards memory: 5 s at 100 kHz is 500k samples.
MAX_OUTPUT_RATE_HZ: Final[float] = 100_000.0

#: Longest record accepted, s (:data:`models.limits.MAX_RECORD_DURATION_MS`).
MAX_RECORD_DURATION_S: Final[float] = MAX_RECORD_DURATION_MS / 1_000.0

#: Relative size of the total sum of squares below which a resultant counts as
#: constant (r^2 is then reported as 0).
_DEGENERATE_SS: Final[float] = 1e-12

#: The haversine fit's MINPACK tolerances (ftol, xtol, gtol): scipy's
#: ``least_squares`` defaults, which the fit used until 2026-12-04.
_LM_TOLERANCE: Final[float] = 1e-8
#: MINPACK's ``info`` values of a converged fit (``least_squares``' success).
_LM_SUCCESS: Final[frozenset[int]] = frozenset({1, 2, 3, 4})

#: Relative tolerance when converting times to sample counts.
_GRID_EPS: Final[float] = 1e-9


@dataclass(frozen=True)
class HaversineFit:
    """Least-squares haversine ``a(t) = A sin^2(pi t / T)`` for ``0 <= t <= T``.

    Attributes
    ----------
    amplitude_g : float
        Peak ``A``, g.
    duration_ms : float
        Duration ``T``, ms.
    r_squared : float
        Coefficient of determination of the fit to the resultant acceleration
        over ``[0, duration]`` of the processed pulse, 1 - SS_res / SS_tot
        (negative when the fit is worse than the mean; 0 for a constant
        resultant).
    """

    amplitude_g: float
    duration_ms: float
    r_squared: float


@dataclass(frozen=True, eq=False)
class ProcessedPulse:
    """A crash pulse on a uniform grid with its summary quantities.

    The arrays are read-only and left out of ``repr``. Two instances are
    equal when every scalar field is equal and every array is bit-identical
    (same shape, dtype and bytes); the hash is consistent with that.

    Attributes
    ----------
    time_s : ndarray, shape (n,)
        Time from the start of the record, s; starts at 0, uniform step
        ``1 / sample_rate_hz``.
    sample_rate_hz : float
        Sampling rate of the arrays, Hz.
    longitudinal_g : ndarray, shape (n,)
        x acceleration, g (SAE J211; a frontal crash is negative); CFC 60
        filtered when measured.
    lateral_g : ndarray, shape (n,)
        y acceleration, g (positive to the right).
    delta_v_kmh : float
        Maximum delta-V: the largest magnitude of the resultant velocity change
        over the record, km/h (49 CFR 563 "maximum delta-V").
    delta_v_longitudinal_kmh : float
        x component of the velocity change at its maximum, km/h.
    delta_v_lateral_kmh : float
        y component of the velocity change at its maximum, km/h.
    pdof_deg : float
        Principal direction of force, deg clockwise from straight ahead, in
        ``[0, 360)``: 0 frontal, 90 right, 180 rear, 270 left.
    peak_accel_g : float
        Peak resultant acceleration up to the end of event, g.
    duration_ms : float
        Time from the start of the record to the end of event, ms.
    haversine : HaversineFit
        Haversine fitted to the resultant acceleration.
    nonphysical : str or None
        Why the measured record looks corrupt (its raw samples are not a vehicle's
        motion: :func:`models.pulse_plausibility.nonphysical_acceleration`), naming
        the field; None when it does not.
    """

    time_s: FloatArray = field(repr=False)
    sample_rate_hz: float
    longitudinal_g: FloatArray = field(repr=False)
    lateral_g: FloatArray = field(repr=False)
    delta_v_kmh: float
    delta_v_longitudinal_kmh: float
    delta_v_lateral_kmh: float
    pdof_deg: float
    peak_accel_g: float
    duration_ms: float
    haversine: HaversineFit
    nonphysical: str | None = None

    def _key(self) -> tuple[object, ...]:
        arrays = tuple(
            (a.shape, a.dtype.str, a.tobytes())
            for a in (self.time_s, self.longitudinal_g, self.lateral_g)
        )
        scalars = (
            self.sample_rate_hz,
            self.delta_v_kmh,
            self.delta_v_longitudinal_kmh,
            self.delta_v_lateral_kmh,
            self.pdof_deg,
            self.peak_accel_g,
            self.duration_ms,
            self.haversine,
            self.nonphysical,
        )
        return arrays + scalars

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ProcessedPulse):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


# --------------------------------------------------------------------------- helpers


def haversine(time_s: npt.ArrayLike, amplitude_g: float, duration_s: float) -> FloatArray:
    """Haversine pulse ``A sin^2(pi t / T)`` on ``[0, T]``, zero elsewhere.

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Times, s.
    amplitude_g : float
        Peak ``A``, g.
    duration_s : float
        Duration ``T``, s; positive.

    Returns
    -------
    ndarray, shape (n,)
        Acceleration magnitude, g.
    """
    t = np.asarray(time_s, dtype=np.float64)
    inside = (t >= 0.0) & (t <= duration_s)
    out = amplitude_g * np.sin(np.pi * t / duration_s) ** 2
    return np.where(inside, out, 0.0)


def haversine_amplitude_g(delta_v_kmh: float, duration_s: float) -> float:
    """Peak of the haversine pulse of a delta-V, ``A = 2 delta-V / (g T)``, in g.

    The one home of this formula (the summary pulse, the surrogates' design runs,
    the test pulses): the operation order is fixed, so every caller gets the
    same bits.

    Parameters
    ----------
    delta_v_kmh : float
        Velocity change, km/h.
    duration_s : float
        Duration ``T``, s; positive.

    Returns
    -------
    float
        ``A``, g.
    """
    return 2.0 * (delta_v_kmh / KMH_PER_MPS) / (STANDARD_GRAVITY * duration_s)


def haversine_delta_v_kmh(amplitude_g: float, duration_s: float) -> float:
    """Delta-V of a haversine pulse, ``A g T / 2``, in km/h.

    Parameters
    ----------
    amplitude_g : float
        Peak, g.
    duration_s : float
        Duration, s.

    Returns
    -------
    float
        Velocity change, km/h (``occupant-lpm-notes.md`` section 3).
    """
    return amplitude_g * STANDARD_GRAVITY * duration_s / 2.0 * KMH_PER_MPS


def pdof_from_delta_v(delta_v_longitudinal: float, delta_v_lateral: float) -> float:
    """PDOF of a delta-V vector, deg clockwise from straight ahead in ``[0, 360)``.

    The force on the vehicle points along the delta-V vector; the PDOF is the
    direction it comes from, i.e. the opposite direction.

    Parameters
    ----------
    delta_v_longitudinal : float
        x (forward) component, any velocity unit.
    delta_v_lateral : float
        y (right) component, same unit.

    Returns
    -------
    float
        PDOF, deg: 0 frontal (dv_x < 0), 90 right (dv_y < 0), 180 rear,
        270 left.
    """
    deg = math.degrees(math.atan2(-delta_v_lateral, -delta_v_longitudinal)) % 360.0
    return 0.0 if deg >= 360.0 else deg + 0.0  # "+ 0.0" turns -0.0 into 0.0


def _number(name: str, value: object) -> float:
    """`value` as a finite float, else ValueError naming `name`."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise PulseError(f"`{name}` must be a number, got {type(value).__name__}.")
    x = float(value)
    if not math.isfinite(x):
        raise PulseError(f"`{name}` must be finite, got {x!r}.")
    return x


def _series(name: str, values: object, limit: float) -> FloatArray:
    """`values` as a finite 1-D float64 array with ``|x| <= limit``, else ValueError."""
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise PulseError(f"`{name}` must be a sequence of numbers.") from exc
    if arr.ndim != 1:
        raise PulseError(f"`{name}` must be one-dimensional, got shape {arr.shape}.")
    if arr.size < MIN_SAMPLES:
        raise PulseError(f"`{name}` is too short: {arr.size} samples, need at least {MIN_SAMPLES}.")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise PulseError(f"`{name}` must be finite; element {bad} is {arr[bad]!r}.")
    if np.any(np.abs(arr) > limit):
        bad = int(np.flatnonzero(np.abs(arr) > limit)[0])
        raise PulseError(
            f"`{name}` element {bad} is {arr[bad]:.4g}, beyond the plausible range +/-{limit:g}."
        )
    return arr


def _check_record_duration(name: str, n: int, step_s: float) -> float:
    """Record length ``(n - 1) * step_s`` in s, checked against the limits."""
    length = (n - 1) * step_s
    if length < EOE_WINDOW_S * (1.0 - _GRID_EPS):
        raise PulseError(
            f"`{name}` is too short: the record spans {length * 1e3:g} ms, need at least "
            f"{EOE_WINDOW_S * 1e3:g} ms (one 49 CFR 563 window)."
        )
    if length > MAX_RECORD_DURATION_S:
        raise PulseError(
            f"`{name}` is too long: the record spans {length:g} s, at most "
            f"{MAX_RECORD_DURATION_S:g} s is accepted."
        )
    return length


def _grid(length_s: float, rate_hz: float) -> FloatArray:
    """Uniform grid ``k / rate_hz`` covering ``[0, length_s]``, s."""
    n = int(math.floor(length_s * rate_hz * (1.0 + _GRID_EPS) + _GRID_EPS)) + 1
    return np.arange(n, dtype=np.float64) / rate_hz


def _cumulative_trapezoid(y: FloatArray, step: float) -> FloatArray:
    """Cumulative trapezoidal integral starting at 0, same length as `y`."""
    out = np.empty_like(y)
    out[0] = 0.0
    np.cumsum((y[1:] + y[:-1]) * (0.5 * step), out=out[1:])
    return out


def _end_of_event_index(dvx_kmh: FloatArray, dvy_kmh: FloatArray, rate_hz: float) -> int | None:
    """Index of the 49 CFR 563.5 end of event on a uniform grid.

    Returns None when time zero is never reached (no crash). When the event
    has not ended by the end of the record, returns the last index.
    """
    w = max(1, int(round(EOE_WINDOW_S * rate_hz)))
    idx = np.arange(dvx_kmh.size)
    back = np.maximum(idx - w, 0)
    change = np.hypot(dvx_kmh - dvx_kmh[back], dvy_kmh - dvy_kmh[back])
    started = np.flatnonzero(change > EOE_DELTA_V_KMH)
    if started.size == 0:
        return None
    t0 = int(started[0])
    ended = np.flatnonzero(change[t0:] <= EOE_DELTA_V_KMH)
    if ended.size == 0:
        return int(dvx_kmh.size - 1)
    return t0 + int(ended[0])


@njit(cache=True, nogil=True)
def _haversine_terms(pi_t: FloatArray, dur: float) -> tuple[FloatArray, FloatArray]:
    """The phase ``pi t / T`` and ``sin(phase) ** 2`` at every sample (numpy's numbers:
    the same division, the C library's sine as numpy's, the square a product)."""
    n = pi_t.shape[0]
    phase = np.empty(n)
    sin2 = np.empty(n)
    for i in range(n):
        ph = pi_t[i] / dur
        s = math.sin(ph)
        phase[i] = ph
        sin2[i] = s * s
    return phase, sin2


@njit(cache=True, nogil=True)
def _haversine_residual(
    t: FloatArray, a: FloatArray, sin2: FloatArray, amp: float, dur: float
) -> FloatArray:
    """``where(0 <= t <= T, A sin2, 0) - a``: the haversine less the data, g."""
    n = t.shape[0]
    out = np.empty(n)
    for i in range(n):
        if t[i] >= 0.0 and t[i] <= dur:
            out[i] = amp * sin2[i] - a[i]
        else:
            out[i] = 0.0 - a[i]
    return out


@njit(cache=True, nogil=True)
def _haversine_jacobian(
    t: FloatArray, phase: FloatArray, sin2: FloatArray, amp: float, dur: float
) -> FloatArray:
    """Columns ``sin2`` and ``-A phase / T sin(2 phase)`` on ``0 <= t <= T``, 0 outside,
    in the order numpy evaluates the expressions, shape (n, 2)."""
    n = t.shape[0]
    jac = np.empty((n, 2))
    neg_amp = -amp
    for i in range(n):
        if t[i] >= 0.0 and t[i] <= dur:
            jac[i, 0] = sin2[i]
            jac[i, 1] = neg_amp * phase[i] / dur * math.sin(2.0 * phase[i])
        else:
            jac[i, 0] = 0.0
            jac[i, 1] = 0.0
    return jac


def _fit_haversine(t: FloatArray, a: FloatArray, delta_v_kmh: float) -> HaversineFit:
    """Least-squares haversine fit to the resultant ``a`` (g) on times ``t`` (s)."""
    peak = float(np.max(a))
    span = float(t[-1])
    step = float(t[1] - t[0])
    if peak <= 0.0:
        return HaversineFit(amplitude_g=0.0, duration_ms=span * 1e3, r_squared=0.0)
    # Start from the haversine with the observed peak and delta-V: T = 2 dv / (A g).
    t_guess = 2.0 * (delta_v_kmh / KMH_PER_MPS) / (peak * STANDARD_GRAVITY)
    t_lo, t_hi = 2.0 * step, max(2.0 * span, 4.0 * step)
    t_guess = min(max(t_guess, 1.5 * t_lo), 0.99 * t_hi)

    # the terms of one duration, shared by the residual and the Jacobian at the same
    # point (MINPACK asks for both there), each computed once (compiled loops:
    # _haversine_terms, _haversine_residual, _haversine_jacobian)
    pi_t = np.pi * t
    last: dict[float, tuple[FloatArray, FloatArray]] = {}

    def terms(dur: float) -> tuple[FloatArray, FloatArray]:
        if dur not in last:
            last.clear()
            last[dur] = _haversine_terms(pi_t, dur)
        return last[dur]

    def residual(p: FloatArray) -> FloatArray:
        dur = float(p[1])
        return _haversine_residual(t, a, terms(dur)[1], float(p[0]), dur)

    def jacobian(p: FloatArray) -> FloatArray:
        # d/dA and d/dT of A sin^2(pi t / T) on [0, T] (0 outside): sin^2(pi t / T)
        # and -A (pi t / T^2) sin(2 pi t / T). [R] exact derivatives instead of
        # scipy's two extra residuals per step: about half the fit time
        dur = float(p[1])
        phase, sin2 = terms(dur)
        return _haversine_jacobian(t, phase, sin2, float(p[0]), dur)

    x0 = np.array([peak, t_guess])
    scale = np.array([max(peak, 1.0), max(t_guess, step)])
    # MINPACK's Levenberg-Marquardt first ([R] a third of the bounded trust-region
    # method's time on the EDR example, 0.8 against 2.3 ms, measured 2026-12-04: its
    # loop is compiled); it takes no bounds, so a fit that leaves them (or fails) is
    # redone by the bounded method from the same start. MINPACK through `leastsq`: the
    # call `least_squares(method="lm")` makes (its tolerances, 200 evaluations, diag =
    # 1 / x_scale, factor 100), the same fit, without that wrapper's set-up (0.3 ms)
    with np.errstate(all="ignore"):  # a trial step may leave the domain
        x, _, _, _, ier = leastsq(
            residual,
            x0,
            Dfun=jacobian,
            full_output=True,
            ftol=_LM_TOLERANCE,
            xtol=_LM_TOLERANCE,
            gtol=_LM_TOLERANCE,
            maxfev=100 * x0.size,
            factor=100.0,
            diag=1.0 / scale,
        )
    x = np.asarray(x, dtype=np.float64)
    if not (ier in _LM_SUCCESS and np.all(np.isfinite(x)) and x[0] >= 0.0 and t_lo <= x[1] <= t_hi):
        x = least_squares(
            residual,
            x0=x0,
            jac=jacobian,
            bounds=(np.array([0.0, t_lo]), np.array([np.inf, t_hi])),
            x_scale=scale,
            method="trf",
        ).x
    amp, dur = float(x[0]), float(x[1])
    ss_res = float(np.sum(residual(x) ** 2))
    ss_tot = float(np.sum((a - np.mean(a)) ** 2))
    # A (numerically) constant resultant has no variance to explain: r^2 = 0.
    degenerate = ss_tot <= _DEGENERATE_SS * float(np.sum(a**2))
    r2 = 0.0 if degenerate else 1.0 - ss_res / ss_tot
    return HaversineFit(amplitude_g=amp, duration_ms=dur * 1e3, r_squared=r2)


def _unit(c: float) -> float:
    """Direction cosine with rounding residue (|c| < 1e-12) and -0.0 set to 0.0."""
    return 0.0 if abs(c) < 1e-12 else c


def _readonly(a: FloatArray) -> FloatArray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a


def _check_delta_v(name: str, dv_kmh: float) -> None:
    if dv_kmh > MAX_DELTA_V_KMH:
        raise PulseError(
            f"`{name}` gives a delta-V of {dv_kmh:.4g} km/h, above the plausible maximum "
            f"{MAX_DELTA_V_KMH:g} km/h."
        )


def _check_implied_acceleration(vx: FloatArray, vy: FloatArray, dt: float) -> None:
    """Refuse a delta-V record changing faster than the accepted acceleration."""
    found = check_implied_acceleration(vx, vy, dt)
    if found is not None:
        name, k, accel_g = found
        raise PulseError(
            f"`{name}` is not a physical record: from element {k - 1} to {k} the delta-V "
            f"changes at {accel_g:.4g} g, beyond the accepted {MAX_ABS_ACCELERATION_G:g} g."
        )


def _check_reversals(
    name: str, dvx_kmh: FloatArray, dvy_kmh: FloatArray, max_dv_kmh: float, rate_hz: float
) -> None:
    """Refuse a delta-V that swings back and forth (:mod:`models.pulse_plausibility`)."""
    band = reversal_band_kmh(max_dv_kmh)
    for axis, series in ((name, dvx_kmh), (name.replace("longitudinal", "lateral"), dvy_kmh)):
        count, first = count_reversals(series, band)
        if count > MAX_DELTA_V_REVERSALS:
            raise PulseError(
                f"`{axis}` is not a physical record: its delta-V turns back {count} times by "
                f"more than {band:.3g} km/h (the first at {first / rate_hz * 1e3:.4g} ms); a "
                f"crash pulse turns at most {MAX_DELTA_V_REVERSALS} times."
            )


def _summarise(
    name: str,
    t: FloatArray,
    ax: FloatArray,
    ay: FloatArray,
    dvx_kmh: FloatArray,
    dvy_kmh: FloatArray,
    rate_hz: float,
    nonphysical: str | None = None,
) -> ProcessedPulse:
    """Common tail for measured pulses: end of event, delta-V, PDOF, peak, fit."""
    if not (np.all(np.isfinite(dvx_kmh)) and np.all(np.isfinite(dvy_kmh))):
        raise PulseError(f"`{name}` values are too large: the delta-V is not finite.")
    end = _end_of_event_index(dvx_kmh, dvy_kmh, rate_hz)
    if end is None:
        raise PulseError(
            f"`{name}` holds no crash pulse: the cumulative delta-V never changes by more "
            f"than {EOE_DELTA_V_KMH} km/h within {EOE_WINDOW_S * 1e3:g} ms "
            "(49 CFR 563.5 time zero)."
        )
    # 49 CFR 563 "maximum delta-V": the largest resultant change over the record
    at_max = int(np.argmax(np.hypot(dvx_kmh, dvy_kmh)))
    dvx, dvy = float(dvx_kmh[at_max]), float(dvy_kmh[at_max])
    dv = math.hypot(dvx, dvy)
    _check_delta_v(name, dv)
    _check_reversals(name, dvx_kmh, dvy_kmh, dv, rate_hz)
    resultant = np.hypot(ax[: end + 1], ay[: end + 1])
    fit = _fit_haversine(t[: end + 1], resultant, dv)
    return ProcessedPulse(
        time_s=_readonly(t),
        sample_rate_hz=rate_hz,
        longitudinal_g=_readonly(ax),
        lateral_g=_readonly(ay),
        delta_v_kmh=dv,
        delta_v_longitudinal_kmh=dvx,
        delta_v_lateral_kmh=dvy,
        pdof_deg=pdof_from_delta_v(dvx, dvy),
        peak_accel_g=float(np.max(resultant)),
        duration_ms=float(t[end]) * 1e3,
        haversine=fit,
        nonphysical=nonphysical,
    )


# --------------------------------------------------------------------------- per kind


def _process_acceleration(pulse: AccelerationPulse, rate_hz: float) -> ProcessedPulse:
    fs = _number("sample_rate_hz", pulse.sample_rate_hz)
    if fs <= MIN_ACCELERATION_SAMPLE_RATE_HZ:
        raise PulseError(
            f"`sample_rate_hz` must exceed {MIN_ACCELERATION_SAMPLE_RATE_HZ:g} Hz (twice the "
            f"CFC {PULSE_CFC} design frequency), got {fs:g}."
        )
    ax_raw = _series("longitudinal_g", pulse.longitudinal_g, MAX_ABS_ACCELERATION_G)
    ay_raw = _series("lateral_g", pulse.lateral_g, MAX_ABS_ACCELERATION_G)
    if ax_raw.size != ay_raw.size:
        raise PulseError(
            f"`lateral_g` has {ay_raw.size} samples but `longitudinal_g` has {ax_raw.size}; "
            "they must be the same length."
        )
    length = _check_record_duration("longitudinal_g", ax_raw.size, 1.0 / fs)
    # both channels through the filter side by side: cfc_filter's numbers, row by row
    raw = np.vstack((ax_raw, ay_raw))
    filtered = cfc_filter_rows(raw, fs, PULSE_CFC)
    ax_f, ay_f = filtered
    nonphysical = nonphysical_acceleration(raw, filtered, ("longitudinal_g", "lateral_g"), fs)
    t_in = np.arange(ax_raw.size, dtype=np.float64) / fs
    t = _grid(length, rate_hz)
    ax = np.interp(t, t_in, ax_f)
    ay = np.interp(t, t_in, ay_f)
    to_kmh = STANDARD_GRAVITY * KMH_PER_MPS
    dvx = _cumulative_trapezoid(ax, 1.0 / rate_hz) * to_kmh
    dvy = _cumulative_trapezoid(ay, 1.0 / rate_hz) * to_kmh
    return _summarise("longitudinal_g", t, ax, ay, dvx, dvy, rate_hz, nonphysical)


def _process_delta_v(pulse: DeltaVPulse, rate_hz: float) -> ProcessedPulse:
    interval_ms = _number("interval_ms", pulse.interval_ms)
    if interval_ms <= 0.0:
        raise PulseError(f"`interval_ms` must be positive, got {interval_ms:g}.")
    if interval_ms > MAX_EDR_INTERVAL_MS:
        raise PulseError(
            f"`interval_ms` must be at most {MAX_EDR_INTERVAL_MS:g} ms (one 49 CFR 563 "
            f"window), got {interval_ms:g}."
        )
    vx = _series("longitudinal_kmh", pulse.longitudinal_kmh, MAX_DELTA_V_KMH)
    vy = _series("lateral_kmh", pulse.lateral_kmh, MAX_DELTA_V_KMH)
    if vx.size != vy.size:
        raise PulseError(
            f"`lateral_kmh` has {vy.size} samples but `longitudinal_kmh` has {vx.size}; "
            "they must be the same length."
        )
    dt = interval_ms / 1e3
    length = _check_record_duration("longitudinal_kmh", vx.size, dt)
    _check_implied_acceleration(vx, vy, dt)
    t = _grid(length, rate_hz)
    # Piecewise-linear delta-V, piecewise-constant acceleration on [t_k, t_k+1).
    k = np.minimum(np.floor(t / dt + _GRID_EPS).astype(np.int64), vx.size - 2)
    to_g = 1.0 / (KMH_PER_MPS * STANDARD_GRAVITY * dt)
    ax = (np.diff(vx) * to_g)[k]
    ay = (np.diff(vy) * to_g)[k]
    t_rec = np.arange(vx.size, dtype=np.float64) * dt
    dvx = np.interp(t, t_rec, vx) - vx[0]
    dvy = np.interp(t, t_rec, vy) - vy[0]
    return _summarise("longitudinal_kmh", t, ax, ay, dvx, dvy, rate_hz)


#: Largest angle between the PDOF and the vehicle's long axis at which a
#: longitudinal-only delta-V is read as the resultant, deg. [R] Beyond 60 deg the
#: longitudinal component is under half the resultant and its 10 % tolerance
#: (49 CFR 563 Table III) doubles or more in the resultant: send the resultant.
MAX_LONGITUDINAL_READING_ANGLE_DEG: Final[float] = 60.0


def resultant_from_longitudinal_kmh(longitudinal_kmh: float, pdof_deg: float) -> float:
    """The resultant delta-V whose longitudinal component along the PDOF is `longitudinal_kmh`.

    ``resultant = |longitudinal| / |cos(PDOF)|`` (the longitudinal component of a
    delta-V along the PDOF).

    Raises
    ------
    PulseError
        The PDOF lies more than :data:`MAX_LONGITUDINAL_READING_ANGLE_DEG` from
        the long axis (a side impact: the longitudinal record does not carry it).
    """
    c = abs(math.cos(math.radians(pdof_deg)))
    if c < math.cos(math.radians(MAX_LONGITUDINAL_READING_ANGLE_DEG)):
        raise PulseError(
            f"`delta_v_axes` longitudinal: a longitudinal delta-V cannot be read as the resultant "
            f"at PDOF {pdof_deg:g} deg (more than {MAX_LONGITUDINAL_READING_ANGLE_DEG:g} deg from "
            "the vehicle's long axis): send the resultant."
        )
    return abs(longitudinal_kmh) / c


def _process_summary(pulse: SummaryPulse, rate_hz: float) -> ProcessedPulse:
    dv = _number("delta_v_kmh", pulse.delta_v_kmh)
    if dv <= 0.0:
        raise PulseError(f"`delta_v_kmh` must be positive, got {dv:g}.")
    _check_delta_v("delta_v_kmh", dv)
    pdof = _number("pdof_deg", pulse.pdof_deg) % 360.0
    pdof = 0.0 if pdof >= 360.0 else pdof
    if pulse.delta_v_axes == "longitudinal":
        dv = resultant_from_longitudinal_kmh(dv, pdof)
        _check_delta_v("delta_v_kmh", dv)
    if pulse.duration_ms is None:
        dur_ms = DEFAULT_HAVERSINE_DURATION_MS
    else:
        dur_ms = _number("duration_ms", pulse.duration_ms)
        if dur_ms < EOE_WINDOW_S * 1e3 or dur_ms > MAX_RECORD_DURATION_S * 1e3:
            raise PulseError(
                f"`duration_ms` must be between {EOE_WINDOW_S * 1e3:g} and "
                f"{MAX_RECORD_DURATION_S * 1e3:g} ms, got {dur_ms:g}."
            )
    dur_s = dur_ms / 1e3
    amp = haversine_amplitude_g(dv, dur_s)
    t = _grid(dur_s, rate_hz)
    a = haversine(t, amp, dur_s)
    rad = math.radians(pdof)
    # The force comes from the PDOF and acts towards the opposite direction.
    cx, cy = _unit(-math.cos(rad)), _unit(-math.sin(rad))
    return ProcessedPulse(
        time_s=_readonly(t),
        sample_rate_hz=rate_hz,
        longitudinal_g=_readonly(a * cx),
        lateral_g=_readonly(a * cy),
        delta_v_kmh=dv,
        delta_v_longitudinal_kmh=dv * cx,
        delta_v_lateral_kmh=dv * cy,
        pdof_deg=pdof,
        peak_accel_g=amp,
        duration_ms=dur_ms,
        haversine=HaversineFit(amplitude_g=amp, duration_ms=dur_ms, r_squared=1.0),
    )


def process_pulse(pulse: Pulse, output_rate_hz: float = DEFAULT_OUTPUT_RATE_HZ) -> ProcessedPulse:
    """Process a crash pulse of any kind.

    Parameters
    ----------
    pulse : AccelerationPulse or DeltaVPulse or SummaryPulse
        The pulse of the notification (units in the field names).
    output_rate_hz : float, optional
        Sampling rate of the returned arrays, Hz; between
        :data:`MIN_OUTPUT_RATE_HZ` and :data:`MAX_OUTPUT_RATE_HZ`. Default 10 kHz.

    Returns
    -------
    ProcessedPulse
        Arrays on ``[0, record end]`` (``[0, T]`` for a summary pulse) and the
        summary quantities; see the module docstring for the rules.

    Raises
    ------
    ValueError
        Naming the field, if a value is not finite, a rate or interval is not
        positive (or an acceleration rate is too low for CFC 60), a series is
        too short (fewer than 3 samples or under 20 ms) or too long (over 5 s),
        a sample is beyond +/-2000 g or +/-200 km/h,
        the channels differ in length, a measured pulse holds no crash (563
        time zero never reached), the delta-V exceeds 200 km/h, or a measured
        pulse is not physical (:mod:`models.pulse_plausibility`).
    TypeError
        If `pulse` is not one of the three pulse kinds.

    Examples
    --------
    >>> from models.notification import SummaryPulse
    >>> p = process_pulse(SummaryPulse(delta_v_kmh=40.0, pdof_deg=0.0, duration_ms=100.0))
    >>> round(p.haversine.amplitude_g, 2), p.pdof_deg
    (22.66, 0.0)
    """
    rate = _number("output_rate_hz", output_rate_hz)
    if not MIN_OUTPUT_RATE_HZ <= rate <= MAX_OUTPUT_RATE_HZ:
        raise PulseError(
            f"`output_rate_hz` must be between {MIN_OUTPUT_RATE_HZ:g} and "
            f"{MAX_OUTPUT_RATE_HZ:g} Hz, got {rate:g}."
        )
    if isinstance(pulse, AccelerationPulse):
        return _process_acceleration(pulse, rate)
    if isinstance(pulse, DeltaVPulse):
        return _process_delta_v(pulse, rate)
    if isinstance(pulse, SummaryPulse):
        return _process_summary(pulse, rate)
    raise TypeError(f"`pulse` must be a pulse dataclass, got {type(pulse).__name__}.")


def warm_up() -> None:
    """Compile (or load from the numba cache) the haversine fit's loops."""
    t = np.linspace(0.0, 0.01, 4)
    phase, sin2 = _haversine_terms(np.pi * t, 0.01)
    _haversine_residual(t, sin2, sin2, 1.0, 0.01)
    _haversine_jacobian(t, phase, sin2, 1.0, 0.01)
    _warm_up_plausibility()
