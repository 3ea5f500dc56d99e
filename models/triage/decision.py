"""The decision: a probability at a threshold, for the field model, the occupant
models and the statistical baseline; the case-level decision is the worst occupant's."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from models.baseline.logistic import BaselineFeatures
from models.field.model import FieldModel, FieldPrediction
from models.field.risk_model import RiskModel, RiskPrediction
from models.impact_mode import ImpactClassification, ImpactMode
from models.notification import (
    AirbagState,
    Occupant,
)
from models.pulse import ProcessedPulse
from models.tiers import (
    RECOMMENDATIONS,
    Tier,
    recommendation,
    second_opinion_recommendation,
    tier_of,
)
from models.triage.loading import EngineModels
from models.triage.result import LPM_OUTCOME, TriageDecision

__all__ = [
    "LPM_THRESHOLDS",
    "BASELINE_OUTCOME",
    "RECOMMENDATION_RECORD_CORRUPT",
    "decide",
    "decide_tiered",
    "flagged_for_corrupt_record",
]


#: Words for a decision made conservatively because the crash pulse record looks
#: corrupt (``models.pulse_plausibility.nonphysical_acceleration``): at least the
#: moderate tier's words.
RECOMMENDATION_RECORD_CORRUPT = (
    "The crash pulse record looks corrupt, so the telemetry cannot rule out severe injury "
    "(decided conservatively, at least moderate risk): " + RECOMMENDATIONS[Tier.MODERATE]
)


#: Decision thresholds on the occupant models' P(ISS >= 15), per mode. Bahouth,
#: Digges & Schulman recommend 0.10 for frontal and 0.05 for side crashes (sensitivity
#: > 0.67, PPV about 0.20; crash-data-and-triage.md section 1) [V]; rear takes the
#: frontal value [R]. The CDC 2008 panel's 20% is a vehicle-level rule for
#: statistical models and misses many seriously injured (Bahouth 2014). They apply
#: to the occupant model's P(ISS >= 15) after the zero-load correction
#: (`models.risk_calibration`): the uncorrected risk curves give ~5.4 % at zero
#: load, above the side threshold.
LPM_THRESHOLDS: Mapping[ImpactMode, float] = {
    ImpactMode.FRONTAL: 0.10,
    ImpactMode.REAR: 0.10,
    ImpactMode.NEAR_SIDE: 0.05,
    ImpactMode.FAR_SIDE: 0.05,
}


#: Outcome of the statistical baseline: police-reported incapacitating or fatal
#: injury (KABCO A or K), NASS-CDS 1997-2000.
BASELINE_OUTCOME = "police_A+K"


def decide(
    probability: float,
    ci95: tuple[float, float],
    threshold: float,
    *,
    outcome: str = LPM_OUTCOME,
    model: str = "occupant_models",
    operating_point: str | None = None,
) -> TriageDecision:
    """A second opinion's decision at `threshold` (positive when p >= threshold).

    It has no tier (tiers belong to the field decision): a positive one says what a
    telemetry indication says (:func:`models.tiers.second_opinion_recommendation`).
    """
    positive = probability >= threshold
    return TriageDecision(
        iss15_plus=positive,
        probability=probability,
        probability_ci95=ci95,
        threshold=threshold,
        recommendation=second_opinion_recommendation(positive),
        outcome=outcome,
        model=model,
        operating_point=operating_point,
    )


def decide_tiered(
    probability: float,
    ci95: tuple[float, float],
    threshold: float,
    high_threshold: float,
    *,
    outcome: str,
    model: str,
    operating_point: str | None,
) -> TriageDecision:
    """The field decision: positive at `threshold`, with its risk tier and the tier's words."""
    tier = tier_of(probability, threshold, high_threshold)
    return TriageDecision(
        iss15_plus=probability >= threshold,
        probability=probability,
        probability_ci95=ci95,
        threshold=threshold,
        recommendation=recommendation(tier),
        outcome=outcome,
        model=model,
        operating_point=operating_point,
        tier=tier,
        high_threshold=high_threshold,
    )


def _baseline_decision(
    models: EngineModels, occupant: Occupant, pulse: ProcessedPulse, impact: ImpactClassification
) -> TriageDecision:
    prediction = models.baseline.predict(
        BaselineFeatures(
            delta_v_kmh=pulse.delta_v_kmh,
            belted=occupant.belted,
            airbag_deployed=occupant.frontal_airbag is AirbagState.DEPLOYED,
            frontal=impact.frontal_nass,
            age_years=occupant.age_years,
            sex=occupant.sex,
        )
    )
    return decide(
        prediction.probability,
        prediction.ci95,
        models.baseline.threshold,
        outcome=BASELINE_OUTCOME,
        model=models.baseline.name,
    )


def _field_decision(
    field_model: FieldModel,
    models: EngineModels,
    prediction: FieldPrediction,
) -> TriageDecision:
    name = models.operating_point or field_model.default_operating_point
    threshold = (
        models.threshold_override
        if models.threshold_override is not None
        else field_model.threshold(prediction.mode, name)
    )
    return decide_tiered(
        prediction.probability,
        prediction.ci95,
        threshold,
        models.high_threshold,
        outcome=field_model.outcome,
        model=f"{field_model.name}@{field_model.version}",
        operating_point=None if models.threshold_override is not None else name,
    )


def _risk_threshold(
    risk_model: RiskModel, models: EngineModels, knowledge: str | None = None
) -> float:
    """The operating threshold of the field risk model for what was known of the occupant
    (:meth:`models.field.risk_model.RiskModel.threshold`; the override where one is set)."""
    if models.threshold_override is not None:
        return models.threshold_override
    name = models.operating_point or risk_model.default_operating_point
    return risk_model.threshold(name, knowledge)


def _risk_decision(
    risk_model: RiskModel, models: EngineModels, prediction: RiskPrediction
) -> TriageDecision:
    """The decision on P(ISS 15+) of the field risk model at its operating point."""
    name = models.operating_point or risk_model.default_operating_point
    decided = decide_tiered(
        prediction.probability,
        prediction.ci95,
        _risk_threshold(risk_model, models, prediction.knowledge),
        models.high_threshold,
        outcome=risk_model.outcome,
        model=f"{risk_model.name}@{risk_model.version}",
        operating_point=None if models.threshold_override is not None else name,
    )
    return dataclasses.replace(
        decided,
        unknown_inputs_range95=prediction.unknown_inputs_range95,
        knowledge=prediction.knowledge if risk_model.knowledge_thresholds else None,
    )


def _worst(decisions: list[TriageDecision]) -> TriageDecision:
    return max(decisions, key=lambda d: (d.iss15_plus, d.probability))


def flagged_for_corrupt_record(decision: TriageDecision) -> TriageDecision:
    """`decision` made conservatively: positive and at least the moderate tier whatever
    its probability (kept as computed), because the pulse it was computed from looks
    corrupt; a high tier keeps its own words."""
    if decision.tier is Tier.HIGH:
        return dataclasses.replace(decision, iss15_plus=True)
    return dataclasses.replace(
        decision,
        iss15_plus=True,
        tier=Tier.MODERATE if decision.tier is not None else None,
        recommendation=RECOMMENDATION_RECORD_CORRUPT,
    )
