"""The one set of input limits: what the engine accepts, defined once.

The engine checks its inputs against these (``models.pulse``, the field and
baseline models), and the HTTP contract (``service/cases/notification.py``) refuses the
same values with a 422 that names the field, so a notification the wire accepts
is one the engine can process. Each limit names its source.
"""

from __future__ import annotations

from typing import Final

from models.injury.filters import SAE_J211_DESIGN_FACTOR

__all__ = [
    "MAX_ABS_ACCELERATION_G",
    "MAX_ACCELERATION_SAMPLE_RATE_HZ",
    "MAX_AGE_YEARS",
    "MAX_DELTA_V_KMH",
    "MAX_EDR_INTERVAL_MS",
    "MAX_MASS_KG",
    "MAX_RECORD_DURATION_MS",
    "MAX_SAMPLES",
    "MAX_STATURE_CM",
    "MIN_ACCELERATION_SAMPLE_RATE_HZ",
    "MIN_EDR_INTERVAL_MS",
    "MIN_MASS_KG",
    "MIN_RECORD_DURATION_MS",
    "MIN_SAMPLES",
    "MIN_STATURE_CM",
    "PULSE_CFC",
]

#: Channel frequency class of vehicle crash pulses (SAE J211-1 table;
#: ``injury-criteria.md`` section 4; ``occupant-lpm-notes.md`` section 3).
PULSE_CFC: Final[int] = 60

#: Largest plausible delta-V, km/h: a delta-V above 200 km/h is refused (a requirement
#: of the service).
MAX_DELTA_V_KMH: Final[float] = 200.0

#: Largest acceleration magnitude in a record, g. [R] Vehicle crash pulses of
#: passenger cars stay well under 200 g even on a rigid pole (haversine peaks
#: 10-60 g, ``occupant-lpm-notes.md`` section 3); 500 g allows unfiltered sensor
#: spikes while refusing unit mistakes (m/s^2 sent as g).
MAX_ABS_ACCELERATION_G: Final[float] = 500.0

#: Lowest sampling rate of an acceleration record, Hz: the CFC 60 design
#: frequency (60 x 2.0775 Hz, SAE J211-1) must lie below the Nyquist frequency.
MIN_ACCELERATION_SAMPLE_RATE_HZ: Final[float] = 2.0 * PULSE_CFC * SAE_J211_DESIGN_FACTOR

#: Highest sampling rate of an acceleration record, Hz. [R] Crash sensor
#: channels are sampled at up to 20 kHz (SAE J211 recommends >= 10 kHz); 50 kHz
#: leaves room without admitting absurd rates.
MAX_ACCELERATION_SAMPLE_RATE_HZ: Final[float] = 50_000.0

#: Shortest record, ms: one 49 CFR 563.5 window (time zero and end of event are
#: decided over 20 ms) [V].
MIN_RECORD_DURATION_MS: Final[float] = 20.0

#: Longest record, ms. [R] 49 CFR 563 treats two events within 5 s as one
#: multi-event crash; a single pulse record is 250-300 ms (Table I).
MAX_RECORD_DURATION_MS: Final[float] = 5_000.0

#: Fewest samples in a measured record (two intervals).
MIN_SAMPLES: Final[int] = 3

#: Most samples in a record. [R] 3 s at 20 kHz; a body of that size is near the
#: service's 1 MiB request limit.
MAX_SAMPLES: Final[int] = 60_000

#: Sampling interval of an EDR delta-V record, ms: at least 1 ms, at most one
#: 49 CFR 563 window (20 ms); Part 563 Table I records at 10 ms [V].
MIN_EDR_INTERVAL_MS: Final[float] = 1.0
MAX_EDR_INTERVAL_MS: Final[float] = 20.0

#: Oldest age accepted, years. [R] The oldest occupant in the NASS-CDS data is 97.
MAX_AGE_YEARS: Final[float] = 120.0

#: Stature and mass of an occupant, cm and kg. [R] Adults and children carried
#: in a seat, with room for both tails of the populations.
MIN_STATURE_CM, MAX_STATURE_CM = 50.0, 250.0
MIN_MASS_KG, MAX_MASS_KG = 10.0, 300.0
