"""The orchestrator: one notification in, one triage result out.

Flow per notification: the pulse is processed once (`models.pulse`); per
occupant the impact mode is classified (`models.impact_mode`). The decision is
the field risk model's (`models.field`): P(MAIS 3+), fitted on real NASS-CDS
crashes, from what the notification carries (delta-V, crash mode incl.
rollover, belt, age, sex, body mass index, multiple impacts), decided at the
configured operating point. Occupants inside an occupant model's coverage are
also simulated by that model (`models.lpm`): its injury measures give region
AIS, ISS and P(ISS >= 15) (`models.injury`), less the risk curves' zero-load
floor (`models.risk_calibration`), with 95% intervals from the PCE surrogates
(`models.surrogate`) when loaded, else from direct runs over the
sensor-uncertainty box. That answer explains the decision (which body regions,
which measures) and is kept with its own decision as a second opinion, as is the
statistical baseline's (`models.baseline`) for every occupant. The case-level
decision is the worst occupant's.

Everything here is a pure function of the notification and the loaded models:
the same inputs and model versions give the same result, bit for bit (only
`timings_ms` varies).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from functools import lru_cache
from pathlib import Path

from models import ENGINE_VERSION
from models.assumptions import Assumption, AssumptionCode
from models.baseline.logistic import BaselineFeatures, BaselineModel, load_default
from models.constants import DEFAULT_POSTURE_SD_DEG, DEFAULT_SEAT_TRACK_SD_MM, Z_95
from models.field.features import FieldInputs, FieldMode, field_inputs
from models.field.model import FieldModel, FieldPrediction
from models.field.model import load_default as load_field_model
from models.impact_mode import ImpactClassification, ImpactMode, classify_impact
from models.injury.assessment import InjuryMeasures
from models.injury.batch_compiled import warm_up as _warm_up_p_iss
from models.lpm.domain import POSTURE_RANGE_DEG, SEAT_TRACK_RANGE_MM, clamp
from models.lpm.fingerprint import lpm_code_sha256, sources_sha256
from models.lpm.params import ParameterSet, available_parameter_sets, load_parameter_set
from models.lpm.simulate import LpmResult, simulate
from models.lpm.simulate import warm_up as _warm_up_lpm
from models.notification import (
    AirbagState,
    Body,
    CrashNotification,
    Occupant,
    Seat,
    SeatTrackSource,
)
from models.pulse import ProcessedPulse, process_pulse
from models.pulse import warm_up as _warm_up_pulse
from models.risk_calibration import (
    CALIBRATION_NAME,
    CALIBRATION_VERSION,
    calibration_sha256,
    corrected_probability,
    zero_load_probability,
)
from models.sensor_evidence import resolve_sensor_evidence
from models.surrogate.evaluate import (
    EVALUATION_NAME,
    EVALUATION_VERSION,
    SurrogateLibrary,
    UncertaintyResult,
    default_artifact_dir,
    evaluation_sha256,
)
from models.surrogate.kernels import warm_up as _warm_up_surrogates
from models.surrogate.spec import P_RESOLUTION

__all__ = [
    "DEFAULT_POSTURE_SD_DEG",
    "DEFAULT_SEAT_TRACK_SD_MM",
    "LPM_THRESHOLDS",
    "LPM_OUTCOME",
    "BASELINE_OUTCOME",
    "IntervalMethod",
    "Method",
    "RECOMMENDATION_NO_TRAUMA_INDICATION",
    "RECOMMENDATION_TRAUMA_CENTER",
    "TRIAGE_SOURCES",
    "SensorInputs",
    "EngineModels",
    "IssEstimate",
    "ModelInfo",
    "OccupantSimulation",
    "OccupantTriage",
    "TriageDecision",
    "TriageResult",
    "UnknownVehicleModel",
    "decide",
    "load_engine_models",
    "warm_up",
    "occupant_evidence",
    "notification_field_inputs",
    "OccupantEvidence",
    "load_surrogates",
    "simulate_notification",
    "triage",
    "triage_code_sha256",
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
#: Outcome of the occupant models' probability.
LPM_OUTCOME = "ISS15+"
#: Outcome of the statistical baseline: police-reported incapacitating or fatal
#: injury (KABCO A or K), NASS-CDS 1997-2000.
BASELINE_OUTCOME = "police_A+K"
#: Sources (under models/) of the orchestration itself: how a notification becomes
#: model inputs and how the answers become a decision. Their checksum is recorded
#: with every case (``triage_code``), beside those of the models they call.
TRIAGE_SOURCES = (
    "triage/__init__.py",
    "pulse.py",
    "impact_mode.py",
    "notification.py",
    "sensor_evidence.py",
    "lpm/domain.py",
)


@lru_cache(maxsize=1)
def triage_code_sha256() -> str:
    """SHA-256 over :data:`TRIAGE_SOURCES` (as :func:`models.lpm.fingerprint.sources_sha256`)."""
    return sources_sha256(TRIAGE_SOURCES)


#: Surrogate inputs that describe the crash (not the occupant sensors): a surrogate
#: is not extrapolated in them.
_CRASH_INPUTS = frozenset({"delta_v_kmh", "angle_deg", "duration_ms"})


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
        Positive: likely ISS 15+, transport to a Level I trauma center.
    probability : float
        Probability of `outcome`.
    probability_ci95 : (float, float)
    threshold : float
        Positive when ``probability >= threshold``.
    recommendation : str
    outcome : str
        What `probability` is a probability of (``MAIS3+`` for the field model,
        ``ISS15+`` for the occupant models, the police-reported outcome for the
        baseline).
    model : str
        Name of the model that gave it.
    operating_point : str or None
        The named operating point the threshold belongs to (field model).
    """

    iss15_plus: bool
    probability: float
    probability_ci95: tuple[float, float]
    threshold: float
    recommendation: str
    outcome: str = LPM_OUTCOME
    model: str = "occupant_models"
    operating_point: str | None = None


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


