"""The wire out: the response models of ``/v1/cases`` and the conversion of an engine
result into them (one place, used by the API, the pages and the command line)."""

from __future__ import annotations

import dataclasses
from datetime import datetime
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    model_validator,
)

from models import notification as engine
from models.assumptions import DESCRIPTIONS, Assumption, AssumptionCode
from models.field.features import FieldMode
from models.impact_mode import ImpactMode
from models.triage import (
    HIGH_RISK_THRESHOLD,
    IntervalMethod,
    Method,
    OccupantTriage,
    Tier,
    TriageDecision,
    TriageResult,
    tier_of,
)
from service.cases.examples import EXAMPLE_CASE_LIST, EXAMPLE_CASE_RESULT, EXAMPLE_STORED_CASE
from service.cases.notification import SourceFormat

__all__ = [
    "OutModel",
    "TriageOut",
    "IssOut",
    "HaversineOut",
    "PulseOut",
    "SensorInputsOut",
    "OccupantOut",
    "RegionRiskOut",
    "VehicleRiskOut",
    "AssumptionOut",
    "ModelVersionOut",
    "CaseResult",
    "StoredCase",
    "CaseSummary",
    "CaseList",
    "TIER_WORDS",
    "derive_tiers",
    "to_case_result",
]


#: What each tier means, for the descriptions of the wire fields.
TIER_WORDS = (
    "`high`: `probability` at or above `high_threshold` (default 0.20, the CDC 2008 expert "
    "panel's 'high risk of severe injury') and `threshold`: the highest-level trauma center "
    "in reach; `moderate`: at or above `threshold` (the operating point's, `iss15_plus`), "
    "below `high_threshold`: vehicle telemetry consistent with severe injury, a moderate-risk "
    "criterion of the 2021 field triage guideline (consider a trauma center, not necessarily "
    "the highest level); `none`: below `threshold`, no telemetry indication."
)


class OutModel(BaseModel):
    """Base of the response models."""

    model_config = ConfigDict(frozen=True)


class TriageOut(OutModel):
    """A trauma-center decision on a probability of serious injury."""

    iss15_plus: bool = Field(
        description="True: `probability` >= `threshold`, a telemetry indication of ISS 15+ "
        "(`tier` `moderate` or `high`; `tier` says which center); or flagged whatever the "
        "probability when the crash pulse record looks corrupt (`pulse_looks_corrupt`, at "
        "least the moderate tier)."
    )
    probability: float = Field(
        ge=0,
        le=1,
        description="Probability of `outcome`. The decision (`triage` of a case or occupant) is "
        "the field risk model's P(ISS 15+) of such occupants in US towaway crashes, fitted on "
        "NASS-CDS 1997-2014 and calibrated with its national weights (field model 2.0.0, kept "
        "for recalls, gave P(MAIS 3+), a broader stand-in). Second opinions: the occupant "
        "models' P(ISS >= 15) attributable to the crash loads (`occupant_model`), and the "
        "statistical baseline's police-reported A+K risk (`baseline`).",
    )
    probability_ci95: tuple[float, float] = Field(
        description="95% interval of `probability` [low, high]; it holds `probability`."
    )
    threshold: float = Field(description="Decision threshold on `probability`.")
    recommendation: str = Field(
        description="What to do with the patient, in words: the tier's (field decision); for "
        "a second opinion, those of a telemetry indication or of none."
    )
    outcome: str = Field(
        description="What `probability` is a probability of: `ISS15+` (field risk model "
        "3.0.0 on, and occupant models), `MAIS3+` (field model 2.0.0, recalls), `police_A+K` "
        "(statistical baseline).",
        examples=["ISS15+"],
    )
    model: str = Field(description="The model that gave it.", examples=["field_iss15@3.2.0"])
    operating_point: str | None = Field(
        default=None,
        description="Named operating point of the field model whose threshold decided "
        "(`sens85`, the default: finds >= 85 % of ISS 15+ occupants held out; `acs_cot`: "
        "under-triage <= 5 %; field model 2.0.0: `sens80_per_mode`, `sens80`, `bahouth`); "
        "null when `AACN_TRIAGE_THRESHOLD` overrides it or for second opinions.",
    )
    unknown_inputs_range95: tuple[float, float] | None = Field(
        default=None,
        description="Field risk model: where some occupant inputs were unknown (age, sex, "
        "stature, mass, belt use), `probability` is the average over such occupants of the "
        "same seat in the field data, and this is the spread of the probability over them "
        "(2.5 and 97.5 percentiles) [low, high]. Not a confidence interval: that is "
        "`probability_ci95`. Null when every input was known, and for second opinions.",
    )
    knowledge: str | None = Field(
        default=None,
        description="Field risk model 3.3.0 on: what was known of the occupant, which the "
        "operating point's threshold was set for so that its promise holds for it: `adult` "
        "(age given, 16 or older), `child` (age given, under 16), `age_unknown`. The "
        "`threshold` is that one. Null for older models and second opinions.",
        examples=["age_unknown"],
    )
    tier: Tier | None = Field(
        default=None,
        description="Risk tier of the field decision (`triage` of a case or occupant): "
        + TIER_WORDS
        + " Null for the second opinions (`occupant_model`, `baseline`): tiers belong to the "
        "field decision. A case stored before tiers is read back with the tier of its stored "
        "probability and threshold, `high_threshold` at its default.",
        examples=["moderate"],
    )
    high_threshold: float | None = Field(
        default=None,
        description="The high-risk threshold the tier was set with (`AACN_HIGH_RISK_THRESHOLD`, "
        "stored with the case); null for second opinions.",
        examples=[0.2],
    )


