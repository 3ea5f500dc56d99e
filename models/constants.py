"""Physical and statistical constants shared by the engine (one home for each).

Each constant names its source. Modules import them from here instead of
writing the number again.
"""

from __future__ import annotations

from typing import Final

__all__ = ["DEFAULT_POSTURE_SD_DEG", "DEFAULT_SEAT_TRACK_SD_MM", "G_MS2", "Z_95"]

#: Standard acceleration of gravity, m/s^2 (ISO 80000-3; CGPM 1901).
G_MS2: Final[float] = 9.80665

#: Two-sided 95 % standard normal quantile, ``Phi^-1(0.975)`` (scipy.stats.norm.ppf).
Z_95: Final[float] = 1.959963984540054

#: Default sensor standard deviations: posture within 5 deg and seat position
#: within 5 cm, 95 % of the time, Gaussian (the sensors' stated bounds): SD = bound / z95;
#: deg, mm.
DEFAULT_POSTURE_SD_DEG: Final[float] = 5.0 / Z_95
DEFAULT_SEAT_TRACK_SD_MM: Final[float] = 50.0 / Z_95