@dataclass(frozen=True)
class EngineModels:
    """Every model the engine answers with, loaded once at start.

    Attributes
    ----------
    baseline : BaselineModel
        The statistical baseline (always present).
    parameter_sets : Mapping[str, ParameterSet]
        Occupant-model parameter sets by vehicle model name.
    surrogates : SurrogateLibrary or None
        PCE surrogates for the confidence intervals; None: the interim interval
        from direct occupant-model runs over the sensor-uncertainty box.
    field : FieldModel or None
        The field risk model the decision is made with; None only for offline
        tools that compute the occupant models' answers alone
        (:func:`occupant_model_answers`): :func:`triage` needs it.
    operating_point : str or None
        Named operating point of the field model (None: the artifact's default).
    threshold_override : float or None
        Replaces the operating point's thresholds when set.
    posture_sd_deg, seat_track_sd_mm : float
        Sensor standard deviations used when a notification gives none.
    """

    baseline: BaselineModel
    parameter_sets: Mapping[str, ParameterSet]
    surrogates: SurrogateLibrary | None = None
    field: FieldModel | None = None
    operating_point: str | None = None
    threshold_override: float | None = None
    posture_sd_deg: float = DEFAULT_POSTURE_SD_DEG
    seat_track_sd_mm: float = DEFAULT_SEAT_TRACK_SD_MM

    @property
    def vehicle_models(self) -> frozenset[str]:
        """Vehicle parameter-set names a notification may name."""
        return frozenset(self.parameter_sets)

    def model_infos(self, vehicle_model: str | None = None) -> dict[str, ModelInfo]:
        """Versions and checksums: the baseline, and the occupant models of `vehicle_model`.

        With `vehicle_model` None, every loaded model.
        """
        b = self.baseline
        infos = {"baseline": ModelInfo(name=b.name, version=b.version, sha256=b.sha256)}
        if self.field is not None:
            f = self.field
            infos["field_model"] = ModelInfo(name=f.name, version=f.version, sha256=f.sha256)
        names = sorted(self.parameter_sets) if vehicle_model is None else [vehicle_model]
        for name in names:
            ps = self.parameter_sets[name]
            infos[f"lpm_parameters:{name}"] = ModelInfo(
                name=ps.name, version=name, sha256=ps.sha256
            )
        infos["lpm_code"] = ModelInfo(
            name="occupant LPMs and injury criteria",
            version=ENGINE_VERSION,
            sha256=lpm_code_sha256(),
        )
        infos["triage_code"] = _triage_code_info()
        infos["risk_calibration"] = ModelInfo(
            name=CALIBRATION_NAME, version=CALIBRATION_VERSION, sha256=calibration_sha256()
        )
        if self.surrogates is not None:
            infos["surrogates"] = ModelInfo(
                name="pce_surrogates",
                version=self.surrogates.version,
                sha256=self.surrogates.sha256,
            )
            infos["surrogate_evaluation"] = ModelInfo(
                name=EVALUATION_NAME, version=EVALUATION_VERSION, sha256=evaluation_sha256()
            )
        return infos


