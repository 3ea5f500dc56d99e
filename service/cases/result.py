"""Engine results -> wire models (one place, used by the API and the CLI)."""

from __future__ import annotations

import dataclasses
from datetime import datetime

from models.assumptions import Assumption
from models.triage import OccupantTriage, TriageDecision, TriageResult
from service.cases.notification import (
    AssumptionOut,
    CaseResult,
    HaversineOut,
    IssOut,
    ModelVersionOut,
    OccupantOut,
    PulseOut,
    SensorInputsOut,
    TriageOut,
)

__all__ = ["to_case_result"]


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
    )


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
        occupants=[_occupant_out(o) for o in result.occupants],
        pulse=PulseOut(
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