class IssOut(OutModel):
    """Injury Severity Score estimate."""

    estimate: int = Field(ge=0, le=75, description="ISS point estimate (Baker rule).")
    ci95: tuple[float, float] | None = Field(
        default=None, description="95% interval of ISS, when the engine provides it."
    )


class HaversineOut(OutModel):
    """Haversine fit a(t) = A sin^2(pi t / T) of the resultant pulse."""

    amplitude_g: float = Field(description="A, g.")
    duration_ms: float = Field(description="T, ms.")
    r_squared: float = Field(description="Coefficient of determination of the fit.")


class PulseOut(OutModel):
    """What the engine derived from the pulse."""

    delta_v_kmh: float = Field(description="Resultant delta-V, km/h.")
    delta_v_longitudinal_kmh: float = Field(description="x delta-V, km/h.")
    delta_v_lateral_kmh: float = Field(description="y delta-V, km/h.")
    pdof_deg: float = Field(description="Principal direction of force, deg clockwise.")
    peak_accel_g: float = Field(description="Peak resultant acceleration, g.")
    duration_ms: float = Field(description="Pulse duration, ms.")
    haversine: HaversineOut
    delta_v_source: Literal["measured", "reconstructed"] = Field(
        default="measured",
        description="Where the delta-V came from: `measured` by the vehicle (EDR or telematics; "
        "acceleration and EDR delta-V pulses, and a summary unless it says otherwise) or "
        "`reconstructed` from crush (as the field data's). A case stored before the source "
        "was recorded reads `measured`: its notification was a vehicle's, read by the field "
        "model of its day as if reconstructed (`cases rescore` lists the advice that changes).",
    )


class SensorInputsOut(OutModel):
    """The posture and seat track an occupant-model answer was computed at."""

    posture_deg: float = Field(
        description="Lumbar flexion of the direct run, deg (after the evidence was resolved "
        "and the value clamped to the models' range)."
    )
    posture_sd_deg: float = Field(description="Posture SD propagated into the intervals, deg.")
    seat_track_mm: float = Field(
        description="Seat track of the direct run, mm forward of mid track (resolved, clamped)."
    )
    seat_track_sd_mm: float = Field(description="Seat track SD propagated into the intervals, mm.")


class RegionRiskOut(OutModel):
    """P(injury of AIS `ais_level` or more) in one body region of one occupant."""

    probability: float = Field(
        ge=0,
        le=1,
        description="Field-calibrated probability of an AIS `ais_level`+ injury in the region, "
        "of such occupants in US towaway crashes (NASS-CDS 1997-2014, national weights).",
        examples=[0.031],
    )
    probability_ci95: tuple[float, float] = Field(
        description="95% interval [low, high] (bootstrap refits by crash); it holds `probability`.",
        examples=[[0.024, 0.040]],
    )
    ais_level: int = Field(
        ge=2,
        le=3,
        description="The AIS level of the outcome: 3 (serious), or 2 where AIS 3+ is too rare in "
        "the region to fit (face, neck; model card).",
        examples=[3],
    )


