"""The field evidence: what the field risk model (`models.field`) is given per
occupant, built as a request builds it (also used by the offline fits)."""

from __future__ import annotations

from dataclasses import dataclass

from models.assumptions import Assumption, AssumptionCode
from models.field.features import FieldInputs, field_inputs
from models.field.measurement import DeltaVSource, SourcedRiskInputs
from models.field.model import FieldModel, FieldPrediction
from models.field.risk_children import Restraint
from models.field.risk_features import MODEL_YEAR_CLAMP, AirbagCode, RiskInputs, SeatSide
from models.field.risk_model import RiskModel, RiskPrediction
from models.impact_mode import ImpactClassification, classify_impact, occupant_side
from models.notification import (
    AirbagState,
    ChildRestraint,
    CrashNotification,
    DriveSide,
    Occupant,
    Pulse,
    Seat,
    Sex,
    SummaryPulse,
)
from models.pulse import ProcessedPulse, process_pulse
from models.triage.decision import _baseline_decision
from models.triage.loading import EngineModels
from models.triage.occupant_model import _lpm_occupant, _LpmAnswer
from models.triage.result import TriageDecision, UnknownVehicleModel

__all__ = [
    "OccupantEvidence",
    "notification_field_inputs",
    "notification_risk_inputs",
    "occupant_evidence",
    "risk_inputs",
]


def _field_assumptions(
    index: int, occupant: Occupant, prediction: FieldPrediction, field_model: FieldModel
) -> list[Assumption]:
    out = []
    imp = field_model.imputation
    if "age_years" in prediction.imputed:
        out.append(
            Assumption(
                AssumptionCode.AGE_IMPUTED,
                f"occupants[{index}]: age unknown: the field model uses the calibration "
                f"median, {imp.age_years:g} years",
                index,
            )
        )
    if "bmi" in prediction.imputed:
        out.append(
            Assumption(
                AssumptionCode.BMI_IMPUTED,
                f"occupants[{index}]: stature or mass unknown: the field model uses the "
                f"calibration median body mass index, {imp.bmi:.1f} kg/m2",
                index,
            )
        )
    if prediction.extrapolated:
        out.append(
            Assumption(
                AssumptionCode.DELTA_V_EXTRAPOLATED,
                f"occupants[{index}]: delta-V above the field model's calibration data "
                f"(largest {field_model.delta_v_max_kmh:.0f} km/h): its probability is "
                "extrapolated",
                index,
            )
        )
    if not occupant.seat.front_row:
        out.append(
            Assumption(
                AssumptionCode.SECOND_ROW_SEAT,
                f"occupants[{index}]: {occupant.seat.value} seat: the field model decides (its "
                "data have no seat column); the occupant models are of the front row",
                index,
            )
        )
    return out


@dataclass(frozen=True)
class OccupantEvidence:
    """What the engine knows of one occupant before the field model decides.

    Attributes
    ----------
    index : int
    impact : ImpactClassification
    field_inputs : FieldInputs
        The field model's inputs.
    baseline : TriageDecision
        The statistical baseline's decision.
    occupant_model : _LpmAnswer or None
        The occupant model's answer (None out of coverage or when it failed).
    """

    index: int
    impact: ImpactClassification
    field_inputs: FieldInputs
    baseline: TriageDecision
    occupant_model: _LpmAnswer | None


