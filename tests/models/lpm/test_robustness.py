"""Robustness over random in-coverage inputs: finite outputs, valid statuses."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from models.impact_mode import ImpactMode
from models.lpm.params import load_parameter_set
from models.lpm.pulses import haversine_pulse
from models.lpm.simulate import simulate
from models.notification import AirbagState, Body, Occupant, Seat

PARAMS = load_parameter_set()
AXIS = {
    ImpactMode.FRONTAL: 0.0,
    ImpactMode.NEAR_SIDE: 270.0,
    ImpactMode.REAR: 180.0,
    ImpactMode.FAR_SIDE: 90.0,
}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    mode=st.sampled_from(list(ImpactMode)),
    obliquity=st.floats(-20.0, 20.0),
    dv=st.floats(5.0, 70.0),
    duration_ms=st.floats(40.0, 140.0),
    body=st.sampled_from(list(Body)),
    seat=st.sampled_from(list(Seat)),
    belted=st.booleans(),
    airbag=st.sampled_from(list(AirbagState)),
    side_airbag=st.one_of(st.none(), st.sampled_from(list(AirbagState))),
    lean=st.floats(5.8, 25.0),
    track=st.floats(-100.0, 100.0),
    fire_ms=st.one_of(st.none(), st.floats(5.0, 60.0)),
)
def test_random_cases_are_finite(
    mode: ImpactMode,
    obliquity: float,
    dv: float,
    duration_ms: float,
    body: Body,
    seat: Seat,
    belted: bool,
    airbag: AirbagState,
    side_airbag: AirbagState | None,
    lean: float,
    track: float,
    fire_ms: float | None,
) -> None:
    occ = Occupant(
        seat=seat,
        body=body,
        belted=belted,
        frontal_airbag=airbag,
        side_airbag=side_airbag,
        airbag_fire_time_ms=fire_ms,
        posture_lumbar_flexion_deg=lean,
        seat_track_mm=track,
    )
    t, ax, ay = haversine_pulse(dv, duration_ms / 1000.0, angle_deg=AXIS[mode] + obliquity)
    r = simulate(t, ax, ay, mode, occ, PARAMS, angle_deg=obliquity)
    assert r.status in (0, 1)
    assert r.angle_deg == obliquity
    for name, h in r.histories.items():
        assert np.all(np.isfinite(h)), name
    for v in vars(r.measures).values():
        assert v is None or (np.isfinite(v) and v >= 0.0)
    assert r.assessment is not None
    assert 0 <= r.assessment.iss <= 75
