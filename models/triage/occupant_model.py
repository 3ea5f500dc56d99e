"""The occupant-model explanation: direct occupant-model runs (`models.lpm`), their
injury scores and P(ISS >= 15), and the 95% intervals from the PCE surrogates or
from direct runs over the sensor-uncertainty box."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

from models.assumptions import Assumption, AssumptionCode
from models.constants import Z_95
from models.impact_mode import ImpactClassification, ImpactMode
from models.injury.assessment import InjuryMeasures
from models.injury.reported import (
    MAX_REPORTED_AIS,
    SIDE_TESTED_MAX_DELTA_V_KMH,
    ReportedLevels,
    reported_levels,
)
from models.lpm.domain import POSTURE_RANGE_DEG, SEAT_TRACK_RANGE_MM, clamp
from models.lpm.params import ParameterSet
from models.lpm.simulate import LpmResult, simulate
from models.notification import (
    AirbagState,
    Occupant,
    SeatTrackSource,
)
from models.pulse import ProcessedPulse
from models.risk_calibration import (
    corrected_probability,
    zero_load_probability,
)
from models.sensor_evidence import resolve_sensor_evidence
from models.surrogate.evaluate import (
    UncertaintyResult,
)
from models.surrogate.spec import P_RESOLUTION
from models.triage.decision import LPM_THRESHOLDS, decide
from models.triage.loading import EngineModels
from models.triage.result import IntervalMethod, IssEstimate, SensorInputs, TriageDecision

__all__ = []


#: Surrogate inputs that describe the crash (not the occupant sensors): a surrogate
#: is not extrapolated in them.
_CRASH_INPUTS = frozenset({"delta_v_kmh", "angle_deg", "duration_ms"})


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


def _reported(
    index: int,
    nominal: LpmResult,
    impact: ImpactClassification,
    pulse: ProcessedPulse,
    iss_ci: tuple[float, float],
    assumptions: list[Assumption],
) -> tuple[ReportedLevels, tuple[float, float]]:
    """The region AIS and ISS as reported (never AIS 6 from a measure), flagged.

    The ISS interval is the surrogate's (of the curves' levels), widened to hold
    the reported ISS when the cap lowered it.
    """
    assert nominal.assessment is not None
    shown = reported_levels(nominal.assessment.region_ais)
    if shown.capped:
        assumptions.append(
            Assumption(
                AssumptionCode.OCCUPANT_MODEL_AIS_CAPPED,
                f"occupants[{index}]: the occupant model's risk curves give AIS 6 in "
                f"{', '.join(shown.capped)} (ISS {nominal.assessment.iss}); reported at AIS "
                f"{MAX_REPORTED_AIS} (ISS {shown.iss}): a dummy measure cannot represent AIS 6",
                index,
            )
        )
        iss_ci = (min(iss_ci[0], float(shown.iss)), max(iss_ci[1], float(shown.iss)))
    lateral = abs(pulse.delta_v_lateral_kmh)
    side = impact.mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE)
    if side and lateral > SIDE_TESTED_MAX_DELTA_V_KMH:
        assumptions.append(
            Assumption(
                AssumptionCode.SIDE_BEYOND_TESTED_SEVERITY,
                f"occupants[{index}]: lateral delta-V {lateral:.0f} km/h is above the side "
                f"crash tests the side occupant models were checked against (up to "
                f"{SIDE_TESTED_MAX_DELTA_V_KMH:g} km/h): their measures are an extrapolation",
                index,
            )
        )
    return shown, iss_ci


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
    shown, iss_ci = _reported(index, nominal, impact, pulse, iv.iss_ci, assumptions)
    return _LpmAnswer(
        decision=decide(corrected_probability(iv.p, p0), p_ci, LPM_THRESHOLDS[impact.mode]),
        iss=IssEstimate(estimate=shown.iss, ci95=iss_ci),
        region_ais=shown.region_ais,
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