def _occupant_evidence(
    index: int,
    occupant: Occupant,
    notification: CrashNotification,
    pulse: ProcessedPulse,
    models: EngineModels,
    assumptions: list[Assumption],
    occupant_models: bool = True,
) -> OccupantEvidence:
    impact = classify_impact(pulse.pdof_deg, occupant.seat, notification.drive_side)
    answer: _LpmAnswer | None = None
    if not occupant.belt_known:
        assumptions.append(
            Assumption(
                AssumptionCode.BELT_UNKNOWN,
                f"occupants[{index}]: belt use unknown: the field risk model integrates over "
                "belt use at this seat; the occupant models and the baseline take unbelted",
                index,
            )
        )
    if occupant.child and occupant.seat.front_row:
        # the occupant models are adult dummies: no explanation of a child
        assumptions.append(
            Assumption(
                AssumptionCode.CHILD_WITHOUT_OCCUPANT_MODEL,
                f"occupants[{index}]: a child (age under 16 or in a child seat): the occupant "
                "models are adult dummies and give no explanation; the field risk model decides",
                index,
            )
        )
    elif impact.in_lpm_coverage and not occupant_models:
        assumptions.append(
            Assumption(
                AssumptionCode.OCCUPANT_MODELS_NOT_RUN,
                f"occupants[{index}]: decision only: the occupant models were not run (no "
                "explanation); the field risk model decides as in a full run",
                index,
            )
        )
    elif impact.in_lpm_coverage:
        params = models.parameter_sets[notification.vehicle_model]
        answer = _lpm_occupant(index, occupant, impact, pulse, params, models, assumptions)
    elif occupant.seat.front_row:  # other seats: said with the field model's assumptions
        assumptions.append(
            Assumption(
                AssumptionCode.OUTSIDE_OCCUPANT_MODEL_COVERAGE,
                f"occupants[{index}]: PDOF {impact.pdof_deg:.0f} deg is outside every occupant "
                "model's coverage; the field model decides without an occupant-model explanation",
                index,
            )
        )
    return OccupantEvidence(
        index=index,
        impact=impact,
        field_inputs=_field_inputs(occupant, notification, pulse, impact),
        baseline=_baseline_decision(models, occupant, pulse, impact),
        occupant_model=answer,
    )


def _field_inputs(
    occupant: Occupant,
    notification: CrashNotification,
    pulse: ProcessedPulse,
    impact: ImpactClassification,
) -> FieldInputs:
    """The field model's inputs of one occupant (a request and the offline fit alike)."""
    return field_inputs(
        occupant,
        pulse.delta_v_kmh,
        impact.mode,
        multiple_impacts=notification.multiple_impacts,
        rollover=notification.rollover,
    )


def notification_field_inputs(notification: CrashNotification) -> list[FieldInputs]:
    """The field model's inputs for every occupant, as :func:`triage` builds them.

    The pulse is processed and each occupant's impact classified exactly as in a
    request; no occupant model runs (the offline fit and its tests use this).
    """
    pulse = process_pulse(notification.pulse)
    out = []
    for occupant in notification.occupants:
        impact = classify_impact(pulse.pdof_deg, occupant.seat, notification.drive_side)
        out.append(_field_inputs(occupant, notification, pulse, impact))
    return out


def occupant_evidence(
    notification: CrashNotification, models: EngineModels
) -> tuple[list[OccupantEvidence], list[Assumption]]:
    """Every occupant's evidence without a decision (offline fits and checks).

    Needs no field model: the offline fit uses it to compute the field model's
    inputs exactly as :func:`triage` does, and the occupant models' answers.

    Returns
    -------
    evidence : list of OccupantEvidence
        One per occupant, in order.
    assumptions : list of str
    """
    if notification.vehicle_model not in models.vehicle_models:
        raise UnknownVehicleModel(f"unknown vehicle model {notification.vehicle_model!r}")
    pulse = process_pulse(notification.pulse)
    assumptions: list[Assumption] = []
    out = [
        _occupant_evidence(i, o, notification, pulse, models, assumptions)
        for i, o in enumerate(notification.occupants)
    ]
    return out, assumptions


_AIRBAG_CODES = {
    AirbagState.DEPLOYED: AirbagCode.DEPLOYED,
    AirbagState.NOT_DEPLOYED: AirbagCode.NOT_DEPLOYED,
    AirbagState.ABSENT: AirbagCode.NONE,
}