class VehicleRiskOut(OutModel):
    """P(anyone in the vehicle ISS 15+): the case-level answer of the field risk model."""

    probability: float = Field(
        ge=0,
        le=1,
        description="Probability that at least one occupant of the vehicle is ISS 15+ (the unit "
        "of OnStar's published injury severity prediction).",
        examples=[0.012],
    )
    probability_ci95: tuple[float, float] = Field(
        description="95% interval [low, high] (bootstrap refits by crash).",
        examples=[[0.009, 0.016]],
    )
    heldout_auc: float = Field(
        description="Its AUC on NASS-CDS vehicles held out by crash (model card).",
        examples=[0.88],
    )
    outcome: str = Field(description="`anyone ISS15+`.", examples=["anyone ISS15+"])
    model: str = Field(description="The model that gave it.", examples=["field_iss15@3.2.0"])
    tier: Tier | None = Field(
        default=None,
        description="The vehicle's own risk tier, from its own probability against the "
        "occupants' `threshold` and `high_threshold` (the vehicle is the unit of the CDC "
        "panel's 20 % and of OnStar's injury severity prediction): " + TIER_WORDS,
        examples=["moderate"],
    )
    threshold: float | None = Field(
        default=None, description="The operating threshold `tier` was set with.", examples=[0.0177]
    )
    high_threshold: float | None = Field(
        default=None, description="The high-risk threshold `tier` was set with.", examples=[0.2]
    )


class OccupantOut(OutModel):
    """The triage of one occupant."""

    seat: engine.Seat
    body: engine.Body = Field(description="Dummy class the engine used.")
    impact_mode: ImpactMode = Field(
        description="The occupant's impact mode: the nearest of the four occupant models' axes "
        "to the PDOF, for this seat."
    )
    field_mode: FieldMode = Field(
        description="The crash mode the field model used: `rollover` when reported, else "
        "`impact_mode`."
    )
    impact_angle_deg: float = Field(description="PDOF relative to the mode's axis, deg.")
    in_lpm_coverage: bool = Field(description="The PDOF lies inside an occupant model's range.")
    method: Method = Field(
        description="How the occupant was answered. The decision is always the field model's; "
        "`lpm`: an occupant model ran and explains it (measures, region AIS, ISS, its own "
        "decision in `occupant_model`); `field`: no occupant model applies (PDOF between the "
        "models' ranges, a second-row seat) or it failed."
    )
    iss: IssOut | None = Field(default=None, description="ISS where the engine provides it.")
    region_ais: dict[str, int] | None = Field(
        default=None, description="AIS per ISS body region, where the engine provides it."
    )
    measures: dict[str, float] | None = Field(
        default=None,
        description="Injury measures from the direct occupant-model run, where computed: "
        "hic15, nij, chest_deflection_mm, chest_vc_m_s, chest_a3ms_g, chest_cti, "
        "abdomen_vc_m_s.",
    )
    measures_ci95: dict[str, tuple[float, float]] | None = Field(
        default=None,
        description="95% interval of each measure under sensor uncertainty; for "
        "`pce_bootstrap`, it includes the surrogate's own error (held-out calibrated margin).",
    )
    interval_method: IntervalMethod | None = Field(
        default=None,
        description="Where the occupant model's 95% intervals come from: `pce_bootstrap` "
        "(surrogates, bootstrap replicates, widened by margins calibrated on held-out "
        "occupant-model runs) or `lpm_sensor_box` (direct runs over the +/-1.96 SD sensor "
        "box); null without an occupant model. The decided probability's interval is the field "
        "model's (bootstrap refits).",
    )
    point_outside_interval: bool = Field(
        default=False,
        description="The direct occupant-model estimate lies outside the surrogate interval.",
    )
    probability_uncorrected: float | None = Field(
        default=None,
        ge=0,
        le=1,
        description="Occupant models only: P(ISS >= 15) from the published risk curves before "
        "the zero-load correction (the mean over the spread when posture or seat position was "
        "not sensed). `occupant_model.probability` = (this - probability_zero_load) / "
        "(1 - probability_zero_load), clipped to [0, 1] (Abbott's formula).",
    )
    probability_zero_load: float | None = Field(
        default=None,
        ge=0,
        le=1,
        description="Occupant models only: the same occupant's P(ISS >= 15) from the risk "
        "curves with every measure at zero (about 0.054: the curves' floor, not crash risk).",
    )
    sensor_inputs: SensorInputsOut | None = Field(
        default=None,
        description="Occupant models only: the posture and seat track the answer was computed "
        "at, with the SDs its intervals propagate (a reading and its sensor SD, or the range "
        "the evidence allows; see `assumptions`).",
    )
    region_risk: dict[str, RegionRiskOut] | None = Field(
        default=None,
        description="Field-calibrated risk of a serious injury in each body region (`head`, "
        "`face`, `neck`, `thorax`, `abdomen`, `spine`, `upper_extremity`, `lower_extremity`), "
        "fitted on real injuries (NASS-CDS 1997-2014); `ais_level` says AIS 3+ or 2+. Null "
        "with field model 2.0.0 (recalls).",
        examples=[
            {
                "head": {"probability": 0.031, "probability_ci95": [0.024, 0.040], "ais_level": 3},
                "neck": {"probability": 0.002, "probability_ci95": [0.001, 0.004], "ais_level": 2},
            }
        ],
    )
    triage: TriageOut = Field(
        description="The decision: the field risk model's P(ISS 15+) at its operating point."
    )
    occupant_model: TriageOut | None = Field(
        default=None,
        description="The occupant models' own decision on their P(ISS >= 15) attributable to "
        "the crash loads, at Bahouth's 0.10 frontal/rear, 0.05 side (second opinion, the "
        "physics explanation); null without an occupant model.",
    )
    baseline: TriageOut = Field(
        description="The statistical baseline's answer (second opinion; outcome is "
        "police-reported serious injury, a proxy for ISS15+)."
    )