def load_surrogates(directory: Path | None = None) -> SurrogateLibrary | None:
    """Load and verify the PCE surrogates; None when none are shipped.

    Raises
    ------
    ValueError
        When artifacts are present but fail verification (checksum mismatch, a
        file missing) or were built from other occupant-model code or parameters.
    """
    root = default_artifact_dir() if directory is None else directory
    if not (root / "manifest.json").is_file() and not any(root.glob("*.npz")):
        return None
    library = SurrogateLibrary.load(root)
    reason = library.stale_reason()
    if reason is not None:
        raise ValueError(f"surrogates are stale: {reason}; run `aacn-triage build-surrogates`")
    return library


def warm_up() -> None:
    """Compile (or load from the numba cache) every compiled loop of the request path:
    the pulse fit, the LPM kernels and measures, the surrogates' loops and their
    P(ISS >= 15)."""
    _warm_up_pulse()
    _warm_up_lpm()
    _warm_up_surrogates()
    _warm_up_p_iss()


def load_engine_models(
    threshold_override: float | None = None,
    *,
    operating_point: str | None = None,
    field_artifact: Path | None = None,
    posture_sd_deg: float = DEFAULT_POSTURE_SD_DEG,
    seat_track_sd_mm: float = DEFAULT_SEAT_TRACK_SD_MM,
    surrogate_dir: Path | None = None,
    use_surrogates: bool = True,
    use_field: bool = True,
    warm: bool = True,
) -> EngineModels:
    """Load and verify the shipped model artifacts, and warm the compiled kernels.

    Raises
    ------
    ValueError
        When an artifact is missing, malformed, altered, or does not match the
        code, or `operating_point` is not one the field model defines.
    """
    field_model: FieldModel | None = None
    if use_field:
        field_model = (
            load_field_model()
            if field_artifact is None
            else FieldModel.from_artifact(field_artifact)
        )
    if (
        field_model is not None
        and operating_point is not None
        and operating_point not in field_model.operating_points
    ):
        raise ValueError(
            f"unknown operating point {operating_point!r}; the field model defines "
            + ", ".join(sorted(field_model.operating_points))
        )
    surrogates = load_surrogates(surrogate_dir) if use_surrogates else None
    parameter_sets = {name: load_parameter_set(name) for name in available_parameter_sets()}
    # the code checksums recorded with every case are computed here, once (they parse
    # source; CPython 3.11's parser is not safe to run from several threads at once)
    lpm_code_sha256()
    triage_code_sha256()
    evaluation_sha256()
    if warm:
        warm_up()
    return EngineModels(
        baseline=load_default(),
        parameter_sets=parameter_sets,
        surrogates=surrogates,
        field=field_model,
        operating_point=operating_point,
        threshold_override=threshold_override,
        posture_sd_deg=posture_sd_deg,
        seat_track_sd_mm=seat_track_sd_mm,
    )


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