def risk_inputs(
    occupant: Occupant, notification: CrashNotification, pulse: ProcessedPulse
) -> RiskInputs:
    """The field risk models' inputs of one occupant (:mod:`models.field.risk_features`).

    The direction of the delta-V is the processed pulse's PDOF; the seat's side
    is the vehicle's side it sits on (the driver's is the drive side); a
    frontal airbag reported absent is the data's "none". The impact count is
    the notification's (None where not sent: the model resolves it from
    ``multiple_impacts``).
    """
    side = occupant_side(occupant.seat, notification.drive_side)
    return SourcedRiskInputs(
        delta_v_kmh=float(pulse.delta_v_kmh),
        pdof_deg=float(pulse.pdof_deg),
        seat_row=occupant.seat.row,
        seat_side=(
            SeatSide.MIDDLE
            if side is None
            else SeatSide.LEFT
            if side is DriveSide.LEFT
            else SeatSide.RIGHT
        ),
        driver=occupant.seat is Seat.DRIVER,
        belted=bool(occupant.belted),
        frontal_airbag=_AIRBAG_CODES[occupant.frontal_airbag],
        rollover=bool(notification.rollover),
        multiple_impacts=bool(notification.multiple_impacts),
        quarter_turns=notification.rollover_quarter_turns,
        age_years=occupant.age_years,
        female=None if occupant.sex is None else occupant.sex is Sex.FEMALE,
        stature_cm=occupant.stature_cm,
        mass_kg=occupant.mass_kg,
        model_year=notification.model_year,
        impact_count=notification.impact_count,
        restraint=restraint_state(occupant),
        delta_v_source=delta_v_source(notification.pulse),
    )


def delta_v_source(pulse: Pulse) -> DeltaVSource:
    """Where a notification's delta-V comes from: a summary says it (measured by default,
    what a telematics unit sends); an acceleration or EDR delta-V record is measured."""
    if isinstance(pulse, SummaryPulse):
        return DeltaVSource(pulse.delta_v_source)
    return DeltaVSource.MEASURED


def restraint_state(occupant: Occupant) -> Restraint | None:
    """The field data's restraint state of an occupant (None: unknown, integrated over).

    A child seat of any kind is the data's "child seat"; a child's lap-shoulder
    belt is belted; otherwise the belt as sensed, unknown where not monitored.
    """
    cr = occupant.child_restraint
    if cr is not None:
        if cr.child_seat:
            return Restraint.CHILD_SEAT
        return Restraint.BELTED if cr is ChildRestraint.LAP_SHOULDER_BELT else Restraint.NONE
    if not occupant.belt_known:
        return None
    return Restraint.BELTED if occupant.belted else Restraint.NONE


def notification_risk_inputs(notification: CrashNotification) -> list[RiskInputs]:
    """The field risk models' inputs for every occupant, as :func:`triage` builds them."""
    pulse = process_pulse(notification.pulse)
    return [risk_inputs(o, notification, pulse) for o in notification.occupants]


