"""The orchestrator: one notification in, one triage result out.

Flow per notification: the pulse is processed once (`models.pulse`); per
occupant the impact mode is classified (`models.impact_mode`); occupants inside
an occupant model's coverage are simulated by that model (`models.lpm`), whose
injury measures give region AIS, ISS and P(ISS >= 15) (`models.injury`), less
the risk curves' zero-load floor (`models.risk_calibration`); the
95% intervals come from the PCE surrogates (`models.surrogate`) when loaded,
else from direct runs over the sensor-uncertainty box. All other occupants are
answered by the statistical baseline (`models.baseline`), which is also kept for
every occupant as a second opinion. The case-level decision is the worst
occupant's.

Everything here is a pure function of the notification and the loaded models:
the same inputs and model versions give the same result, bit for bit (only
`timings_ms` varies).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from models import ENGINE_VERSION
from models.baseline.logistic import BaselineFeatures, BaselineModel, load_default
from models.impact_mode import ImpactClassification, ImpactMode, classify_impact
from models.injury.assessment import InjuryMeasures
from models.lpm.domain import POSTURE_RANGE_DEG, SEAT_TRACK_RANGE_MM, clamp
from models.lpm.fingerprint import lpm_code_sha256, sources_sha256
from models.lpm.params import ParameterSet, available_parameter_sets, load_parameter_set
from models.lpm.simulate import LpmResult, simulate, warm_up
from models.notification import AirbagState, Body, CrashNotification, Occupant, Seat
from models.pulse import ProcessedPulse, process_pulse
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
from models.surrogate.spec import P_RESOLUTION

__all__ = [
    "DEFAULT_POSTURE_SD_DEG",
    "DEFAULT_SEAT_TRACK_SD_MM",
    "LPM_THRESHOLDS",
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
#: Default sensor standard deviations: posture within 5 deg and seat position within
#: 5 cm, 95% of the time, Gaussian (issue 5): SD = bound / 1.96.
DEFAULT_POSTURE_SD_DEG = 5.0 / 1.959964
DEFAULT_SEAT_TRACK_SD_MM = 50.0 / 1.959964
#: z of a two-sided 95% interval.
_Z95 = 1.959964
#: Sources (under models/) of the orchestration itself: how a notification becomes
#: model inputs and how the answers become a decision. Their checksum is recorded
#: with every case (``triage_code``), beside those of the models they call.
TRIAGE_SOURCES = (
    "triage.py",
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
    measures_ci95: Mapping[str, tuple[float, float]] | None = None
    interval_method: str = "coefficient_covariance"
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
    parameter_sets : Mapping[str, ParameterSet]
        Occupant-model parameter sets by vehicle model name.
    surrogates : SurrogateLibrary or None
        PCE surrogates for the confidence intervals; None: the interim interval
        from direct occupant-model runs over the sensor-uncertainty box.
    threshold_override : float or None
        Replaces every model's own decision threshold when set.
    posture_sd_deg, seat_track_sd_mm : float
        Sensor standard deviations used when a notification gives none.
    """

    baseline: BaselineModel
    parameter_sets: Mapping[str, ParameterSet]
    surrogates: SurrogateLibrary | None = None
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


def load_engine_models(
    threshold_override: float | None = None,
    *,
    posture_sd_deg: float = DEFAULT_POSTURE_SD_DEG,
    seat_track_sd_mm: float = DEFAULT_SEAT_TRACK_SD_MM,
    surrogate_dir: Path | None = None,
    use_surrogates: bool = True,
    warm: bool = True,
) -> EngineModels:
    """Load and verify the shipped model artifacts, and warm the compiled kernels.

    Raises
    ------
    ValueError
        When an artifact is missing, malformed, or does not match the code.
    """
    surrogates = load_surrogates(surrogate_dir) if use_surrogates else None
    parameter_sets = {name: load_parameter_set(name) for name in available_parameter_sets()}
    if warm:
        warm_up()
    return EngineModels(
        baseline=load_default(),
        parameter_sets=parameter_sets,
        surrogates=surrogates,
        threshold_override=threshold_override,
        posture_sd_deg=posture_sd_deg,
        seat_track_sd_mm=seat_track_sd_mm,
    )


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


def _triage_code_info() -> ModelInfo:
    return ModelInfo(
        name="notification-to-answer orchestration (pulse, impact mode, sensor evidence, decision)",
        version=ENGINE_VERSION,
        sha256=triage_code_sha256(),
    )