def _worst(decisions: list[TriageDecision]) -> TriageDecision:
    return max(decisions, key=lambda d: (d.iss15_plus, d.probability))


def _triage_code_info() -> ModelInfo:
    return ModelInfo(
        name="notification-to-answer orchestration (pulse, impact mode, sensor evidence, decision)",
        version=ENGINE_VERSION,
        sha256=triage_code_sha256(),
    )


def _used_models(models: EngineModels, vehicle_model: str, used_lpm: bool) -> dict[str, ModelInfo]:
    infos = models.model_infos(vehicle_model)
    if not used_lpm:
        keep = ("baseline", "field_model", "triage_code")
        return {k: infos[k] for k in keep if k in infos}
    return infos


def _in_domain(occupant: Occupant, index: int, assumptions: list[Assumption]) -> Occupant:
    """The occupant with posture and seat track clamped to the models' domain."""
    posture = clamp(occupant.posture_lumbar_flexion_deg, POSTURE_RANGE_DEG)
    track = clamp(occupant.seat_track_mm, SEAT_TRACK_RANGE_MM)
    if posture != occupant.posture_lumbar_flexion_deg:
        assumptions.append(
            Assumption(
                AssumptionCode.POSTURE_CLAMPED,
                f"occupants[{index}]: lumbar flexion {occupant.posture_lumbar_flexion_deg:g} deg "
                f"clamped to {posture:g} deg (occupant-model range {POSTURE_RANGE_DEG})",
                index,
            )
        )
    if track != occupant.seat_track_mm:
        assumptions.append(
            Assumption(
                AssumptionCode.SEAT_TRACK_CLAMPED,
                f"occupants[{index}]: seat track {occupant.seat_track_mm:g} mm clamped to "
                f"{track:g} mm (occupant-model range {SEAT_TRACK_RANGE_MM})",
                index,
            )
        )
    return dataclasses.replace(occupant, posture_lumbar_flexion_deg=posture, seat_track_mm=track)


def _measures_dict(measures: InjuryMeasures) -> dict[str, float]:
    values = ((f.name, getattr(measures, f.name)) for f in dataclasses.fields(measures))
    return {k: float(v) for k, v in values if v is not None}


def _run(
    pulse: ProcessedPulse,
    impact: ImpactClassification,
    occupant: Occupant,
    params: ParameterSet,
) -> LpmResult:
    return simulate(
        pulse.time_s,
        pulse.longitudinal_g,
        pulse.lateral_g,
        impact.mode,
        occupant,
        params,
        angle_deg=impact.angle_from_axis_deg,
    )


def _sensor_box(
    pulse: ProcessedPulse,
    impact: ImpactClassification,
    occupant: Occupant,
    params: ParameterSet,
    posture_sd: float,
    track_sd: float,
) -> list[LpmResult]:
    """Direct runs at the 8 non-central points of the +/-1.96 SD sensor box.

    The interim interval when no surrogate is loaded: the range of each output over
    posture and seat track within their 95% sensor bounds (clamped to the domain).
    """
    runs = []
    for dp in (-Z_95, 0.0, Z_95):
        for dt in (-Z_95, 0.0, Z_95):
            if dp == 0.0 and dt == 0.0:
                continue
            shifted = dataclasses.replace(
                occupant,
                posture_lumbar_flexion_deg=clamp(
                    occupant.posture_lumbar_flexion_deg + dp * posture_sd, POSTURE_RANGE_DEG
                ),
                seat_track_mm=clamp(occupant.seat_track_mm + dt * track_sd, SEAT_TRACK_RANGE_MM),
            )
            result = _run(pulse, impact, shifted, params)
            if result.assessment is not None:
                runs.append(result)
    return runs


