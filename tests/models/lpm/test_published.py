"""Against published values (issue 4, "Done when").

Frontal: a belted, airbag-equipped Hybrid III 50M in a 56 km/h full-width
rigid-barrier pulse of a compact car. The range each measure must fall in:

* upper bounds: the FMVSS 208 injury limits for this very test (56 km/h
  rigid barrier, belted 50M), which every car sold in the US meets and which
  NCAP reports against: HIC15 <= 700 [V] (49 CFR 571.208 S6.2), Nij <= 1.0,
  chest deflection <= 63 mm, chest 3 ms <= 60 g [U]
  (shared/reference/injury-criteria.md section 1; constants in
  models/injury/criteria.py);
* lower bounds: a belted 50M at 56 km/h always loads the restraints; NCAP
  frontal results of airbag-era small cars have HIC15 of the order of
  100-600 and chest deflections of 20-50 mm (the 2007 Yaris moderate-overlap
  test, a different test, gave HIC15 612, injury-criteria.md section 6 [U]).
  The lower bounds below (HIC15 >= 80, deflection >= 15 mm, Nij >= 0.1,
  3 ms >= 25 g) are engineering floors [R]; the NCAP-MGA-2006-011 (2010
  Yaris) dummy values are not in the references yet (open item).

Published dummy values of small cars (models/lpm/data/PUBLISHED_NCAP.md):
no US NCAP frontal dummy values of a 2008-2014 small car were found in the
sources reachable here; the published values closest to the class are the
IIHS moderate-overlap results (64 km/h, 40 % offset deformable barrier,
Hybrid III 50M driver, airbag and belt): IIHS microcar data table (2012 Scion
iQ HIC15 222, Nij 0.31, chest 28 mm; 2011 Smart Fortwo 234, 0.30, 22 mm; 2008
Smart Fortwo 621, 0.48, 25 mm), the IIHS 2007 Nissan Versa test (HIC15 492,
Nij 0.37, chest 29 mm) and the IIHS 2009 Honda Fit test (HIC 264).
The offset test is a different pulse (longer, one-sided crush), so the
model's NCAP-pulse values are compared with the published span widened by a
stated 25 % on each side, not calibrated to it.

Near side: the reference paper's 50 km/h moving-barrier case without side
airbags gives ISS >= 15 for the restrained 50M (paper section 3.2: "only the
side impact MVCs were serious ... due to the absence of side impact airbags").
"""

from __future__ import annotations

import pytest

from models.impact_mode import ImpactMode
from models.injury.criteria import (
    FMVSS208_CHEST_A3MS_LIMIT_G,
    FMVSS208_CHEST_DEFLECTION_LIMIT_MM,
    FMVSS208_HIC15_LIMIT,
    FMVSS208_NIJ_LIMIT,
)
from models.lpm.params import ParameterSet
from models.lpm.pulses import ncap_frontal_pulse, side_pulse
from models.lpm.simulate import simulate
from models.notification import Body
from tests.models.lpm.helpers import occupant

#: Published (upper) and floor (lower) bounds per measure, see the module docstring.
FRONTAL_RANGES = {
    "hic15": (80.0, FMVSS208_HIC15_LIMIT),
    "nij": (0.1, FMVSS208_NIJ_LIMIT),
    "chest_deflection_mm": (15.0, FMVSS208_CHEST_DEFLECTION_LIMIT_MM[Body.MALE_50TH]),
    "chest_a3ms_g": (25.0, FMVSS208_CHEST_A3MS_LIMIT_G),
}


def test_ncap_frontal_belted_airbag_50m_inside_published_ranges(params: ParameterSet) -> None:
    r = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(Body.MALE_50TH), params)
    assert r.status == 0
    for k, (lo, hi) in FRONTAL_RANGES.items():
        v = getattr(r.measures, k)
        assert lo <= v <= hi, f"{k} = {v:.2f} outside [{lo}, {hi}]"


#: Published span (min, max) of the small-car values above, per measure.
PUBLISHED_SMALL_CAR = {
    "hic15": (222.0, 621.0),
    "nij": (0.30, 0.48),
    "chest_deflection_mm": (22.0, 29.0),
}
#: Allowance for the different test (offset deformable barrier at 64 km/h vs
#: the full-width rigid barrier at 56 km/h) [R].
TEST_DIFFERENCE = 0.25


def test_ncap_frontal_belted_airbag_50m_near_published_small_car_values(
    params: ParameterSet,
) -> None:
    r = simulate(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(Body.MALE_50TH), params)
    for k, (lo, hi) in PUBLISHED_SMALL_CAR.items():
        v = getattr(r.measures, k)
        lo_ok, hi_ok = lo * (1.0 - TEST_DIFFERENCE), hi * (1.0 + TEST_DIFFERENCE)
        assert lo_ok <= v <= hi_ok, f"{k} = {v:.2f} outside [{lo_ok:.2f}, {hi_ok:.2f}]"


@pytest.mark.parametrize("body", list(Body))
def test_near_side_50_kmh_without_side_airbags_is_iss15(params: ParameterSet, body: Body) -> None:
    """IIHS-type side test: 1500 kg barrier at 50 km/h into a 1100 kg car."""
    r = simulate(*side_pulse(), ImpactMode.NEAR_SIDE, occupant(body), params)
    assert r.assessment is not None
    assert r.assessment.iss >= 15, (r.measures, r.assessment.region_ais)
