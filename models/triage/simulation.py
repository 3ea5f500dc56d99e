"""Direct occupant-model runs of a notification with their full time histories:
for the command line's ``simulate`` and the offline checks, not the request path."""

from __future__ import annotations

from dataclasses import dataclass

from models.assumptions import Assumption
from models.impact_mode import ImpactClassification, classify_impact
from models.lpm.simulate import LpmResult
from models.notification import (
    CrashNotification,
    Occupant,
)
from models.pulse import ProcessedPulse, process_pulse
from models.sensor_evidence import resolve_sensor_evidence
from models.triage.loading import EngineModels
from models.triage.occupant_model import _in_domain, _run
from models.triage.result import UnknownVehicleModel

__all__ = ["OccupantSimulation", "simulate_notification"]


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