def _mode_airbag_deployed(occupant: Occupant, mode: ImpactMode) -> bool:
    """Whether the airbag that acts in the mode's occupant model deployed."""
    if mode is ImpactMode.NEAR_SIDE:
        return occupant.side_airbag is AirbagState.DEPLOYED
    return occupant.frontal_airbag is AirbagState.DEPLOYED


@dataclass(frozen=True)
class _LpmAnswer:
    """An occupant model's answer for one occupant (the explanation of a decision)."""

    decision: TriageDecision
    iss: IssEstimate
    region_ais: Mapping[str, int]
    measures: Mapping[str, float]
    measures_ci95: Mapping[str, tuple[float, float]]
    interval_method: IntervalMethod
    point_outside_interval: bool
    probability_uncorrected: float
    probability_zero_load: float
    sensor_inputs: SensorInputs


def _sensed(occupant: Occupant) -> bool:
    """Posture and seat position both come from sensor readings."""
    return occupant.posture_sensed and occupant.seat_track_source is SeatTrackSource.SENSOR


@dataclass(frozen=True)
class _Intervals:
    """The occupant model's point P(ISS >= 15) and its intervals, by one method."""

    p: float
    p_ci: tuple[float, float]
    iss_ci: tuple[float, float]
    measures_ci: dict[str, tuple[float, float]]
    method: IntervalMethod
    outside: bool


def _surrogate_uncertainty(
    index: int,
    occupant: Occupant,
    lpm_occupant: Occupant,
    impact: ImpactClassification,
    pulse: ProcessedPulse,
    models: EngineModels,
    sds: tuple[float, float],
    assumptions: list[Assumption],
) -> UncertaintyResult | None:
    """The surrogate's propagation of the sensor spread, or None (the reason noted)."""
    # the rear surrogates are built without a frontal airbag acting; an explicit
    # firing time makes the rear LPM use one, so the surrogate does not apply
    rear_with_bag = impact.mode is ImpactMode.REAR and occupant.airbag_fire_time_ms is not None
    if models.surrogates is None or rear_with_bag:
        return None
    try:
        family = models.surrogates.family(
            impact.mode,
            occupant.body,
            occupant.belted,
            _mode_airbag_deployed(occupant, impact.mode),
        )
        uncertainty = family.propagate(
            delta_v_kmh=pulse.delta_v_kmh,
            angle_deg=impact.angle_from_axis_deg,
            posture_deg=lpm_occupant.posture_lumbar_flexion_deg,
            seat_track_mm=lpm_occupant.seat_track_mm,
            duration_ms=pulse.haversine.duration_ms,
            posture_sd_deg=sds[0],
            seat_track_sd_mm=sds[1],
            age_years=lpm_occupant.age_years,  # the chest curve the direct run used
        )
    except (KeyError, ValueError) as exc:
        assumptions.append(
            Assumption(
                AssumptionCode.SURROGATE_UNAVAILABLE,
                f"occupants[{index}]: surrogate unavailable ({exc}); interval from direct "
                "occupant-model runs over the sensor-uncertainty box",
                index,
            )
        )
        return None
    outside_design = set(uncertainty.clamped_inputs) & _CRASH_INPUTS
    if outside_design:
        assumptions.append(
            Assumption(
                AssumptionCode.OUTSIDE_SURROGATE_DESIGN,
                f"occupants[{index}]: {', '.join(sorted(outside_design))} outside the "
                "surrogate's design range; interval from direct occupant-model runs over "
                "the sensor-uncertainty box",
                index,
            )
        )
        return None
    return uncertainty