def _used_models(models: EngineModels, vehicle_model: str, used_lpm: bool) -> dict[str, ModelInfo]:
    infos = models.model_infos(vehicle_model)
    if not used_lpm:
        return {"baseline": infos["baseline"], "triage_code": infos["triage_code"]}
    return infos


def _in_domain(occupant: Occupant, index: int, assumptions: list[str]) -> Occupant:
    """The occupant with posture and seat track clamped to the models' domain."""
    posture = clamp(occupant.posture_lumbar_flexion_deg, POSTURE_RANGE_DEG)
    track = clamp(occupant.seat_track_mm, SEAT_TRACK_RANGE_MM)
    if posture != occupant.posture_lumbar_flexion_deg:
        assumptions.append(
            f"occupants[{index}]: lumbar flexion {occupant.posture_lumbar_flexion_deg:g} deg "
            f"clamped to {posture:g} deg (occupant-model range {POSTURE_RANGE_DEG})"
        )
    if track != occupant.seat_track_mm:
        assumptions.append(
            f"occupants[{index}]: seat track {occupant.seat_track_mm:g} mm clamped to "
            f"{track:g} mm (occupant-model range {SEAT_TRACK_RANGE_MM})"
        )
    return dataclasses.replace(occupant, posture_lumbar_flexion_deg=posture, seat_track_mm=track)


def _measures_dict(measures: InjuryMeasures) -> dict[str, float]:
    return {k: float(v) for k, v in dataclasses.asdict(measures).items() if v is not None}


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
    for dp in (-_Z95, 0.0, _Z95):
        for dt in (-_Z95, 0.0, _Z95):
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


