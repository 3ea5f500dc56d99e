"""Properties of the engine's answer over random notifications (hypothesis)."""

from __future__ import annotations

import math

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from models.notification import AirbagState, Body, Occupant, Seat, summary_notification
from models.triage import load_engine_models, triage

MODELS = load_engine_models()

occupants = st.builds(
    Occupant,
    seat=st.sampled_from(list(Seat)),
    body=st.sampled_from(list(Body)),
    belted=st.booleans(),
    frontal_airbag=st.sampled_from(list(AirbagState)),
    side_airbag=st.one_of(st.none(), st.sampled_from(list(AirbagState))),
    age_years=st.one_of(st.none(), st.floats(16.0, 95.0)),
    posture_lumbar_flexion_deg=st.floats(0.0, 30.0),
    seat_track_mm=st.floats(-150.0, 150.0),
)


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    delta_v=st.floats(5.0, 130.0),
    pdof=st.floats(0.0, 359.9),
    occupant=occupants,
)
def test_every_answer_is_a_consistent_decision(
    delta_v: float, pdof: float, occupant: Occupant
) -> None:
    result = triage(summary_notification((occupant,), delta_v, pdof), MODELS)
    occ = result.occupants[0]
    d = occ.triage
    lo, hi = d.probability_ci95
    assert 0.0 <= d.probability <= 1.0
    assert 0.0 <= lo <= hi <= 1.0
    assert d.iss15_plus == (d.probability >= d.threshold)
    assert lo <= d.probability <= hi, "the decided probability lies inside its interval"
    assert d.outcome == "ISS15+"
    assert occ.region_risk is not None
    for r in occ.region_risk.values():
        assert r.ci95[0] <= r.probability <= r.ci95[1]
    if occ.method == "lpm":
        assert occ.probability_uncorrected is not None
        assert occ.probability_zero_load is not None
        m = occ.occupant_model
        assert m is not None
        assert m.probability <= occ.probability_uncorrected
        m_lo, m_hi = m.probability_ci95
        assert m_lo <= m.probability <= m_hi or occ.point_outside_interval
        assert occ.iss is not None
        assert 0 <= occ.iss.estimate <= 75
        assert occ.measures is not None
        assert all(math.isfinite(v) and v >= 0.0 for v in occ.measures.values())
    assert result.triage.probability == max(o.triage.probability for o in result.occupants)
