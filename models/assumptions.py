"""What the engine assumed, clamped or could not do: each with a code an integrator can act on.

Every answer lists its assumptions as :class:`Assumption` (a stable
:class:`AssumptionCode`, the occupant it concerns, and a sentence for people).
The codes are part of the contract: a call center can, say, ask the caller for
an occupant's age when it sees ``age_imputed``, or show a rollover warning. The
table of codes is :data:`DESCRIPTIONS` (published in the OpenAPI document and
in ``docs/api.md``).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Final

__all__ = ["DESCRIPTIONS", "Assumption", "AssumptionCode"]


class AssumptionCode(StrEnum):
    """Stable codes of the engine's assumptions (see :data:`DESCRIPTIONS`)."""

    BODY_UNKNOWN = "body_unknown"
    BODY_FROM_STATURE_MASS = "body_from_stature_mass"
    ROLLOVER_REPORTED = "rollover_reported"
    MULTIPLE_IMPACTS_REPORTED = "multiple_impacts_reported"
    AGE_IMPUTED = "age_imputed"
    BMI_IMPUTED = "bmi_imputed"
    DELTA_V_EXTRAPOLATED = "delta_v_extrapolated"
    SECOND_ROW_SEAT = "second_row_seat"
    SEAT_WITHOUT_OCCUPANT_MODEL = "seat_without_occupant_model"
    SEX_IMPUTED = "sex_imputed"
    STATURE_MASS_IMPUTED = "stature_mass_imputed"
    MODEL_YEAR_IMPUTED = "model_year_imputed"
    MODEL_YEAR_BEYOND_DATA = "model_year_beyond_data"
    QUARTER_TURNS_IMPUTED = "quarter_turns_imputed"
    IMPACT_COUNT_IMPUTED = "impact_count_imputed"
    OUTSIDE_FIELD_POPULATION = "outside_field_population"
    INPUTS_INTEGRATED = "inputs_integrated"
    DELTA_V_MEASURED = "delta_v_measured"
    DELTA_V_READ_AS_RECONSTRUCTED = "delta_v_read_as_reconstructed"
    BELT_UNKNOWN = "belt_unknown"
    CHILD_WITHOUT_OCCUPANT_MODEL = "child_without_occupant_model"
    CHILD_REGION_RISK_EXTRAPOLATED = "child_region_risk_extrapolated"
    OUTSIDE_OCCUPANT_MODEL_COVERAGE = "outside_occupant_model_coverage"
    OCCUPANT_MODELS_NOT_RUN = "occupant_models_not_run"
    OCCUPANT_MODEL_FAILED = "occupant_model_failed"
    POSTURE_NOT_SENSED = "posture_not_sensed"
    SEAT_POSITION_NOT_SENSED = "seat_position_not_sensed"
    SEAT_TRACK_SWITCH = "seat_track_switch"
    POSTURE_CLAMPED = "posture_clamped"
    SEAT_TRACK_CLAMPED = "seat_track_clamped"
    SIDE_AIRBAG_NOT_REPORTED = "side_airbag_not_reported"
    SPREAD_MEAN = "occupant_model_spread_mean"
    SURROGATE_UNAVAILABLE = "surrogate_unavailable"
    OUTSIDE_SURROGATE_DESIGN = "outside_surrogate_design"
    POINT_OUTSIDE_INTERVAL = "point_outside_interval"
    OCCUPANT_MODEL_AIS_CAPPED = "occupant_model_ais_capped"
    SIDE_BEYOND_TESTED_SEVERITY = "side_beyond_tested_severity"
    PULSE_LOOKS_CORRUPT = "pulse_looks_corrupt"
    # what a VEDS document (RFC 8148) left open when it was mapped to a notification
    VEDS_CRASH_TIME_ASSUMED = "veds_crash_time_assumed"
    VEDS_MOST_SEVERE_PULSE = "veds_most_severe_pulse"
    VEDS_BELT_NOT_REPORTED = "veds_belt_not_reported"
    VEDS_AIRBAG_BY_CATEGORY = "veds_airbag_by_category"
    VEDS_AIRBAG_AMBIGUOUS = "veds_airbag_ambiguous"
    VEDS_FRONTAL_AIRBAG_NOT_REPORTED = "veds_frontal_airbag_not_reported"
    VEDS_VEHICLE_CLASS_ASSUMED = "veds_vehicle_class_assumed"
    VEDS_DRIVE_SIDE_ASSUMED = "veds_drive_side_assumed"
    VEDS_MODEL_YEAR_DROPPED = "veds_model_year_dropped"


