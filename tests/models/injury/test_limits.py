"""The injury limits shown beside each measure are the engine's published constants."""

from __future__ import annotations

import pytest

from models.impact_mode import ImpactMode
from models.injury import criteria, risk
from models.injury.limits import SIDE_MODES, injury_limit
from models.notification import Body


def test_injury_limits_are_the_engines_published_constants() -> None:
    frontal = {
        m: injury_limit(m, ImpactMode.FRONTAL, Body.FEMALE_5TH)
        for m in ("hic15", "nij", "chest_deflection_mm", "chest_a3ms_g", "chest_vc_m_s")
    }
    assert frontal["hic15"] is not None
    assert frontal["nij"] is not None
    assert frontal["hic15"].value == criteria.FMVSS208_HIC15_LIMIT == 700.0
    assert frontal["nij"].value == criteria.FMVSS208_NIJ_LIMIT
    deflection = frontal["chest_deflection_mm"]
    assert deflection is not None
    assert deflection.value == criteria.FMVSS208_CHEST_DEFLECTION_LIMIT_MM[Body.FEMALE_5TH]
    assert frontal["chest_vc_m_s"] is not None
    assert frontal["chest_vc_m_s"].value == risk.VC_TOLERANCE_LAU_VIANO_1986_CHEST
    side_vc = injury_limit("abdomen_vc_m_s", ImpactMode.NEAR_SIDE, Body.MALE_50TH)
    assert side_vc is not None
    assert side_vc.value == risk.VC_TOLERANCE_VIANO_1989_ABDOMEN
    # no limit held by the engine: shown without one
    assert injury_limit("chest_cti", ImpactMode.FRONTAL, Body.MALE_50TH) is None
    assert injury_limit("chest_deflection_mm", ImpactMode.FAR_SIDE, Body.MALE_50TH) is None


@pytest.mark.parametrize("mode", list(ImpactMode))
def test_the_side_modes_measure_rib_deflection_and_take_the_lateral_vc(mode: ImpactMode) -> None:
    deflection = injury_limit("chest_deflection_mm", mode, Body.MALE_50TH)
    chest_vc = injury_limit("chest_vc_m_s", mode, Body.MALE_50TH)
    assert chest_vc is not None
    if mode in SIDE_MODES:
        assert deflection is None
        assert chest_vc.value == risk.VC_TOLERANCE_VIANO_1989_CHEST
    else:
        assert deflection is not None
        assert deflection.value == 63.0
        assert chest_vc.value == risk.VC_TOLERANCE_LAU_VIANO_1986_CHEST
    assert SIDE_MODES == {ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE}