class AssumptionOut(OutModel):
    """One assumption of an answer: a stable code, the occupant, the words."""

    code: AssumptionCode = Field(
        description="Stable code (act on it; the codes and their meaning: "
        + "; ".join(f"`{c.value}`: {d}" for c, d in DESCRIPTIONS.items())
        + ")."
    )
    message: str = Field(description="The assumption in words, with its numbers.")
    occupant: int | None = Field(
        default=None, description="Index of the occupant it concerns; null for the whole crash."
    )


class ModelVersionOut(OutModel):
    """Version and checksum of one model artifact."""

    version: str = Field(description="Version of the model artifact.")
    sha256: str = Field(description="SHA-256 of the artifact's bytes.")


class CaseResult(OutModel):
    """The answer to one notification."""

    model_config = ConfigDict(frozen=True, json_schema_extra={"examples": [EXAMPLE_CASE_RESULT]})

    case_id: str | None = Field(description="Id of the stored case (null from the CLI).")
    event_id: str = Field(description="The sender's event id.")
    received_at: datetime = Field(description="When the service received the notification.")
    triage: TriageOut = Field(description="The case-level decision: the worst occupant's.")
    vehicle: VehicleRiskOut | None = Field(
        default=None,
        description="P(anyone in the vehicle ISS 15+) with its held-out AUC; null with field "
        "model 2.0.0 (recalls).",
    )
    occupants: list[OccupantOut] = Field(description="One result per occupant, in input order.")
    pulse: PulseOut
    assumptions: list[AssumptionOut] = Field(
        default_factory=list, description="What the engine assumed or clamped."
    )
    engine_version: str = Field(description="Version of the engine code.")
    models: dict[str, ModelVersionOut] = Field(description="Every model used: version, sha256.")
    timings_ms: dict[str, float] = Field(description="Time spent per step, ms.")
    stored: bool = Field(
        default=True,
        description="The case is committed to the audit store (201, and replays of a stored "
        "case). False with `spooled`: the store could not take it (database down, read-only or "
        "full), so the case was recorded durably in the service's local spool and answered "
        "with 202; it is stored, under this `case_id`, once the store returns.",
    )
    spooled: bool = Field(
        default=False,
        description="The case is recorded in the local spool, waiting to be stored (202).",
    )

    @model_validator(mode="before")
    @classmethod
    def _tiers_of_a_stored_result(cls, data: Any) -> Any:
        """A result stored before tiers is read with the tiers :func:`derive_tiers` gives."""
        return derive_tiers(data) if isinstance(data, dict) else data


