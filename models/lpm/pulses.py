"""Synthetic crash pulses for tests, the benchmark and calibration.

Haversine ``a(t) = A sin^2(pi t / T)`` for 0 <= t <= T (the intended form of the
reference paper's equation (1), occupant-lpm-notes.md section 3), with
delta-V = A T / 2.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from models.pulse import haversine, haversine_amplitude_g

__all__ = ["haversine_pulse", "ncap_frontal_pulse", "side_pulse"]


def haversine_pulse(
    delta_v_kmh: float,
    duration_s: float,
    *,
    angle_deg: float = 0.0,
    sample_rate_hz: float = 10_000.0,
    record_s: float = 0.25,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Haversine vehicle pulse with a given delta-V along a PDOF.

    Parameters
    ----------
    delta_v_kmh : float
        Magnitude of the velocity change, km/h.
    duration_s : float
        Pulse duration T, s.
    angle_deg : float
        PDOF, deg clockwise from straight ahead (0 frontal, 90 struck on the
        right, 180 rear); the vehicle accelerates opposite to the PDOF vector.
    sample_rate_hz, record_s : float
        Sampling rate (Hz) and record length (s).

    Returns
    -------
    time_s, accel_x_g, accel_y_g : ndarray, shape (n,)
        J211 axes, g.
    """
    t = np.arange(int(round(record_s * sample_rate_hz)) + 1) / sample_rate_hz
    a = haversine(t, haversine_amplitude_g(delta_v_kmh, duration_s), duration_s)
    th = math.radians(angle_deg)
    return t, -a * math.cos(th), -a * math.sin(th)


def ncap_frontal_pulse(
    sample_rate_hz: float = 10_000.0,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """US NCAP 56 km/h full-width rigid barrier, compact car.

    Delta-V 56 km/h plus ~10 % rebound = 61.6 km/h (17.1 m/s) over T = 90 ms:
    haversine peak 39 g (occupant-lpm-notes.md section 3: ~43 g at 80 ms,
    ~35 g at 100 ms for a 17 m/s change).
    """
    return haversine_pulse(61.6, 0.090, sample_rate_hz=sample_rate_hz)


def side_pulse(
    delta_v_kmh: float = 28.8,
    duration_s: float = 0.06,
    *,
    right: bool = False,
    sample_rate_hz: float = 10_000.0,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Lateral pulse of a struck car.

    The default is the IIHS-type 50 km/h side test: a 1500 kg barrier into a
    1100 kg car gives the car 50 x 1500 / 2600 = 28.8 km/h (notes section 3).
    ``right`` selects the struck side (False: struck on the left).
    """
    return haversine_pulse(
        delta_v_kmh, duration_s, angle_deg=90.0 if right else 270.0, sample_rate_hz=sample_rate_hz
    )
