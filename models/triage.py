"""The orchestrator: one notification in, one triage result out.

Flow per notification: the pulse is processed once (`models.pulse`); per
occupant the impact mode is classified (`models.impact_mode`); occupants inside
an occupant model's coverage are answered by that model when one is loaded,
all others by the statistical baseline (`models.baseline`), which is also kept
for every occupant as a second opinion. The case-level decision is the worst
occupant's.

Everything here is a pure function of the notification and the loaded models:
the same inputs and model versions give the same result, bit for bit (only
`timings_ms` varies).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field

from models import ENGINE_VERSION
from models.baseline.logistic import BaselineFeatures, BaselineModel, load_default
from models.impact_mode import ImpactClassification, classify_impact
from models.notification import AirbagState, Body, CrashNotification, Occupant, Seat
from models.pulse import ProcessedPulse, process_pulse

__all__ = [
    "RECOMMENDATION_NO_TRAUMA_INDICATION",
    "RECOMMENDATION_TRAUMA_CENTER",
    "EngineModels",
    "IssEstimate",
    "ModelInfo",
    "OccupantTriage",
    "TriageDecision",
    "TriageResult",
    "UnknownVehicleModel",
    "decide",
    "load_engine_models",
    "triage",
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


class UnknownVehicleModel(ValueError):
    """The notification names a vehicle parameter set that is not loaded."""


@dataclass(frozen=True)
class ModelInfo:
    """Name, version and checksum of one model artifact (recorded with every case)."""

    name: str
    version: str
    sha256: str


@dataclass(frozen=True)
class TriageDecision:
    """An ISS15+ decision on a probability with its 95% interval."""

    iss15_plus: bool
    probability: float
    probability_ci95: tuple[float, float]
    threshold: float
    recommendation: str


@dataclass(frozen=True)
class IssEstimate:
    """ISS point estimate and, where available, its 95% interval."""

    estimate: int
    ci95: tuple[float, float] | None = None


@dataclass(frozen=True)
class OccupantTriage:
    """The triage of one occupant."""

    seat: Seat
    body: Body
    impact: ImpactClassification
    method: str
    triage: TriageDecision
    baseline: TriageDecision
    iss: IssEstimate | None = None
    region_ais: Mapping[str, int] | None = None
    measures: Mapping[str, float] | None = None


@dataclass(frozen=True)
class TriageResult:
    """The engine's answer to a notification."""

    event_id: str
    triage: TriageDecision
    occupants: tuple[OccupantTriage, ...]
    pulse: ProcessedPulse
    assumptions: tuple[str, ...]
    engine_version: str
    models: Mapping[str, ModelInfo]
    timings_ms: Mapping[str, float] = field(compare=False)


@dataclass(frozen=True)
class EngineModels:
    """Every model the engine answers with, loaded once at start.

    Attributes
    ----------
    baseline : BaselineModel
        The statistical baseline (always present).
    vehicle_models : frozenset of str
        Vehicle parameter-set names a notification may name.
    threshold_override : float or None
        Replaces every model's own decision threshold when set.
    """

    baseline: BaselineModel
    vehicle_models: frozenset[str] = frozenset({"compact_sedan"})
    threshold_override: float | None = None

    def model_infos(self) -> dict[str, ModelInfo]:
        """The versions and checksums of the loaded models."""
        b = self.baseline
        return {"baseline": ModelInfo(name=b.name, version=b.version, sha256=b.sha256)}


def load_engine_models(threshold_override: float | None = None) -> EngineModels:
    """Load and verify the shipped model artifacts.

    Raises
    ------
    ValueError
        When an artifact is missing or malformed.
    """
    return EngineModels(baseline=load_default(), threshold_override=threshold_override)


def decide(probability: float, ci95: tuple[float, float], threshold: float) -> TriageDecision:
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
    threshold = (
        models.threshold_override
        if models.threshold_override is not None
        else models.baseline.threshold
    )
    return decide(prediction.probability, prediction.ci95, threshold)


def _worst(decisions: list[TriageDecision]) -> TriageDecision:
    return max(decisions, key=lambda d: (d.iss15_plus, d.probability))


def triage(notification: CrashNotification, models: EngineModels) -> TriageResult:
    """Triage every occupant of a notification.

    Parameters
    ----------
    notification : CrashNotification
    models : EngineModels

    Returns
    -------
    TriageResult

    Raises
    ------
    UnknownVehicleModel
        When `notification.vehicle_model` names no loaded parameter set.
    ValueError
        When the pulse cannot be processed (the message names the field).
    """
    if notification.vehicle_model not in models.vehicle_models:
        raise UnknownVehicleModel(
            f"unknown vehicle model {notification.vehicle_model!r}; known: "
            + ", ".join(sorted(models.vehicle_models))
        )
    t0 = time.perf_counter()
    pulse = process_pulse(notification.pulse)
    t1 = time.perf_counter()

    assumptions: list[str] = []
    if notification.rollover:
        assumptions.append(
            "rollover reported: not modelled by the engine; weigh it in field triage"
        )
    if notification.multiple_impacts:
        assumptions.append(
            "multiple impacts reported: the engine models the recorded pulse as one event"
        )

    occupants: list[OccupantTriage] = []
    for i, occupant in enumerate(notification.occupants):
        impact = classify_impact(pulse.pdof_deg, occupant.seat, notification.drive_side)
        baseline = _baseline_decision(models, occupant, pulse, impact)
        if impact.in_lpm_coverage:
            assumptions.append(
                f"occupants[{i}]: {impact.mode.value} occupant model not yet available; "
                "statistical baseline used"
            )
        occupants.append(
            OccupantTriage(
                seat=occupant.seat,
                body=occupant.body,
                impact=impact,
                method="baseline",
                triage=baseline,
                baseline=baseline,
            )
        )
    t2 = time.perf_counter()

    return TriageResult(
        event_id=notification.event_id,
        triage=_worst([o.triage for o in occupants]),
        occupants=tuple(occupants),
        pulse=pulse,
        assumptions=tuple(assumptions),
        engine_version=ENGINE_VERSION,
        models=models.model_infos(),
        timings_ms={
            "pulse": 1000.0 * (t1 - t0),
            "occupants": 1000.0 * (t2 - t1),
            "engine_total": 1000.0 * (t2 - t0),
        },
    )