class StoredCase(OutModel):
    """A stored case, as the audit trail holds it."""

    model_config = ConfigDict(frozen=True, json_schema_extra={"examples": [EXAMPLE_STORED_CASE]})

    case_id: str = Field(description="Id of the case.")
    event_id: str = Field(description="The sender's event id.")
    client_name: str = Field(description="Name of the API key that submitted it.")
    received_at: datetime = Field(description="When the notification was received.")
    stored_at: datetime = Field(description="When the case was committed.")
    request_sha256: str = Field(description="SHA-256 of the canonical JSON of the notification.")
    notification: dict[str, Any] = Field(
        description="The notification as received; for a VEDS document, the JSON notification "
        "it was mapped to (the XML itself is `source_document`)."
    )
    result: CaseResult = Field(description="The result exactly as it was answered.")
    models: dict[str, ModelVersionOut] = Field(description="Every model used: version, sha256.")
    source_format: SourceFormat = Field(
        default="json",
        description="How the notification came in: `json` (this contract) or `veds` "
        "(`application/EmergencyCallData.VEDS+xml`, RFC 8148).",
    )
    source_document: str | None = Field(
        default=None,
        description="The VEDS XML document exactly as received (null for JSON).",
    )
    source_mapping: dict[str, Any] | None = Field(
        default=None,
        description="For VEDS: which elements were mapped to which fields, what was assumed "
        "(assumption codes) and what was not used (null for JSON).",
    )
    tiers_derived: bool = Field(
        default=False,
        description="True: the case was stored before risk tiers; `result` shows the tiers of "
        "its stored probabilities and thresholds, with the high-risk threshold at its default "
        "(0.20). The stored record itself is never altered.",
    )


class CaseSummary(OutModel):
    """One row of the case list."""

    case_id: str = Field(description="Id of the case.")
    event_id: str = Field(description="The sender's event id.")
    client_name: str = Field(description="Name of the API key that submitted it.")
    received_at: datetime = Field(description="When the notification was received.")
    iss15_plus: bool = Field(description="Case-level decision.")
    tier: Tier = Field(
        description="Case-level risk tier (its worst occupant's; derived for a case stored "
        "before tiers).",
        examples=["moderate"],
    )
    probability: float = Field(description="Case-level probability.")
    impact_modes: list[str] = Field(description="Impact mode of each occupant.")


class CaseList(OutModel):
    """A page of cases, newest first."""

    model_config = ConfigDict(frozen=True, json_schema_extra={"examples": [EXAMPLE_CASE_LIST]})

    items: list[CaseSummary] = Field(description="The cases of this page.")
    next_cursor: str | None = Field(description="Pass as `cursor` for the next page; null at end.")


def _triage_out(d: TriageDecision) -> TriageOut:
    return TriageOut(
        iss15_plus=d.iss15_plus,
        probability=d.probability,
        probability_ci95=d.probability_ci95,
        threshold=d.threshold,
        recommendation=d.recommendation,
        outcome=d.outcome,
        model=d.model,
        operating_point=d.operating_point,
        unknown_inputs_range95=d.unknown_inputs_range95,
        knowledge=d.knowledge,
        tier=d.tier,
        high_threshold=d.high_threshold,
    )


def _derived(decision: Any, threshold: Any, high_threshold: float) -> Any:
    """`decision` (a stored field decision or vehicle answer) with a tier where it has none."""
    if not isinstance(decision, dict) or "tier" in decision:
        return decision
    p = decision.get("probability")
    t = decision.get("threshold", threshold)
    if not isinstance(p, int | float) or not isinstance(t, int | float):
        return decision  # not a decision: validation says what is wrong with it
    high = decision.get("high_threshold") or high_threshold
    return {
        **decision,
        "tier": tier_of(float(p), float(t), float(high)).value,
        "threshold": t,
        "high_threshold": high,
    }


