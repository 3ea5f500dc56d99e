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
from models.triage.loading import EngineModels
from models.triage.result import LPM_OUTCOME, TriageDecision

__all__ = [
    "RECOMMENDATION_TRAUMA_CENTER",
    "RECOMMENDATION_NO_TRAUMA_INDICATION",
    "RECOMMENDATION_RECORD_CORRUPT",
    "LPM_THRESHOLDS",
    "BASELINE_OUTCOME",
    "decide",
    "flagged_for_corrupt_record",
]


#: Words for a positive decision. CDC 2011 / ACS 2021 field triage: "vehicle
#: telemetry data consistent with severe injury" (crash-data-and-triage.md s.4).
RECOMMENDATION_TRAUMA_CENTER = (
    "Transport to a Level I trauma center: vehicle telemetry consistent with severe "
    "injury (ISS 15 or more likely)."
)


#: Words for a negative decision: telemetry alone does not call for a trauma center.
RECOMMENDATION_NO_TRAUMA_INDICATION = (
    "No telemetry indication of ISS 15 or more: destination by EMS field assessment "
    "under local protocol."
)


#: Words for a decision made conservatively because the crash pulse record looks
#: corrupt (``models.pulse_plausibility.nonphysical_acceleration``).
RECOMMENDATION_RECORD_CORRUPT = (
    "Transport to a Level I trauma center: the crash pulse record looks corrupt, so the "
    "telemetry cannot rule out severe injury (decided conservatively)."
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
    """Turn a probability into a decision at `threshold` (positive when p >= threshold)."""
    positive = probability >= threshold
    return TriageDecision(
        iss15_plus=positive,
        probability=probability,
        probability_ci95=ci95,
        threshold=threshold,
        recommendation=(
            RECOMMENDATION_TRAUMA_CENTER if positive else RECOMMENDATION_NO_TRAUMA_INDICATION
        ),
        outcome=outcome,
        model=model,
        operating_point=operating_point,
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
    return decide(
        prediction.probability,
        prediction.ci95,
        threshold,
        outcome=field_model.outcome,
        model=f"{field_model.name}@{field_model.version}",
        operating_point=None if models.threshold_override is not None else name,
    )


def _risk_decision(
    risk_model: RiskModel, models: EngineModels, prediction: RiskPrediction
) -> TriageDecision:
    """The decision on P(ISS 15+) of the field risk model at its operating point."""
    name = models.operating_point or risk_model.default_operating_point
    threshold = (
        models.threshold_override
        if models.threshold_override is not None
        else risk_model.threshold(name)
    )
    return decide(
        prediction.probability,
        prediction.ci95,
        threshold,
        outcome=risk_model.outcome,
        model=f"{risk_model.name}@{risk_model.version}",
        operating_point=None if models.threshold_override is not None else name,
    )


def _worst(decisions: list[TriageDecision]) -> TriageDecision:
    return max(decisions, key=lambda d: (d.iss15_plus, d.probability))


def flagged_for_corrupt_record(decision: TriageDecision) -> TriageDecision:
    """`decision` made conservatively: positive whatever its probability (kept as computed),
    because the pulse it was computed from looks corrupt."""
    return dataclasses.replace(
        decision, iss15_plus=True, recommendation=RECOMMENDATION_RECORD_CORRUPT
    )
