"""Risk tiers of the field decision in the field-triage guideline's own terms, and the
words of each tier's recommendation.

The 2021 National Guideline for the Field Triage of Injured Patients (Newgard et al.,
J Trauma Acute Care Surg 2022; crash-data-and-triage.md section 4) lists "vehicle
telemetry data consistent with severe injury" among its moderate-risk (yellow)
criteria: a trauma center is to be considered, and it need not be the highest level.
Only its high-risk (red) criteria send a patient to the highest-level center. The CDC's
2008 expert panel on vehicle telemetry (CDC, GM Foundation, OnStar) set "high risk of
severe injury" at a 20 % probability of ISS 15+. So a field decision has one of three
tiers:

- ``high``: P at or above the high-risk threshold (default 20 %) and at or above the
  operating point's threshold;
- ``moderate``: P at or above the operating point's threshold (``iss15_plus``), below
  the high-risk threshold;
- ``none``: P below the operating point's threshold: no telemetry indication.

Tiers belong to the field decision (each occupant's, the case's, the vehicle's); the
second opinions (occupant models, statistical baseline) have none and speak in the
moderate tier's words when positive (:func:`second_opinion_recommendation`).
"""

from __future__ import annotations

from collections.abc import Mapping
from enum import StrEnum
from typing import Final

__all__ = [
    "HIGH_RISK_THRESHOLD",
    "PEDIATRIC_CRITERION_MAX_AGE_YEARS",
    "PEDIATRIC_CRITERION_WORDS",
    "PEDIATRIC_WORDS",
    "RECOMMENDATIONS",
    "Tier",
    "ThresholdOrderError",
    "check_threshold_order",
    "child_recommendation",
    "recommendation",
    "second_opinion_recommendation",
    "tier_of",
]


class Tier(StrEnum):
    """Risk tier of a field decision (module docstring)."""

    HIGH = "high"
    MODERATE = "moderate"
    NONE = "none"


#: Default high-risk threshold on P(ISS 15+): the CDC 2008 expert panel's 20 %, "high
#: risk of severe injury" (at most four of five flagged without severe injury;
#: crash-data-and-triage.md section 4; Bahouth, Digges & Schulman). The panel set it
#: for the vehicle; here it applies to each occupant's and the vehicle's probability.
HIGH_RISK_THRESHOLD: Final[float] = 0.20

#: The words of each tier (the guideline's terms; the high and moderate wordings are
#: those of the project's issue, with a capital and a full stop).
RECOMMENDATIONS: Final[Mapping[Tier, str]] = {
    Tier.HIGH: "Transport to the highest-level trauma center in reach.",
    Tier.MODERATE: (
        "Vehicle telemetry consistent with severe injury (2021 guideline, moderate risk): "
        "consider a trauma center, which need not be the highest level; EMS judgment and "
        "local protocol decide."
    ),
    Tier.NONE: (
        "No telemetry indication of ISS 15 or more: destination by EMS field assessment "
        "under local protocol."
    ),
}


class ThresholdOrderError(ValueError):
    """The high-risk threshold lies below an operating threshold: the tiers would not nest."""


def tier_of(probability: float, threshold: float, high_threshold: float) -> Tier:
    """The tier of `probability` against the operating `threshold` and `high_threshold`.

    High needs both: at or above the high-risk threshold *and* the operating
    threshold, so that a high tier always has ``iss15_plus`` (the service refuses a
    high threshold below the operating one; a stored case decided under such a
    setting is read back in the same nesting).
    """
    if probability < threshold:
        return Tier.NONE
    return Tier.HIGH if probability >= high_threshold else Tier.MODERATE


def recommendation(tier: Tier) -> str:
    """The recommendation in words of a field decision of `tier`.

    The one place the words are chosen: a variant (e.g. for children) is added here.
    """
    return RECOMMENDATIONS[tier]


#: The pediatric sentence of a child's field decision. [V] 2021 National Guideline for
#: the Field Triage of Injured Patients (Newgard et al. 2022; crash-data-and-triage.md
#: section 4): injured children go preferentially to trauma centers with pediatric
#: capability.
PEDIATRIC_WORDS: Final[str] = (
    "A child: prefer a trauma center with pediatric capability (2021 guideline)."
)

#: The guideline's pediatric crash criterion, a criterion of its own. [V] 2021 guideline,
#: high-risk auto crash: "child (age 0-9 years) unrestrained or in unsecured child safety
#: seat" (NEMSIS eInjury.04 2904029).
PEDIATRIC_CRITERION_WORDS: Final[str] = (
    "Guideline criterion met: a child of 0-9 years unrestrained or in an unsecured child "
    "seat (2021 guideline, high-risk auto crash): consider a trauma center with pediatric "
    "capability whatever the telemetry says."
)

#: Ages of the pediatric crash criterion, years ([0, 10)).
PEDIATRIC_CRITERION_MAX_AGE_YEARS: Final[float] = 10.0


def child_recommendation(tier: Tier, criterion: bool) -> str:
    """The words of a child's field decision of `tier`: the tier's, then the pediatric
    sentence, and the pediatric crash criterion first where it applies."""
    words = f"{RECOMMENDATIONS[tier]} {PEDIATRIC_WORDS}"
    return f"{PEDIATRIC_CRITERION_WORDS} {words}" if criterion else words


def second_opinion_recommendation(positive: bool) -> str:
    """The words of a second opinion (occupant models, baseline): it has no tier, and a
    positive one says what a telemetry indication says (the moderate tier's words)."""
    return RECOMMENDATIONS[Tier.MODERATE if positive else Tier.NONE]


def check_threshold_order(high_threshold: float, thresholds: Mapping[str, float]) -> None:
    """Raise ThresholdOrderError when `high_threshold` lies below any of `thresholds`.

    Parameters
    ----------
    high_threshold : float
    thresholds : mapping
        The operating thresholds in use, by a name for the message (the operating
        point, with the crash mode where thresholds differ by mode).
    """
    if not 0.0 < high_threshold < 1.0:
        raise ThresholdOrderError(f"the high-risk threshold {high_threshold!r} is not in (0, 1)")
    above = {name: t for name, t in thresholds.items() if t > high_threshold}
    if above:
        listed = ", ".join(f"{name} {t:.4f}" for name, t in sorted(above.items()))
        raise ThresholdOrderError(
            f"the high-risk threshold {high_threshold:.4f} (AACN_HIGH_RISK_THRESHOLD) lies "
            f"below the operating threshold ({listed}): the high tier must lie within the "
            "flagged; raise it or choose another operating point"
        )
