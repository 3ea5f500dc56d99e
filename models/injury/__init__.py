"""Injury criteria, risk curves, AIS and ISS; the limits shown beside the measures.

Layout::

    filters     CFC filter (SAE J211-1 App. C / ISO 6487)
    criteria    HIC, Nij, chest deflection / compression, VC, CTI, 3 ms clip
    risk        P(AIS >= n) curves, each named after its source
    scores      ISS regions, Baker ISS, exact P(ISS >= threshold)
    assessment  measures -> regional AIS distributions, ISS, P(ISS >= 15)

Plain numpy in, frozen dataclasses out; no web or database dependency.
Coefficients and their sources: ``injury-criteria.md`` (labels [V], [S], [U],
[R] in the docstrings are that file's confidence labels).
"""

from models.injury import risk
from models.injury.assessment import (
    ISS_TRIAGE_THRESHOLD,
    InjuryAssessment,
    InjuryMeasures,
    assess,
    region_cumulative_risk,
)
from models.injury.criteria import (
    CHEST_DEPTH_MM,
    CTI_INTERCEPTS,
    NIJ_INTERCEPTS,
    VC_CONSTANTS,
    ChestDeflectionResult,
    CtiIntercepts,
    HicResult,
    NijIntercepts,
    NijMode,
    NijResult,
    VcConstants,
    chest_deflection,
    clip_3ms,
    cti,
    hic,
    nij,
    occipital_condyle_moment,
    viscous_criterion,
)
from models.injury.filters import CFC_CLASSES, cfc_coefficients, cfc_filter
from models.injury.scores import (
    ISS_REGIONS,
    ais_distribution_from_cumulative,
    ais_level,
    iss,
    iss_distribution,
    p_iss_at_least,
)

__all__ = [
    "CFC_CLASSES",
    "CHEST_DEPTH_MM",
    "CTI_INTERCEPTS",
    "ISS_REGIONS",
    "ISS_TRIAGE_THRESHOLD",
    "NIJ_INTERCEPTS",
    "VC_CONSTANTS",
    "ChestDeflectionResult",
    "CtiIntercepts",
    "HicResult",
    "InjuryAssessment",
    "InjuryMeasures",
    "NijIntercepts",
    "NijMode",
    "NijResult",
    "VcConstants",
    "ais_distribution_from_cumulative",
    "ais_level",
    "assess",
    "cfc_coefficients",
    "cfc_filter",
    "chest_deflection",
    "clip_3ms",
    "cti",
    "hic",
    "iss",
    "iss_distribution",
    "nij",
    "occipital_condyle_moment",
    "p_iss_at_least",
    "region_cumulative_risk",
    "risk",
    "viscous_criterion",
]