def _intervals_from_surrogate(
    index: int,
    nominal: LpmResult,
    uncertainty: UncertaintyResult,
    sensed: bool,
    assumptions: list[Assumption],
) -> _Intervals:
    """Intervals from the surrogate; the point is the spread's mean when nothing was sensed."""
    assert nominal.assessment is not None
    p = float(nominal.assessment.p_iss15)
    iss = int(nominal.assessment.iss)
    measures = _measures_dict(nominal.measures)
    p_ci = (float(uncertainty.p_iss15_ci95[0]), float(uncertainty.p_iss15_ci95[1]))
    iss_ci = (float(uncertainty.iss_ci95[0]), float(uncertainty.iss_ci95[1]))
    measures_ci = {
        k: (float(v[0]), float(v[1])) for k, v in uncertainty.measures_ci95.items() if k in measures
    }
    if not sensed:
        # a posture or seat position that was not sensed is a spread, not a
        # reading: the point estimate is the expectation over the spread the
        # interval propagates, not the value at one assumed posture
        p = float(uncertainty.p_iss15)
        assumptions.append(
            Assumption(
                AssumptionCode.SPREAD_MEAN,
                f"occupants[{index}]: occupant-model P(ISS >= 15) is the mean over the "
                "unsensed posture / seat position spread; measures, region AIS and ISS "
                "are those of the run at the assumed posture and seat position",
                index,
            )
        )
    tol = P_RESOLUTION  # the surrogate's resolution of P near 0 and 1
    outside = not (p_ci[0] - tol <= p <= p_ci[1] + tol) or not (
        iss_ci[0] - 0.5 <= iss <= iss_ci[1] + 0.5
    )
    if outside:
        assumptions.append(
            Assumption(
                AssumptionCode.POINT_OUTSIDE_INTERVAL,
                f"occupants[{index}]: the direct occupant-model estimate lies outside the "
                "surrogate's 95% interval",
                index,
            )
        )
    else:
        # within the surrogate's resolution of its interval (P near 0 or 1, ISS
        # within half a point): the interval is stretched to hold the estimate,
        # so that an unflagged answer always lies inside its own interval
        p_ci = (min(p_ci[0], p), max(p_ci[1], p))
        iss_ci = (min(iss_ci[0], float(iss)), max(iss_ci[1], float(iss)))
    return _Intervals(p, p_ci, iss_ci, measures_ci, IntervalMethod.PCE_BOOTSTRAP, outside)


def _intervals_from_box(
    nominal: LpmResult,
    pulse: ProcessedPulse,
    impact: ImpactClassification,
    lpm_occupant: Occupant,
    params: ParameterSet,
    sds: tuple[float, float],
) -> _Intervals:
    """Intervals from direct runs over the +/-1.96 SD sensor box (no surrogate)."""
    assert nominal.assessment is not None
    measures = _measures_dict(nominal.measures)
    box = [nominal, *_sensor_box(pulse, impact, lpm_occupant, params, sds[0], sds[1])]
    ps = [float(r.assessment.p_iss15) for r in box if r.assessment is not None]
    isss = [float(r.assessment.iss) for r in box if r.assessment is not None]
    measures_ci = {}
    for key in measures:
        values = [_measures_dict(r.measures).get(key) for r in box]
        finite = [v for v in values if v is not None]
        measures_ci[key] = (min(finite), max(finite))
    return _Intervals(
        float(nominal.assessment.p_iss15),
        (min(ps), max(ps)),
        (min(isss), max(isss)),
        measures_ci,
        IntervalMethod.LPM_SENSOR_BOX,
        False,
    )


