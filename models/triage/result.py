"""The engine's answer: the result types of a triage (decisions, ISS, occupant and case)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum

from models.assumptions import Assumption
from models.field.features import FieldMode
from models.field.risk_model import RegionRisk
from models.impact_mode import ImpactClassification
from models.notification import (
    Body,
    Seat,
)
from models.pulse import ProcessedPulse
from models.tiers import Tier

__all__ = [
    "LPM_OUTCOME",
    "UnknownVehicleModel",
    "IntervalMethod",
    "Method",
    "ModelInfo",
    "TriageDecision",
    "IssEstimate",
    "SensorInputs",
    "OccupantTriage",
    "TriageResult",
    "VehicleRiskAnswer",
]


#: Outcome of the occupant models' probability.
LPM_OUTCOME = "ISS15+"


class UnknownVehicleModel(ValueError):
    """The notification names a vehicle parameter set that is not loaded."""


class IntervalMethod(StrEnum):
    """Where an occupant model's 95% intervals come from."""

    #: the PCE surrogates: sensor samples through the point surrogate and its
    #: bootstrap replicates, widened by held-out calibrated margins
    PCE_BOOTSTRAP = "pce_bootstrap"
    #: direct occupant-model runs over the +/-1.96 SD sensor box
    LPM_SENSOR_BOX = "lpm_sensor_box"


class Method(StrEnum):
    """How an occupant was answered.

    The decision is always the field model's. ``LPM``: an occupant model ran and
    explains it (measures, region AIS, ISS); ``FIELD``: no occupant model applies
    (PDOF between the models' ranges, a second-row seat) or it failed.
    """

    LPM = "lpm"
    FIELD = "field"


@dataclass(frozen=True)
class ModelInfo:
    """Name, version and checksum of one model artifact (recorded with every case)."""

    name: str
    version: str
    sha256: str


@dataclass(frozen=True)
class TriageDecision:
    """A trauma-center decision on a probability with its 95% interval.

    Attributes
    ----------
    iss15_plus : bool
        Positive: ``probability >= threshold`` (the operating point's), a telemetry
        indication of ISS 15+.
    probability : float
        Probability of `outcome`.
    probability_ci95 : (float, float)
    threshold : float
        Positive when ``probability >= threshold``.
    recommendation : str
        The words of the tier (:mod:`models.tiers`); for a second opinion, the
        words of a positive or negative telemetry indication.
    outcome : str
        What `probability` is a probability of (``ISS15+`` for the field risk
        model 3.0.0 on and the occupant models, ``MAIS3+`` for field model 2.0.0,
        the police-reported outcome for the baseline).
    model : str
        Name of the model that gave it.
    operating_point : str or None
        The named operating point the threshold belongs to (field model).
    unknown_inputs_range95 : (float, float) or None
        Field risk model: the spread of the probability over the occupant
        inputs that were unknown and integrated over (2.5 and 97.5
        percentiles); not a confidence interval. None when all were known.
    knowledge : str or None
        Field risk model: what was known of the occupant, which the threshold
        was set for (``adult``, ``child``, ``age_unknown``).
    tier : Tier or None
        The field decision's risk tier; None for the second opinions (tiers belong
        to the field decision only).
    high_threshold : float or None
        The high-risk threshold the tier was set with (field decision only).
    """

    iss15_plus: bool
    probability: float
    probability_ci95: tuple[float, float]
    threshold: float
    recommendation: str
    outcome: str = LPM_OUTCOME
    model: str = "occupant_models"
    operating_point: str | None = None
    unknown_inputs_range95: tuple[float, float] | None = None
    knowledge: str | None = None
    tier: Tier | None = None
    high_threshold: float | None = None


@dataclass(frozen=True)
class IssEstimate:
    """ISS point estimate and, where available, its 95% interval."""

    estimate: int
    ci95: tuple[float, float] | None = None


@dataclass(frozen=True)
class SensorInputs:
    """The occupant inputs an occupant-model answer was computed at.

    Attributes
    ----------
    posture_deg, seat_track_mm : float
        Lumbar flexion (deg) and seat track (mm forward of mid track) of the
        direct run, after the sensor evidence was resolved and the values
        clamped to the models' domain.
    posture_sd_deg, seat_track_sd_mm : float
        Standard deviations propagated into the intervals (deg, mm).
    """

    posture_deg: float
    posture_sd_deg: float
    seat_track_mm: float
    seat_track_sd_mm: float


@dataclass(frozen=True)
class OccupantTriage:
    """The triage of one occupant.

    `triage` is the decision (the field model's); `occupant_model` the occupant
    models' own decision on their P(ISS >= 15) (None without an occupant model),
    `baseline` the statistical baseline's: both second opinions. The remaining
    fields are the occupant model's explanation (None without one).
    """

    seat: Seat
    body: Body
    impact: ImpactClassification
    method: Method
    triage: TriageDecision
    baseline: TriageDecision
    field_mode: FieldMode = FieldMode.FRONTAL
    occupant_model: TriageDecision | None = None
    iss: IssEstimate | None = None
    region_ais: Mapping[str, int] | None = None
    measures: Mapping[str, float] | None = None
    measures_ci95: Mapping[str, tuple[float, float]] | None = None
    interval_method: IntervalMethod | None = None
    point_outside_interval: bool = False
    #: occupant models only: P(ISS >= 15) from the risk curves before the
    #: zero-load correction, and the same occupant's P(ISS >= 15) at zero load
    #: (`models.risk_calibration`)
    probability_uncorrected: float | None = None
    probability_zero_load: float | None = None
    #: occupant models only: the posture and seat track used, with their SDs
    sensor_inputs: SensorInputs | None = None
    #: the field risk models' P(AIS 3+ injury) per body region (AIS 2+ where the
    #: region's `ais_level` says so); None with a MAIS 3+ field model (2.0.0)
    region_risk: Mapping[str, RegionRisk] | None = None


@dataclass(frozen=True)
class VehicleRiskAnswer:
    """P(anyone in the vehicle ISS 15+), the case-level answer of the field risk model.

    Attributes
    ----------
    probability : float
    probability_ci95 : (float, float)
        Bootstrap refits by crash.
    heldout_auc : float
        Its AUC on vehicles held out by crash (NASS-CDS 1997-2014, unweighted).
    model : str
        ``name@version``.
    outcome : str
    tier : Tier or None
        Its own risk tier, from its own probability against the occupants' operating
        threshold and the high-risk threshold (the vehicle is the unit of the CDC
        panel's 20 % and of OnStar's published prediction).
    threshold, high_threshold : float or None
        The thresholds `tier` was set with.
    """

    probability: float
    probability_ci95: tuple[float, float]
    heldout_auc: float
    model: str
    outcome: str = "anyone ISS15+"
    tier: Tier | None = None
    threshold: float | None = None
    high_threshold: float | None = None


@dataclass(frozen=True)
class TriageResult:
    """The engine's answer to a notification."""

    event_id: str
    triage: TriageDecision
    occupants: tuple[OccupantTriage, ...]
    pulse: ProcessedPulse
    assumptions: tuple[Assumption, ...]
    engine_version: str
    models: Mapping[str, ModelInfo]
    timings_ms: Mapping[str, float] = field(compare=False)
    #: P(anyone in the vehicle ISS 15+); None with a MAIS 3+ field model (2.0.0)
    vehicle: VehicleRiskAnswer | None = None
    #: Where the delta-V came from: ``measured`` (the vehicle's sensors) or
    #: ``reconstructed`` (from crush, as the field data's)
    delta_v_source: str = "measured"