def derive_tiers(result: dict[str, Any]) -> dict[str, Any]:
    """A stored result with the tiers of its field decisions filled in where it has none.

    A case stored before tiers carries its probabilities and operating thresholds;
    its tiers are those they give (:func:`models.triage.tier_of`), with the high-risk
    threshold at its default (:data:`models.triage.HIGH_RISK_THRESHOLD`) where none
    was stored. The case's decision, each occupant's ``triage`` and the vehicle answer
    (against the case's threshold) get one; second opinions never do. `result` itself
    is not changed (a new document is returned).
    """
    case = result.get("triage")
    if not isinstance(case, dict) or "tier" in case:
        return result
    out = dict(result)
    out["triage"] = _derived(case, None, HIGH_RISK_THRESHOLD)
    occupants = result.get("occupants")
    if isinstance(occupants, list):
        out["occupants"] = [
            {**o, "triage": _derived(o.get("triage"), None, HIGH_RISK_THRESHOLD)}
            if isinstance(o, dict)
            else o
            for o in occupants
        ]
    if isinstance(result.get("vehicle"), dict):
        out["vehicle"] = _derived(result["vehicle"], case.get("threshold"), HIGH_RISK_THRESHOLD)
    return out


def _occupant_out(o: OccupantTriage) -> OccupantOut:
    return OccupantOut(
        seat=o.seat,
        body=o.body,
        impact_mode=o.impact.mode,
        field_mode=o.field_mode,
        impact_angle_deg=o.impact.angle_from_axis_deg,
        in_lpm_coverage=o.impact.in_lpm_coverage,
        method=o.method,
        iss=IssOut(estimate=o.iss.estimate, ci95=o.iss.ci95) if o.iss is not None else None,
        region_ais=dict(o.region_ais) if o.region_ais is not None else None,
        measures=dict(o.measures) if o.measures is not None else None,
        measures_ci95=dict(o.measures_ci95) if o.measures_ci95 is not None else None,
        interval_method=o.interval_method,
        point_outside_interval=o.point_outside_interval,
        probability_uncorrected=o.probability_uncorrected,
        probability_zero_load=o.probability_zero_load,
        sensor_inputs=(
            SensorInputsOut(**dataclasses.asdict(o.sensor_inputs))
            if o.sensor_inputs is not None
            else None
        ),
        region_risk=(
            {
                name: RegionRiskOut(
                    probability=r.probability, probability_ci95=r.ci95, ais_level=r.ais_level
                )
                for name, r in o.region_risk.items()
            }
            if o.region_risk is not None
            else None
        ),
        triage=_triage_out(o.triage),
        occupant_model=_triage_out(o.occupant_model) if o.occupant_model is not None else None,
        baseline=_triage_out(o.baseline),
    )


def to_case_result(
    result: TriageResult,
    *,
    case_id: str | None,
    received_at: datetime,
    extra_assumptions: list[Assumption] | None = None,
) -> CaseResult:
    """The wire form of an engine result."""
    p = result.pulse
    return CaseResult(
        case_id=case_id,
        event_id=result.event_id,
        received_at=received_at,
        triage=_triage_out(result.triage),
        vehicle=(
            VehicleRiskOut(
                probability=result.vehicle.probability,
                probability_ci95=result.vehicle.probability_ci95,
                heldout_auc=result.vehicle.heldout_auc,
                outcome=result.vehicle.outcome,
                model=result.vehicle.model,
                tier=result.vehicle.tier,
                threshold=result.vehicle.threshold,
                high_threshold=result.vehicle.high_threshold,
            )
            if result.vehicle is not None
            else None
        ),
        occupants=[_occupant_out(o) for o in result.occupants],
        pulse=PulseOut(
            delta_v_source="reconstructed"
            if result.delta_v_source == "reconstructed"
            else "measured",
            delta_v_kmh=p.delta_v_kmh,
            delta_v_longitudinal_kmh=p.delta_v_longitudinal_kmh,
            delta_v_lateral_kmh=p.delta_v_lateral_kmh,
            pdof_deg=p.pdof_deg,
            peak_accel_g=p.peak_accel_g,
            duration_ms=p.duration_ms,
            haversine=HaversineOut(
                amplitude_g=p.haversine.amplitude_g,
                duration_ms=p.haversine.duration_ms,
                r_squared=p.haversine.r_squared,
            ),
        ),
        assumptions=[
            AssumptionOut(code=a.code, message=a.message, occupant=a.occupant)
            for a in (*(extra_assumptions or []), *result.assumptions)
        ],
        engine_version=result.engine_version,
        models={
            name: ModelVersionOut(version=m.version, sha256=m.sha256)
            for name, m in result.models.items()
        },
        timings_ms=dict(result.timings_ms),
    )