def _lpm_occupant(
    index: int,
    occupant: Occupant,
    impact: ImpactClassification,
    pulse: ProcessedPulse,
    params: ParameterSet,
    models: EngineModels,
    assumptions: list[Assumption],
) -> _LpmAnswer | None:
    """Answer one in-coverage occupant with its occupant model; None when it fails."""
    sensed = _sensed(occupant)
    occupant = resolve_sensor_evidence(occupant, index, assumptions)
    lpm_occupant = _in_domain(occupant, index, assumptions)
    if impact.mode is ImpactMode.NEAR_SIDE and occupant.side_airbag is None:
        assumptions.append(
            Assumption(
                AssumptionCode.SIDE_AIRBAG_NOT_REPORTED,
                f"occupants[{index}]: side airbag state not reported: none assumed for the "
                "near-side occupant model (the conservative choice)",
                index,
            )
        )
    nominal = _run(pulse, impact, lpm_occupant, params)
    if nominal.assessment is None:
        assumptions.append(
            Assumption(
                AssumptionCode.OCCUPANT_MODEL_FAILED,
                f"occupants[{index}]: occupant model failed ({nominal.message}); "
                "the field model decides without its explanation",
                index,
            )
        )
        return None
    sds = (
        occupant.posture_sd_deg or models.posture_sd_deg,
        occupant.seat_track_sd_mm or models.seat_track_sd_mm,
    )
    uncertainty = _surrogate_uncertainty(
        index, occupant, lpm_occupant, impact, pulse, models, sds, assumptions
    )
    iv = (
        _intervals_from_surrogate(index, nominal, uncertainty, sensed, assumptions)
        if uncertainty is not None
        else _intervals_from_box(nominal, pulse, impact, lpm_occupant, params, sds)
    )
    # the thresholds apply to the risk attributable to the crash loads: remove the
    # risk curves' zero-load floor from the point and from the interval, at the
    # occupant's age (the direct run and the surrogate both use it)
    p0 = zero_load_probability(nominal.measures, occupant.body, occupant.age_years, impact.mode)
    p_ci = (corrected_probability(iv.p_ci[0], p0), corrected_probability(iv.p_ci[1], p0))
    return _LpmAnswer(
        decision=decide(corrected_probability(iv.p, p0), p_ci, LPM_THRESHOLDS[impact.mode]),
        iss=IssEstimate(estimate=int(nominal.assessment.iss), ci95=iv.iss_ci),
        region_ais=dict(nominal.assessment.region_ais),
        measures=_measures_dict(nominal.measures),
        measures_ci95=iv.measures_ci,
        interval_method=iv.method,
        point_outside_interval=iv.outside,
        probability_uncorrected=iv.p,
        probability_zero_load=p0,
        sensor_inputs=SensorInputs(
            posture_deg=lpm_occupant.posture_lumbar_flexion_deg,
            posture_sd_deg=sds[0],
            seat_track_mm=lpm_occupant.seat_track_mm,
            seat_track_sd_mm=sds[1],
        ),
    )


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
) -> OccupantEvidence:
    impact = classify_impact(pulse.pdof_deg, occupant.seat, notification.drive_side)
    answer: _LpmAnswer | None = None
    if impact.in_lpm_coverage:
        params = models.parameter_sets[notification.vehicle_model]
        answer = _lpm_occupant(index, occupant, impact, pulse, params, models, assumptions)
    elif occupant.seat.front_row:
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