def _lpm_occupant(
    index: int,
    occupant: Occupant,
    impact: ImpactClassification,
    pulse: ProcessedPulse,
    params: ParameterSet,
    models: EngineModels,
    baseline: TriageDecision,
    assumptions: list[str],
) -> OccupantTriage | None:
    """Answer one in-coverage occupant with its occupant model; None to fall back."""
    occupant = resolve_sensor_evidence(occupant, index, assumptions)
    lpm_occupant = _in_domain(occupant, index, assumptions)
    if impact.mode is ImpactMode.NEAR_SIDE and occupant.side_airbag is None:
        assumptions.append(
            f"occupants[{index}]: side airbag state not reported: none assumed for the "
            "near-side occupant model (the conservative choice)"
        )
    nominal = _run(pulse, impact, lpm_occupant, params)
    if nominal.assessment is None:
        assumptions.append(
            f"occupants[{index}]: occupant model failed ({nominal.message}); "
            "statistical baseline used"
        )
        return None
    posture_sd = occupant.posture_sd_deg or models.posture_sd_deg
    track_sd = occupant.seat_track_sd_mm or models.seat_track_sd_mm
    p = float(nominal.assessment.p_iss15)
    iss = int(nominal.assessment.iss)
    measures = _measures_dict(nominal.measures)
    uncertainty: UncertaintyResult | None = None
    # the rear surrogates are built without a frontal airbag acting; an explicit
    # firing time makes the rear LPM use one, so the surrogate does not apply
    rear_with_bag = impact.mode is ImpactMode.REAR and occupant.airbag_fire_time_ms is not None
    if models.surrogates is not None and not rear_with_bag:
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
                posture_sd_deg=posture_sd,
                seat_track_sd_mm=track_sd,
                age_years=lpm_occupant.age_years,  # the chest curve the direct run used
            )
        except (KeyError, ValueError) as exc:
            assumptions.append(
                f"occupants[{index}]: surrogate unavailable ({exc}); interval from direct "
                "occupant-model runs over the sensor-uncertainty box"
            )
        else:
            outside_design = set(uncertainty.clamped_inputs) & _CRASH_INPUTS
            if outside_design:
                assumptions.append(
                    f"occupants[{index}]: {', '.join(sorted(outside_design))} outside the "
                    "surrogate's design range; interval from direct occupant-model runs over "
                    "the sensor-uncertainty box"
                )
                uncertainty = None
    if uncertainty is not None:
        p_ci = (float(uncertainty.p_iss15_ci95[0]), float(uncertainty.p_iss15_ci95[1]))
        iss_ci = (float(uncertainty.iss_ci95[0]), float(uncertainty.iss_ci95[1]))
        measures_ci = {
            k: (float(v[0]), float(v[1]))
            for k, v in uncertainty.measures_ci95.items()
            if k in measures
        }
        method = "pce_bootstrap"
        tol = P_RESOLUTION  # the surrogate's resolution of P near 0 and 1
        outside = not (p_ci[0] - tol <= p <= p_ci[1] + tol) or not (
            iss_ci[0] - 0.5 <= iss <= iss_ci[1] + 0.5
        )
        if outside:
            assumptions.append(
                f"occupants[{index}]: the direct occupant-model estimate lies outside the "
                "surrogate's 95% interval"
            )
        else:
            # within the surrogate's resolution of its interval (P near 0 or 1, ISS
            # within half a point): the interval is stretched to hold the estimate,
            # so that an unflagged answer always lies inside its own interval
            p_ci = (min(p_ci[0], p), max(p_ci[1], p))
            iss_ci = (min(iss_ci[0], float(iss)), max(iss_ci[1], float(iss)))
    else:
        box = [nominal, *_sensor_box(pulse, impact, lpm_occupant, params, posture_sd, track_sd)]
        ps = [float(r.assessment.p_iss15) for r in box if r.assessment is not None]
        isss = [float(r.assessment.iss) for r in box if r.assessment is not None]
        p_ci = (min(ps), max(ps))
        iss_ci = (min(isss), max(isss))
        measures_ci = {}
        for key in measures:
            values = [_measures_dict(r.measures).get(key) for r in box]
            finite = [v for v in values if v is not None]
            measures_ci[key] = (min(finite), max(finite))
        method = "lpm_sensor_box"
        outside = False
    threshold = (
        models.threshold_override
        if models.threshold_override is not None
        else LPM_THRESHOLDS[impact.mode]
    )
    # the thresholds apply to the risk attributable to the crash loads: remove the
    # risk curves' zero-load floor from the point and from the interval (the
    # surrogates are built at the default age, so their floor is the default age's)
    p0 = zero_load_probability(nominal.measures, occupant.body, occupant.age_years, impact.mode)
    p0_ci = (
        zero_load_probability(nominal.measures, occupant.body, None, impact.mode)
        if method == "pce_bootstrap"
        else p0
    )
    p_corrected = corrected_probability(p, p0)
    p_ci_corrected = (corrected_probability(p_ci[0], p0_ci), corrected_probability(p_ci[1], p0_ci))
    return OccupantTriage(
        seat=occupant.seat,
        body=occupant.body,
        impact=impact,
        method="lpm",
        triage=decide(p_corrected, p_ci_corrected, threshold),
        baseline=baseline,
        iss=IssEstimate(estimate=iss, ci95=iss_ci),
        region_ais=dict(nominal.assessment.region_ais),
        measures=measures,
        measures_ci95=measures_ci,
        interval_method=method,
        point_outside_interval=outside,
        probability_uncorrected=p,
        probability_zero_load=p0,
        sensor_inputs=SensorInputs(
            posture_deg=lpm_occupant.posture_lumbar_flexion_deg,
            posture_sd_deg=posture_sd,
            seat_track_mm=lpm_occupant.seat_track_mm,
            seat_track_sd_mm=track_sd,
        ),
    )


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
    used_lpm = False
    for i, occupant in enumerate(notification.occupants):
        impact = classify_impact(pulse.pdof_deg, occupant.seat, notification.drive_side)
        baseline = _baseline_decision(models, occupant, pulse, impact)
        answer: OccupantTriage | None = None
        if impact.in_lpm_coverage:
            params = models.parameter_sets[notification.vehicle_model]
            answer = _lpm_occupant(
                i, occupant, impact, pulse, params, models, baseline, assumptions
            )
            used_lpm = used_lpm or answer is not None
        elif not occupant.seat.front_row:
            assumptions.append(
                f"occupants[{i}]: {occupant.seat.value} seat: the occupant models are of the "
                "front row; statistical baseline used (fitted on front-seat occupants)"
            )
        else:
            assumptions.append(
                f"occupants[{i}]: PDOF {impact.pdof_deg:.0f} deg is outside every occupant "
                "model's coverage; statistical baseline used"
            )
        occupants.append(
            answer
            or OccupantTriage(
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
        models=_used_models(models, notification.vehicle_model, used_lpm),
        timings_ms={
            "pulse": 1000.0 * (t1 - t0),
            "occupants": 1000.0 * (t2 - t1),
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
) -> tuple[ProcessedPulse, list[OccupantSimulation], list[str]]:
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
    assumptions: list[str] = []
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
