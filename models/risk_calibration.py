"""The occupant models' P(ISS >= 15) on the scale of the field-triage thresholds.

The published injury risk curves the occupant models use are logistic fits whose
risk does not vanish at zero load: the NHTSA/Eppinger 1999 Nij curves give
P(AIS >= 2) = 11.4 %, P(AIS >= 3) = 3.8 % and P(AIS >= 5) = 2.2 % at Nij = 0,
the Lau & Viano VC and Kleinberger CTI curves about 0.9 % each
(``models.injury.risk``). Combined over the ISS regions this gives every
occupant a P(ISS >= 15) of about 5.4 % before any load acts: above the side
threshold of 0.05 (Bahouth, Digges & Schulman; ``models.triage.LPM_THRESHOLDS``),
so that an 8 km/h side crash sent its occupants to a trauma center. A risk
curve's value at zero stimulus is a property of the fitted family, not a
probability of injury from the crash: survival-analysis fits in the stimulus
(Weibull, log-normal, log-logistic, as in the ISO/TR 12350:2013 procedure for
side-impact risk curves) pass through zero risk at zero stimulus.

The correction is Abbott's formula for a background response in quantal
dose-response data (W. S. Abbott, "A method of computing the effectiveness of an
insecticide", J. Econ. Entomol. 18:265-267, 1925): with P0 the probability at
zero load of the same occupant, mode and set of measures,

    P_corrected = (P - P0) / (1 - P0),   clipped to [0, 1],

the probability of ISS >= 15 attributable to the crash loads if the zero-load
"response" and the load-induced one are independent (P = P0 + (1 - P0) P_load).
It is affine and increasing in P, so it keeps the order of cases, maps a
95 % interval to the 95 % interval of the corrected value and a sample mean to
the corrected mean, and gives exactly 0 at zero load. The regional AIS levels
and the ISS point estimate (medians of the regional distributions) are not
changed. [R] engineering choice: the field calibration of occupant-model risk
that Bahouth's thresholds presume is not available (no ISS-coded field data in
hand); this removes the one part that is an artefact of the curve family.

The correction is versioned (:data:`CALIBRATION_VERSION`) and recorded with
every case (``models.triage.EngineModels.model_infos``).
"""

from __future__ import annotations

import dataclasses
import hashlib
from functools import lru_cache
from pathlib import Path
from typing import Final

from models.impact_mode import ImpactMode
from models.injury.assessment import InjuryMeasures, assess
from models.notification import Body

__all__ = [
    "CALIBRATION_NAME",
    "CALIBRATION_VERSION",
    "calibration_sha256",
    "corrected_probability",
    "zero_load_probability",
]

#: Name and version of the correction, stored with every case answered by an
#: occupant model. Bump the version on any change to this module.
CALIBRATION_NAME: Final[str] = "zero-load (Abbott) correction of occupant-model P(ISS>=15)"
CALIBRATION_VERSION: Final[str] = "1"


@lru_cache(maxsize=1)
def calibration_sha256() -> str:
    """SHA-256 of this module's source (the correction's checksum in a case record)."""
    return hashlib.sha256(Path(__file__).read_bytes().replace(b"\r\n", b"\n")).hexdigest()


@lru_cache(maxsize=256)
def _zero_load_probability(
    present: tuple[str, ...], body: Body, age_years: float | None, mode: ImpactMode
) -> float:
    zero = InjuryMeasures(**dict.fromkeys(present, 0.0))
    return float(assess(zero, body, age_years, mode.value).p_iss15)


def zero_load_probability(
    measures: InjuryMeasures, body: Body, age_years: float | None, mode: ImpactMode
) -> float:
    """P(ISS >= 15) of the same occupant when every measure it reports is zero.

    Parameters
    ----------
    measures : InjuryMeasures
        The occupant's measures; only which fields are present (not None) matters.
    body : Body
        Hybrid III 50th male or 5th female.
    age_years : float or None
        Occupant age, years (selects the age-dependent chest curve), as in
        :func:`models.injury.assessment.assess`.
    mode : ImpactMode
        Impact mode (selects the side curves).

    Returns
    -------
    float
        P0 in [0, 1).
    """
    present = tuple(
        f.name for f in dataclasses.fields(InjuryMeasures) if getattr(measures, f.name) is not None
    )
    return _zero_load_probability(present, Body(body), age_years, ImpactMode(mode))


def corrected_probability(p: float, p0: float) -> float:
    """Abbott's correction: (p - p0) / (1 - p0), clipped to [0, 1].

    Parameters
    ----------
    p : float
        P(ISS >= 15) from the risk curves, in [0, 1].
    p0 : float
        The same occupant's P(ISS >= 15) at zero load, in [0, 1).

    Returns
    -------
    float

    Raises
    ------
    ValueError
        If `p0` is not in [0, 1).

    Examples
    --------
    >>> corrected_probability(0.0544, 0.0544)
    0.0
    >>> round(corrected_probability(0.55, 0.10), 3)
    0.5
    """
    if not 0.0 <= p0 < 1.0:
        raise ValueError(f"`p0` must be in [0, 1), got {p0!r}.")
    return min(max((float(p) - p0) / (1.0 - p0), 0.0), 1.0)
