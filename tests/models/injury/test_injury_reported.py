"""The region AIS the service reports: never AIS 6 from a dummy measure (issue 39, item 4)."""

from __future__ import annotations

import itertools

import pytest

from models.injury.assessment import InjuryMeasures, assess
from models.injury.reported import MAX_REPORTED_AIS, reported_levels
from models.injury.scores import ISS_REGIONS, iss, p_iss_at_least
from models.notification import Body


@pytest.mark.parametrize("hic", [2_500.0, 5_405.0, 35_000.0])
def test_a_head_hic_in_the_thousands_is_reported_at_most_ais_5(hic: float) -> None:
    a = assess(InjuryMeasures(hic15=hic, nij=2.0), Body.MALE_50TH, 40.0, "near_side")
    assert a.region_ais["head_neck"] == 6  # the curves' median level
    shown = reported_levels(a.region_ais)
    assert shown.region_ais["head_neck"] == MAX_REPORTED_AIS
    assert shown.capped == ("head_neck",)
    assert a.iss == 75  # any AIS 6 makes ISS 75
    assert shown.iss == 25  # head/neck AIS 5 alone, the other regions uninjured


def test_levels_below_the_cap_are_unchanged_and_nothing_is_flagged() -> None:
    for levels in itertools.product(range(6), repeat=3):
        region_ais = dict(zip(("head_neck", "chest", "abdomen"), levels, strict=True))
        shown = reported_levels(region_ais)
        assert shown.region_ais == region_ais
        assert shown.capped == ()
        assert shown.iss == iss(region_ais)


def test_the_cap_cannot_move_p_iss15() -> None:
    """AIS 5 and AIS 6 both give ISS >= 15, so P(ISS >= 15) does not depend on the cap."""
    dist6 = [0.0, 0.0, 0.0, 0.0, 0.0, 0.2, 0.8]
    dist5 = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]
    zero = [1.0] + [0.0] * 6
    for dist in (dist6, dist5):
        regions = {r: dist if r == "head_neck" else zero for r in ISS_REGIONS}
        assert p_iss_at_least(regions, 15) == pytest.approx(1.0)
