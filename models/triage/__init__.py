"""The orchestrator: one notification in, one triage result out.

Flow per notification: the pulse is processed once (`models.pulse`); per
occupant the impact mode is classified (`models.impact_mode`). The decision is
the field risk model's (`models.field.risk_model`): P(ISS 15+), fitted on real
NASS-CDS crashes 1997-2014, from what the notification carries (delta-V and its
direction, crash mode by seat, belt, frontal airbag, seat, age, stature, mass,
rollover and quarter turns, multiple impacts, model year), decided at the
configured operating point, with each body region's risk and the vehicle's
P(anyone ISS 15+) beside it (a MAIS 3+ field model, 2.0.0, for recalls).
Occupants inside an occupant model's coverage are also simulated by that model
(`models.lpm`): its injury measures give region AIS, ISS and P(ISS >= 15)
(`models.injury`), less the risk curves' zero-load floor
(`models.risk_calibration`), with 95% intervals from the PCE surrogates
(`models.surrogate`) when loaded, else from direct runs over the
sensor-uncertainty box. That answer explains the decision (which body regions,
which measures) and is kept with its own decision as a second opinion, as is the
statistical baseline's (`models.baseline`) for every occupant. The case-level
decision is the worst occupant's. The field decision has a risk tier in the
field-triage guideline's terms (`models.tiers`): high (P at or above the high-risk
threshold, 20 % by default), moderate (at or above the operating point's
threshold), none; the vehicle's P(anyone ISS 15+) has its own.

Everything here is a pure function of the notification and the loaded models:
the same inputs and model versions give the same result, bit for bit (only
`timings_ms` varies).

One face: import from ``models.triage``, not from its modules (each is listed in
``docs/layout.md``). Imports run one way: result <- loading <- decision <-
occupant_model <- field_evidence <- run; simulation beside run.
"""

from models.tiers import (
    HIGH_RISK_THRESHOLD,
    RECOMMENDATIONS,
    ThresholdOrderError,
    Tier,
    recommendation,
    tier_of,
)
from models.triage.decision import (
    LPM_THRESHOLDS,
    decide,
)
from models.triage.field_evidence import (
    notification_field_inputs,
    occupant_evidence,
)
from models.triage.loading import (
    TRIAGE_SOURCES,
    EngineModels,
    load_engine_models,
    operating_thresholds,
    triage_code_sha256,
    warm_up,
)
from models.triage.result import (
    IntervalMethod,
    Method,
    OccupantTriage,
    TriageDecision,
    TriageResult,
    UnknownVehicleModel,
)
from models.triage.run import (
    triage,
)
from models.triage.simulation import (
    simulate_notification,
)

__all__ = [
    "LPM_THRESHOLDS",
    "IntervalMethod",
    "Method",
    "HIGH_RISK_THRESHOLD",
    "RECOMMENDATIONS",
    "ThresholdOrderError",
    "Tier",
    "operating_thresholds",
    "recommendation",
    "tier_of",
    "TRIAGE_SOURCES",
    "EngineModels",
    "OccupantTriage",
    "TriageDecision",
    "TriageResult",
    "UnknownVehicleModel",
    "decide",
    "load_engine_models",
    "warm_up",
    "occupant_evidence",
    "notification_field_inputs",
    "simulate_notification",
    "triage",
    "triage_code_sha256",
]