def _risk_assumptions(
    index: int,
    occupant: Occupant,
    inputs: RiskInputs,
    prediction: RiskPrediction,
    model: RiskModel,
) -> list[Assumption]:
    """What the field risk models assumed for one occupant, each named."""
    imp = model.imputation
    who = f"occupants[{index}]"
    texts = {
        "age_years": (
            AssumptionCode.AGE_IMPUTED,
            f"{who}: age unknown: the field risk models use their data's median, "
            f"{imp.age_years:g} years",
        ),
        "female": (
            AssumptionCode.SEX_IMPUTED,
            f"{who}: sex unknown: the field risk models use their data's share of women, "
            f"{imp.female:.2f}",
        ),
        "stature_cm": (
            AssumptionCode.STATURE_MASS_IMPUTED,
            f"{who}: stature unknown: the field risk models use their data's median, "
            f"{imp.stature_cm:g} cm",
        ),
        "mass_kg": (
            AssumptionCode.STATURE_MASS_IMPUTED,
            f"{who}: mass unknown: the field risk models use their data's median, "
            f"{imp.mass_kg:g} kg",
        ),
        "model_year": (
            AssumptionCode.MODEL_YEAR_IMPUTED,
            f"{who}: vehicle model year unknown: the field risk models use "
            f"{imp.model_year:g} (their latest accident year's median)",
        ),
        "quarter_turns": (
            AssumptionCode.QUARTER_TURNS_IMPUTED,
            f"{who}: rollover without quarter turns: the field risk models use "
            f"{imp.quarter_turns:g} (the median of rolled vehicles in their data)",
        ),
        "impact_count": (
            AssumptionCode.IMPACT_COUNT_IMPUTED,
            f"{who}: multiple impacts without their count: the field risk models use "
            f"{model.impact_count_imputed or 0.0:g} (the median of vehicles with two or more "
            "in their data)",
        ),
    }
    out = [Assumption(*texts[name], index) for name in prediction.imputed]
    if "delta_v_kmh" in prediction.integrated and model.measurement is not None:
        out.append(
            Assumption(
                AssumptionCode.DELTA_V_MEASURED,
                f"{who}: delta-V measured by the vehicle ({inputs.delta_v_kmh:.1f} km/h): the "
                "field risk models learned reconstructed delta-V, which reads lower; the "
                "probability is the average over the reconstructed delta-V the measurement "
                f"model ({model.measurement.label}) gives for it",
                index,
            )
        )
    if any(k != "delta_v_kmh" for k in prediction.integrated):
        words = {
            "age_years": "age",
            "female": "sex",
            "stature_cm": "stature",
            "mass_kg": "mass",
            "restraint": "belt use",
        }
        named = ", ".join(words[k] for k in prediction.integrated if k in words)
        spread = prediction.unknown_inputs_range95
        out.append(
            Assumption(
                AssumptionCode.INPUTS_INTEGRATED,
                f"{who}: {named} unknown: the probability is the average over such occupants "
                f"of this seat in the field data (the spread over them "
                + (f"{spread[0]:.4f}-{spread[1]:.4f}" if spread else "not computed")
                + ", in `unknown_inputs_range95`)",
                index,
            )
        )
    covers_children = model.donors is not None
    if covers_children and occupant.child and "regions_from" in model.document:
        out.append(
            Assumption(
                AssumptionCode.CHILD_REGION_RISK_EXTRAPOLATED,
                f"{who}: a child: the region risks are the adults' models' "
                f"({model.document['regions_from']['version']}), extrapolated",
                index,
            )
        )
    if occupant.age_years is not None and occupant.age_years < 16.0 and not covers_children:
        out.append(
            Assumption(
                AssumptionCode.OUTSIDE_FIELD_POPULATION,
                f"{who}: age {occupant.age_years:g}: the field risk models' data are of "
                "occupants 16 or older; the probability is extrapolated",
                index,
            )
        )
    year = inputs.model_year
    lo_year, hi_year = MODEL_YEAR_CLAMP
    if year is not None and not lo_year <= year <= hi_year and "model_year" in model.used_inputs:
        out.append(
            Assumption(
                AssumptionCode.MODEL_YEAR_BEYOND_DATA,
                f"{who}: model year {year} is outside the field risk models' data "
                f"({lo_year:.0f}-{hi_year:.0f}): they take {min(max(year, lo_year), hi_year):.0f}",
                index,
            )
        )
    if (
        model.measurement is None
        and isinstance(inputs, SourcedRiskInputs)
        and inputs.delta_v_source is DeltaVSource.MEASURED
    ):
        out.append(
            Assumption(
                AssumptionCode.DELTA_V_READ_AS_RECONSTRUCTED,
                f"{who}: delta-V measured by the vehicle, read as reconstructed by "
                f"{model.name}@{model.version} (no measurement model): the probability errs high",
                index,
            )
        )
    if prediction.extrapolated:
        out.append(
            Assumption(
                AssumptionCode.DELTA_V_EXTRAPOLATED,
                f"{who}: delta-V above the field risk models' data (largest "
                f"{model.delta_v_max_kmh:.0f} km/h): the probability is extrapolated",
                index,
            )
        )
    if not occupant.seat.front_row:
        out.append(
            Assumption(
                AssumptionCode.SEAT_WITHOUT_OCCUPANT_MODEL,
                f"{who}: {occupant.seat.value} seat: the field risk model decides (its data "
                "hold this seat row and side); no occupant model is of this seat",
                index,
            )
        )
    return out