#: What each code means and what an integrator may do about it.
DESCRIPTIONS: Final[dict[AssumptionCode, str]] = {
    AssumptionCode.BODY_UNKNOWN: (
        "No body class, stature or mass: the occupant models used the Hybrid III 50th "
        "male. Send stature and mass when known."
    ),
    AssumptionCode.BODY_FROM_STATURE_MASS: (
        "The body class was chosen from stature and mass (the nearer Hybrid III dummy)."
    ),
    AssumptionCode.ROLLOVER_REPORTED: (
        "A rollover was reported: the decided probability is that of a rollover (in the field "
        "data); the occupant models see only the planar pulse."
    ),
    AssumptionCode.MULTIPLE_IMPACTS_REPORTED: (
        "Multiple impacts were reported: the decided probability includes them; the occupant "
        "models run the recorded pulse as one event."
    ),
    AssumptionCode.AGE_IMPUTED: (
        "Age unknown: the field model used the calibration median. Ask the caller and resend."
    ),
    AssumptionCode.BMI_IMPUTED: (
        "Stature or mass unknown: the field model used the calibration median body mass index."
    ),
    AssumptionCode.DELTA_V_EXTRAPOLATED: (
        "Delta-V above the field model's calibration data: its probability is extrapolated."
    ),
    AssumptionCode.SECOND_ROW_SEAT: (
        "A second-row seat: the field model decides; the occupant models are of the front row."
    ),
    AssumptionCode.SEAT_WITHOUT_OCCUPANT_MODEL: (
        "A seat without occupant models (front middle, second or third row): the field risk "
        "model decides (its data hold these seats); no occupant-model explanation."
    ),
    AssumptionCode.SEX_IMPUTED: (
        "Sex unknown: the field risk models used the share of women of their data."
    ),
    AssumptionCode.STATURE_MASS_IMPUTED: (
        "Stature or mass unknown: the field risk models used the medians of their data."
    ),
    AssumptionCode.MODEL_YEAR_IMPUTED: (
        "Vehicle model year unknown: the field risk models used the median model year of "
        "their latest accident year. Send it (VIN 10th character) when known."
    ),
    AssumptionCode.MODEL_YEAR_BEYOND_DATA: (
        "A vehicle model year outside the field risk models' data (1980-2015): they take "
        "the nearest year of the data (not extrapolated)."
    ),
    AssumptionCode.QUARTER_TURNS_IMPUTED: (
        "Rollover reported without its quarter turns: the field risk models used the median "
        "of rolled vehicles in their data."
    ),
    AssumptionCode.IMPACT_COUNT_IMPUTED: (
        "Multiple impacts reported without their count: the field risk models used the median "
        "count of vehicles with two or more harmful events in their data. Send "
        "`crash.impact_count` where the vehicle counts its events."
    ),
    AssumptionCode.OUTSIDE_FIELD_POPULATION: (
        "An occupant outside the field risk models' data (under 16 years): the probability "
        "is that of a 16-year-old and is extrapolated."
    ),
    AssumptionCode.INPUTS_INTEGRATED: (
        "Some occupant inputs (age, sex, stature, mass, belt use) were unknown: the decided "
        "probability is the average over such occupants of the same seat (and whatever else "
        "is known) in the field data, not the probability at their medians. "
        "`unknown_inputs_range95` gives the spread over them; `probability_ci95` stays the "
        "confidence interval of the average. Send the inputs when known."
    ),
    AssumptionCode.DELTA_V_MEASURED: (
        "The delta-V was measured by the vehicle (EDR or telematics; a summary says so by "
        "default): the field risk models learned the reconstructed delta-V of NASS-CDS, which "
        "reads lower, so the probability is the average over the reconstructed delta-V that "
        "the measurement model (models/field/measurement.py) allows for it. Send "
        "`delta_v_source: reconstructed` for a reconstruction."
    ),
    AssumptionCode.DELTA_V_READ_AS_RECONSTRUCTED: (
        "The delta-V was measured by the vehicle but the field model deciding has no "
        "measurement model (a model before 3.4.0): it read the measured value as if "
        "reconstructed, so its probability errs high."
    ),
    AssumptionCode.BELT_UNKNOWN: (
        "Belt use unknown (not monitored): the field risk model integrates over belt use at "
        "this seat; the occupant models, which need a state, take unbelted (the conservative "
        "choice)."
    ),
    AssumptionCode.CHILD_WITHOUT_OCCUPANT_MODEL: (
        "A child (under 16 years, or in a child seat): the occupant models are adult dummies, "
        "so no occupant-model explanation is given; the field risk model, fitted on children "
        "too, decides."
    ),
    AssumptionCode.CHILD_REGION_RISK_EXTRAPOLATED: (
        "A child: the decision (ISS 15+) is fitted on children too, but the body-region risks "
        "are the adults' models' (the field model's region models were fitted on adults), "
        "extrapolated."
    ),
    AssumptionCode.OUTSIDE_OCCUPANT_MODEL_COVERAGE: (
        "The PDOF lies between the occupant models' ranges: the field model decides without "
        "an occupant-model explanation."
    ),
    AssumptionCode.OCCUPANT_MODELS_NOT_RUN: (
        "A decision-only run (a fleet's rescoring): the occupant models were not run, so no "
        "occupant-model explanation is given; the field risk model's decision is the one a "
        "full run gives."
    ),
    AssumptionCode.OCCUPANT_MODEL_FAILED: (
        "The occupant model failed for this occupant: the field model decides without its "
        "explanation."
    ),
    AssumptionCode.POSTURE_NOT_SENSED: (
        "No posture reading: the occupant model's intervals span the whole posture range."
    ),
    AssumptionCode.SEAT_POSITION_NOT_SENSED: (
        "No seat position reading: the intervals span the whole seat track."
    ),
    AssumptionCode.SEAT_TRACK_SWITCH: (
        "Only the EDR seat track switch: the seat is in the part of the track it indicates."
    ),
    AssumptionCode.POSTURE_CLAMPED: "A posture outside the occupant models' range was clamped.",
    AssumptionCode.SEAT_TRACK_CLAMPED: (
        "A seat track outside the occupant models' range was clamped."
    ),
    AssumptionCode.SIDE_AIRBAG_NOT_REPORTED: (
        "Side airbag state not reported for a near-side occupant: none assumed (the "
        "conservative choice). Send `side_airbag` when known."
    ),
    AssumptionCode.SPREAD_MEAN: (
        "Posture or seat position not sensed: the occupant models' P(ISS >= 15) is the mean "
        "over the spread its interval propagates."
    ),
    AssumptionCode.SURROGATE_UNAVAILABLE: (
        "No surrogate for this configuration: the occupant model's intervals come from direct "
        "runs over the sensor box."
    ),
    AssumptionCode.OUTSIDE_SURROGATE_DESIGN: (
        "The crash is outside the surrogates' design range: the occupant model's intervals "
        "come from direct runs over the sensor box."
    ),
    AssumptionCode.POINT_OUTSIDE_INTERVAL: (
        "The direct occupant-model estimate lies outside the surrogate's 95 % interval."
    ),
    AssumptionCode.OCCUPANT_MODEL_AIS_CAPPED: (
        "The occupant model's risk curves put a body region at AIS 6 (maximal); a dummy "
        "measure cannot represent that level, so the region is reported at AIS 5 and the ISS "
        "from the reported levels (models/injury/reported.py). On real crashes most occupants "
        "the models put at AIS 6 had no AIS 5+ injury (docs/occupant-models.md)."
    ),
    AssumptionCode.SIDE_BEYOND_TESTED_SEVERITY: (
        "Side impact with a lateral delta-V above the severity of the side crash tests the "
        "side occupant models were checked against (IIHS side test, struck-car delta-V up to "
        "31 km/h): the models extrapolate the door intrusion and their head and chest loads are "
        "not bounded by any published test; read their measures as an upper bound."
    ),
    AssumptionCode.PULSE_LOOKS_CORRUPT: (
        "The acceleration record as sent looks corrupt: its samples are not a vehicle's motion "
        "(a sign change at nearly every sample, or far more energy above the CFC 60 band than "
        "in it), so the probability computed from it cannot rule out a severe crash. Every "
        "occupant is flagged for a trauma center (the conservative decision). Check the "
        "sensor's data path."
    ),
    AssumptionCode.VEDS_CRASH_TIME_ASSUMED: (
        "VEDS: no incident time (veds:Crash/nc:ActivityDate): the document's received or post "
        "time, else the time the service received it, was taken as the crash time."
    ),
    AssumptionCode.VEDS_MOST_SEVERE_PULSE: (
        "VEDS: several crash pulses: the one with the largest delta-V was triaged, the others "
        "count as multiple impacts."
    ),
    AssumptionCode.VEDS_BELT_NOT_REPORTED: (
        "VEDS: belt not reported, or not monitored, for an occupied seat: belt use unknown "
        "(the field risk model integrates over it; the occupant models take unbelted)."
    ),
    AssumptionCode.VEDS_AIRBAG_BY_CATEGORY: (
        "VEDS: airbags name no seat: the state every reported airbag of a category shares was "
        "given to each seat it can protect (FRONT: the front row; SIDE and CURTAIN: every seat)."
    ),
    AssumptionCode.VEDS_AIRBAG_AMBIGUOUS: (
        "VEDS: airbags of one category disagree (some deployed, some not) and name no seat: "
        "frontal not deployed, side not reported assumed (the conservative choices)."
    ),
    AssumptionCode.VEDS_FRONTAL_AIRBAG_NOT_REPORTED: (
        "VEDS: no FRONT airbag reported: the front row's frontal airbags are taken as not "
        "deployed (the conservative choice)."
    ),
    AssumptionCode.VEDS_VEHICLE_CLASS_ASSUMED: (
        "VEDS: the document names make, model and year, not an occupant-model vehicle class: "
        "the default class (compact_sedan) was used."
    ),
    AssumptionCode.VEDS_DRIVE_SIDE_ASSUMED: (
        "VEDS: no drive side in the document: left-hand drive assumed (seat code 1, the "
        "driver, on the left)."
    ),
    AssumptionCode.VEDS_MODEL_YEAR_DROPPED: (
        "VEDS: the model year (nc:ItemModelYearDate) is not four ASCII digits from 1950 to "
        "2100: it was dropped, and the crash triaged without it (the field risk models then "
        "take their median year: model_year_imputed)."
    ),
}


@dataclass(frozen=True)
class Assumption:
    """One assumption of an answer.

    Attributes
    ----------
    code : AssumptionCode
    message : str
        The assumption in words, with its numbers.
    occupant : int or None
        Index of the occupant it concerns; None for the whole notification.
    """

    code: AssumptionCode
    message: str
    occupant: int | None = None
