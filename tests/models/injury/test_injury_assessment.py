"""assess(): regional distributions, documented rules, ISS and P(ISS >= 15)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.injury import risk
from models.injury.assessment import InjuryMeasures, assess, region_cumulative_risk
from models.injury.criteria import cti
from models.injury.scores import ISS_REGIONS, p_iss_at_least
from models.notification import Body

M50 = Body.MALE_50TH
F05 = Body.FEMALE_5TH
UNINJURED = (1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def test_no_measures_means_no_injury() -> None:
    a = assess(InjuryMeasures(), M50)
    assert set(a.region_ais_probability) == set(ISS_REGIONS)
    assert all(p == UNINJURED for p in a.region_ais_probability.values())
    assert a.region_ais == dict.fromkeys(ISS_REGIONS, 0)
    assert a.iss == 0
    assert a.p_iss15 == 0.0


def test_distributions_are_complete_and_sum_to_one() -> None:
    m = InjuryMeasures(
        hic15=900.0,
        nij=0.7,
        chest_deflection_mm=45.0,
        chest_vc_m_s=0.9,
        chest_a3ms_g=55.0,
        abdomen_vc_m_s=1.1,
    )
    for mode in ImpactMode:
        a = assess(m, F05, age_years=70.0, impact_mode=mode.value)
        for region, p in a.region_ais_probability.items():
            assert len(p) == 7
            assert sum(p) == pytest.approx(1.0, abs=1e-12), region
            assert min(p) >= 0.0
        for region in ("face", "extremities", "external"):
            assert a.region_ais_probability[region] == UNINJURED
        assert a.p_iss15 == pytest.approx(p_iss_at_least(a.region_ais_probability))


def test_hic_alone_gives_the_prasad_mertz_distribution() -> None:
    a = assess(InjuryMeasures(hic15=1000.0), M50)
    cum = risk.hic_prasad_mertz_1999(1000.0)
    p = np.asarray(a.region_ais_probability["head_neck"])
    np.testing.assert_allclose(p[1:6], cum[:-1] - cum[1:], atol=1e-12)
    assert p[6] == pytest.approx(cum[5])
    # Median level: P(AIS >= 3) = 0.53 >= 0.5 > P(AIS >= 4) = 0.17.
    assert a.region_ais["head_neck"] == 3
    assert a.iss == 9
    # One injured region: ISS >= 15 iff its AIS >= 4 (16).
    assert a.p_iss15 == pytest.approx(cum[3])


def test_hic_and_nij_share_the_region_by_maximum() -> None:
    cum = region_cumulative_risk(InjuryMeasures(hic15=300.0, nij=1.2), M50)["head_neck"]
    h = risk.hic_prasad_mertz_1999(300.0)
    n = risk.nij_eppinger_1999(1.2)
    assert cum[0] == pytest.approx(max(h[0], n[1]))  # AIS1+: HIC, or Nij's AIS2+ as lower bound
    for k in (1, 2, 3, 4):
        assert cum[k] == pytest.approx(max(h[k], n[k]))
    assert cum[5] == pytest.approx(h[5])  # Nij publishes no AIS 6


def test_chest_deflection_alone_reaches_at_most_ais_3() -> None:
    a = assess(InjuryMeasures(chest_deflection_mm=90.0), M50)
    p = a.region_ais_probability["chest"]
    p3 = float(risk.chest_deflection_ais3_ncap_2008(90.0, M50))
    assert p[3] == pytest.approx(p3)
    assert p[1] == p[2] == p[4] == p[5] == p[6] == 0.0
    assert a.region_ais["chest"] == 3
    assert a.p_iss15 == 0.0  # 9 < 15 with a single region


def test_age_selects_the_age_dependent_chest_curve() -> None:
    m = InjuryMeasures(chest_deflection_mm=40.0)
    p_none = region_cumulative_risk(m, M50)["chest"][2]
    p_35 = region_cumulative_risk(m, M50, age_years=35.0)["chest"][2]
    p_80 = region_cumulative_risk(m, M50, age_years=80.0)["chest"][2]
    assert p_35 == pytest.approx(p_none, rel=1e-4)
    assert p_80 > p_35


def test_side_modes_use_side_curves() -> None:
    m = InjuryMeasures(chest_deflection_mm=40.0, chest_vc_m_s=1.0, abdomen_vc_m_s=1.5)
    for mode in ("near_side", "far_side"):
        cum = region_cumulative_risk(m, M50, age_years=80.0, impact_mode=mode)
        assert cum["chest"][2] == pytest.approx(
            max(
                float(risk.thorax_rib_deflection_ais3_ncap_2008_es2re(40.0)),
                float(risk.chest_vc_ais4_viano_1989_lateral(1.0)),
            )
        )
        assert cum["chest"][3] == pytest.approx(float(risk.chest_vc_ais4_viano_1989_lateral(1.0)))
        assert cum["abdomen"][3] == pytest.approx(
            float(risk.abdomen_vc_ais4_viano_1989_lateral(1.5))
        )
        assert cum["abdomen"][4] == 0.0
    rear = region_cumulative_risk(m, M50, impact_mode="rear")
    front = region_cumulative_risk(m, M50, impact_mode=ImpactMode.FRONTAL)
    for region in ISS_REGIONS:
        np.testing.assert_array_equal(rear[region], front[region])
    assert front["abdomen"][4] == pytest.approx(float(risk.abdomen_vc_ais5_lau_viano_1986(1.5)))


def test_cti_is_computed_from_a3ms_and_deflection_when_missing() -> None:
    implicit = assess(InjuryMeasures(chest_deflection_mm=30.0, chest_a3ms_g=70.0), F05)
    explicit = assess(
        InjuryMeasures(chest_deflection_mm=30.0, chest_a3ms_g=70.0, chest_cti=cti(70.0, 30.0, F05)),
        F05,
    )
    assert implicit == explicit
    only_a3ms = assess(InjuryMeasures(chest_a3ms_g=70.0), F05)
    assert only_a3ms.region_ais_probability["chest"] == UNINJURED


def test_two_injured_regions_cross_the_threshold_together() -> None:
    m = InjuryMeasures(hic15=1000.0, chest_deflection_mm=70.0)
    a = assess(m, M50)
    head = risk.hic_prasad_mertz_1999(1000.0)
    chest3 = float(risk.chest_deflection_ais3_ncap_2008(70.0, M50))
    # ISS >= 15: head AIS >= 4, or head AIS 3 with chest AIS 3 (18).
    expected = head[3] + (head[2] - head[3]) * chest3
    assert a.p_iss15 == pytest.approx(expected)
    assert a.iss == 18
    assert a.region_ais == {**dict.fromkeys(ISS_REGIONS, 0), "head_neck": 3, "chest": 3}


def test_p_iss15_increases_with_hic() -> None:
    values = [assess(InjuryMeasures(hic15=h, nij=0.5), M50).p_iss15 for h in (100, 500, 1000, 2000)]
    assert values == sorted(values)
    assert values[-1] > values[0]


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"measures": InjuryMeasures(hic15=-1.0)}, "measures.hic15"),
        ({"measures": InjuryMeasures(nij=float("nan"))}, "measures.nij"),
        ({"impact_mode": "oblique"}, "impact_mode"),
        ({"age_years": -3.0}, "age_years"),
        ({"body": "male_95th"}, "body"),
    ],
)
def test_validation(kwargs: dict[str, object], name: str) -> None:
    args: dict[str, object] = {"measures": InjuryMeasures(), "body": M50}
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        assess(**args)  # type: ignore[arg-type]


def test_result_types_are_frozen() -> None:
    a = assess(InjuryMeasures(hic15=500.0), M50)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.iss = 3  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        InjuryMeasures().nij = 1.0  # type: ignore[misc]