def _occupant_triage(
    occupant: Occupant, evidence: OccupantEvidence, decision: TriageDecision, mode: FieldMode
) -> OccupantTriage:
    decided = OccupantTriage(
        seat=occupant.seat,
        body=occupant.body,
        impact=evidence.impact,
        method=Method.FIELD,
        triage=decision,
        baseline=evidence.baseline,
        field_mode=mode,
    )
    answer = evidence.occupant_model
    if answer is None:
        return decided
    return dataclasses.replace(
        decided,
        method=Method.LPM,
        occupant_model=answer.decision,
        iss=answer.iss,
        region_ais=answer.region_ais,
        measures=answer.measures,
        measures_ci95=answer.measures_ci95,
        interval_method=answer.interval_method,
        point_outside_interval=answer.point_outside_interval,
        probability_uncorrected=answer.probability_uncorrected,
        probability_zero_load=answer.probability_zero_load,
        sensor_inputs=answer.sensor_inputs,
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


def triage(notification: CrashNotification, models: EngineModels) -> TriageResult:
    """Triage every occupant of a notification.

    Parameters
    ----------
    notification : CrashNotification
    models : EngineModels
        With a field model.

    Returns
    -------
    TriageResult

    Raises
    ------
    UnknownVehicleModel
        When `notification.vehicle_model` names no loaded parameter set.
    ValueError
        When the pulse cannot be processed (the message names the field), or
        `models` holds no field model.
    """
    if models.field is None:
        raise ValueError("the engine models hold no field model: triage needs one")
    field_model = models.field
    if notification.vehicle_model not in models.vehicle_models:
        raise UnknownVehicleModel(
            f"unknown vehicle model {notification.vehicle_model!r}; known: "
            + ", ".join(sorted(models.vehicle_models))
        )
    t0 = time.perf_counter()
    pulse = process_pulse(notification.pulse)
    t1 = time.perf_counter()

    assumptions: list[Assumption] = []
    if notification.rollover:
        assumptions.append(
            Assumption(
                AssumptionCode.ROLLOVER_REPORTED,
                "rollover reported: the field model's probability is that of a rollover (it is "
                "in its data); the occupant models see only the planar crash pulse",
            )
        )
    if notification.multiple_impacts:
        assumptions.append(
            Assumption(
                AssumptionCode.MULTIPLE_IMPACTS_REPORTED,
                "multiple impacts reported: the field model's probability includes them (they "
                "are in its data); the occupant models run the recorded pulse as one event",
            )
        )

    occupants: list[OccupantTriage] = []
    field_ms = 0.0
    for i, occupant in enumerate(notification.occupants):
        evidence = _occupant_evidence(i, occupant, notification, pulse, models, assumptions)
        tf = time.perf_counter()
        prediction = field_model.predict(evidence.field_inputs)
        decision = _field_decision(field_model, models, prediction)
        field_ms += 1000.0 * (time.perf_counter() - tf)
        assumptions.extend(_field_assumptions(i, occupant, prediction, field_model))
        occupants.append(_occupant_triage(occupant, evidence, decision, prediction.mode))
    used_lpm = any(o.method is Method.LPM for o in occupants)
    t2 = time.perf_counter()

    return TriageResult(
        event_id=notification.event_id,
        triage=_worst([o.triage for o in occupants]),
        occupants=tuple(occupants),
        pulse=pulse,
        assumptions=tuple(assumptions),
        engine_version=ENGINE_VERSION,
        models=_used_models(models, notification.vehicle_model, used_lpm),
        timings_ms={
            "pulse": 1000.0 * (t1 - t0),
            "occupants": 1000.0 * (t2 - t1),
            "field_model": field_ms,
            "engine_total": 1000.0 * (t2 - t0),
        },
    )


@dataclass(frozen=True)
class OccupantSimulation:
    """One occupant's direct occupant-model run (None where out of coverage)."""

    index: int
    occupant: Occupant
    impact: ImpactClassification
    result: LpmResult | None


def simulate_notification(
    notification: CrashNotification, models: EngineModels
) -> tuple[ProcessedPulse, list[OccupantSimulation], list[Assumption]]:
    """Run the occupant models of a notification, keeping the full time histories.

    Returns
    -------
    pulse : ProcessedPulse
    simulations : list of OccupantSimulation
        One per occupant, in order.
    assumptions : list of str
    """
    if notification.vehicle_model not in models.vehicle_models:
        raise UnknownVehicleModel(f"unknown vehicle model {notification.vehicle_model!r}")
    pulse = process_pulse(notification.pulse)
    params = models.parameter_sets[notification.vehicle_model]
    assumptions: list[Assumption] = []
    out = []
    for i, occupant in enumerate(notification.occupants):
        impact = classify_impact(pulse.pdof_deg, occupant.seat, notification.drive_side)
        result = None
        if impact.in_lpm_coverage:
            # the same nominal posture and seat track as the triage's direct run
            occupant = resolve_sensor_evidence(occupant, i, assumptions)
            result = _run(pulse, impact, _in_domain(occupant, i, assumptions), params)
        out.append(OccupantSimulation(i, occupant, impact, result))
    return pulse, out, assumptions
