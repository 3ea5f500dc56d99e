"""Interior geometry per seat: the front passenger has his own panel and airbag."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.lpm import kernel as K
from models.lpm.params import ParameterSet
from models.lpm.pulses import ncap_frontal_pulse
from models.lpm.simulate import prepare, simulate
from models.notification import Body, Occupant, Seat
from tests.models.lpm.helpers import occupant
from tests.models.lpm.test_published import FRONTAL_RANGES


def _passenger(body: Body = Body.MALE_50TH, *, airbag: bool = True) -> Occupant:
    return dataclasses.replace(occupant(body, airbag=airbag), seat=Seat.FRONT_PASSENGER)


def test_passenger_has_no_wheel_and_the_passenger_bag(params: ParameterSet) -> None:
    occ = _passenger()
    pr = prepare(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occ, params)
    drv = prepare(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(), params)
    names = pr.model.contact_names
    assert names == drv.model.contact_names  # same history keys for both seats
    for name in ("wheel_chest", "wheel_head"):
        assert pr.model.ct[names.index(name), K.C_EN] == 0.0
    bag = names.index("airbag_chest")
    assert not np.array_equal(pr.model.ct[bag], drv.model.ct[bag])
    assert pr.model.bag[2] == params["frontal.passenger.airbag.depth"]
    knee = names.index("knee_bolster")
    gap = params["frontal.passenger.knee_gap"] - params["frontal.knee.gap"]
    assert pr.model.ct[knee, K.C_AX] == pytest.approx(drv.model.ct[knee, K.C_AX] + gap)
    r = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occ, params)
    assert r.info["airbag_depth_m"] == params["frontal.passenger.airbag.depth"]
    assert np.all(r.histories["force_wheel_head_n"] == 0.0)
    assert np.max(r.histories["force_airbag_head_n"]) > 0.0


@pytest.mark.parametrize("body", list(Body))
def test_belted_passenger_with_airbag_inside_fmvss208_limits(
    params: ParameterSet, body: Body
) -> None:
    """FMVSS 208 applies the same limits to the right front passenger."""
    r = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, _passenger(body), params)
    assert r.status == 0
    for k, (lo, hi) in FRONTAL_RANGES.items():
        if k == "chest_deflection_mm" and body is Body.FEMALE_5TH:
            hi = 52.0  # FMVSS 208 5F limit (injury-criteria.md s1 [U])
        v = getattr(r.measures, k)
        assert lo <= v <= hi, f"{k} = {v:.2f} outside [{lo}, {hi}]"


def test_passenger_without_airbag_is_not_hit_by_a_wheel(params: ParameterSet) -> None:
    """Belted, no airbag: the driver's head meets the wheel, the passenger's does not."""
    drv = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(airbag=False), params)
    pas = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, _passenger(airbag=False), params)
    assert np.max(drv.histories["force_wheel_head_n"]) > 0.0
    assert pas.measures.hic15 is not None
    assert drv.measures.hic15 is not None
    assert pas.measures.hic15 < drv.measures.hic15
