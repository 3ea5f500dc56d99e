"""Contact penetrations are continuous in time (kernel ``ARM_TIME_S``, ``EDGE_RADIUS_M``).

Before the arming state and the rounded surface ends, a head that went around
the end of the wheel rim or of the bag face and came back into the span from
behind met the surface at once tens of millimetres deep: a force step of
several kN in one 0.1 ms step. Measured on the surrogates' held-out points
then: the wheel-head penetration jumped by more than 5 mm in one step in 14 %
of the runs of the belted 50M without airbag, the head-in-bag penetration in
about half of the runs with an airbag; and Nij of the belted 50M without
airbag was 1.19 at 55 km/h against 0.74-0.83 at 54 and 56 km/h.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from models.impact_mode import ImpactMode
from models.lpm.params import ParameterSet
from models.lpm.pulses import haversine_pulse
from models.lpm.simulate import simulate
from models.notification import AirbagState, Body
from tests.models.lpm.helpers import occupant

#: Largest penetration change in one output step (0.1 ms), m: a surface met
#: from the front at the highest relative speeds of these cases (unrestrained
#: head on the windshield, ~25 m/s at 90 km/h) moves 2.5 mm per step.
MAX_STEP_M = 0.004


def _max_penetration_step(result_histories: dict[str, np.ndarray]) -> tuple[float, str]:
    """Largest one-step rise of a contact's penetration, m, and the contact.

    Rises only: a contact that is lost in one step (a structure crushed
    through beyond its give, ``kernel`` "deep behind" test, or a point more
    than ``EDGE_RADIUS_M`` behind the face sliding past its end) drops its
    penetration to zero at once; that is the loss of a contact, not a
    surface met from behind.
    """
    worst, name = 0.0, ""
    for key, pen in result_histories.items():
        if key.startswith("penetration_") and pen.size > 1:
            step = float(np.max(np.diff(pen)))
            if step > worst:
                worst, name = step, key
    return worst, name


def test_frontal_penetrations_do_not_jump() -> None:
    """40 seeded random frontal cases over both dummies, every belt x airbag
    combination, 20-90 km/h, posture, seat track and pulse duration."""
    from models.lpm.params import load_parameter_set

    params = load_parameter_set()
    rng = np.random.default_rng(20261201)
    bad = []
    for i in range(40):
        body = (Body.MALE_50TH, Body.FEMALE_5TH)[i % 2]
        belted, bag = ((True, True), (True, False), (False, True), (False, False))[(i // 2) % 4]
        dv = float(rng.uniform(20.0, 90.0))
        duration = float(rng.uniform(0.05, 0.13))
        occ = occupant(
            body,
            belted=belted,
            airbag=bag,
            lean_deg=float(rng.uniform(0.0, 25.0)),
            track_mm=float(rng.uniform(-120.0, 120.0)),
        )
        r = simulate(*haversine_pulse(dv, duration), ImpactMode.FRONTAL, occ, params)
        step, name = _max_penetration_step(dict(r.histories))
        if step > MAX_STEP_M:
            bad.append((i, body.value, belted, bag, round(dv, 1), name, round(step, 4)))
    assert bad == []


def test_no_neck_load_spike_from_a_surface_met_from_behind(params: ParameterSet) -> None:
    """The belted 50M, airbag not deployed (the surrogate family's occupant and
    pulse shape, 90 ms): Nij varies smoothly over 54-56 km/h (it was 1.19 at 55
    km/h and 0.74-0.83 beside it)."""
    occ = replace(occupant(Body.MALE_50TH, belted=True), frontal_airbag=AirbagState.NOT_DEPLOYED)
    nijs = []
    for dv in (54.0, 55.0, 56.0):
        r = simulate(*haversine_pulse(dv, 0.09), ImpactMode.FRONTAL, occ, params)
        assert r.measures.nij is not None
        nijs.append(r.measures.nij)
    assert max(nijs) <= 1.15 * min(nijs), nijs
