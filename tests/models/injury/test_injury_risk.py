"""Risk curves: published values at documented points, monotonicity, shapes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from models.injury import risk
from models.notification import Body

M50 = Body.MALE_50TH
F05 = Body.FEMALE_5TH


def _logistic(alpha: float, beta: float, x: float) -> float:
    return 1.0 / (1.0 + math.exp(alpha - beta * x))


# ---------------------------------------------------------------- head


def test_prasad_mertz_at_hic_1000_matches_the_published_figures() -> None:
    # Wikipedia: HIC 1000 -> 18 % AIS4+, 55 % AIS3+, 90 % AIS2+ (within ~2 points).
    p = risk.hic_prasad_mertz_1999(1000.0)
    assert p.shape == (6,)
    assert p[1] == pytest.approx(0.90, abs=0.02)
    assert p[2] == pytest.approx(0.55, abs=0.025)
    assert p[3] == pytest.approx(0.18, abs=0.02)


@pytest.mark.parametrize("h", [150.0, 700.0, 1500.0])
def test_prasad_mertz_formula(h: float) -> None:
    p = risk.hic_prasad_mertz_1999(h)
    for n, (a, b) in enumerate(
        zip(risk.HIC_PRASAD_MERTZ_ALPHA, risk.HIC_PRASAD_MERTZ_BETA, strict=True)
    ):
        assert p[n] == pytest.approx(1 / (1 + math.exp(a + 200 / h - b * h)), rel=1e-12)


def test_prasad_mertz_is_forced_monotone_where_curves_cross() -> None:
    # Raw AIS6 exceeds raw AIS5+ above HIC ~3250 and AIS5+ exceeds AIS4+ above ~3740.
    h = 5000.0
    a, b = risk.HIC_PRASAD_MERTZ_ALPHA, risk.HIC_PRASAD_MERTZ_BETA
    raw = [1 / (1 + math.exp(a[n] + 200 / h - b[n] * h)) for n in range(6)]
    assert raw[5] > raw[4] > raw[3]
    p = risk.hic_prasad_mertz_1999(h)
    assert p[4] == pytest.approx(raw[3])
    assert p[5] == pytest.approx(raw[3])


def test_prasad_mertz_monotone_in_hic_and_level() -> None:
    p = risk.hic_prasad_mertz_1999(np.linspace(0.0, 8000.0, 4001))
    assert p.shape == (4001, 6)
    assert np.all(np.diff(p, axis=0) >= -1e-15)
    assert np.all(np.diff(p, axis=1) <= 0.0)
    assert np.all(p[0] == 0.0)


def test_ncap_2008_head_lognormal() -> None:
    assert risk.hic15_ais3_ncap_2008(math.exp(7.45231)) == pytest.approx(0.5)
    z = (math.log(700.0) - 7.45231) / 0.73998
    assert risk.hic15_ais3_ncap_2008(700.0) == pytest.approx(0.5 * math.erfc(-z / math.sqrt(2)))
    assert risk.hic15_ais3_ncap_2008(700.0) == pytest.approx(0.1116, abs=5e-4)
    assert risk.hic15_ais3_ncap_2008(0.0) == 0.0


# ---------------------------------------------------------------- neck


def test_eppinger_levels_and_forcing() -> None:
    p = risk.nij_eppinger_1999(0.0)
    assert math.isnan(p[0])
    assert math.isnan(p[5])
    assert p[1] == pytest.approx(_logistic(2.054, 1.195, 0.0))
    assert p[2] == pytest.approx(0.038, abs=5e-4)
    # Raw AIS4+ at Nij = 0 is 6.3 %, above AIS3+: forced down to AIS3+.
    assert _logistic(2.693, 1.195, 0.0) == pytest.approx(0.063, abs=5e-4)
    assert p[3] == pytest.approx(p[2])
    # Above Nij = 0.69 the published curves are nested and returned as published.
    q = risk.nij_eppinger_1999(1.5)
    assert q[3] == pytest.approx(_logistic(2.693, 1.195, 1.5))
    assert q[3] < q[2]
    grid = risk.nij_eppinger_1999(np.linspace(0, 3, 301))[:, 1:5]
    assert np.all(np.diff(grid, axis=1) <= 0.0)


def test_ncap_2008_neck() -> None:
    assert risk.nij_ais3_ncap_2008(1.0) == pytest.approx(_logistic(3.2269, 1.9688, 1.0))
    assert risk.nij_ais3_ncap_2008(1.0) == pytest.approx(0.2213, abs=5e-4)
    assert risk.neck_axial_force_ais3_ncap_2008(4.17, M50) == pytest.approx(
        _logistic(10.9745, 2.375, 4.17)
    )
    assert risk.neck_axial_force_ais3_ncap_2008(-2.62, F05) == pytest.approx(
        _logistic(10.958, 3.770, 2.62)
    )
    combined = risk.neck_ais3_ncap_2008(0.3, 6.0, 1.0, M50)
    assert combined == pytest.approx(_logistic(10.9745, 2.375, 6.0))


# ---------------------------------------------------------------- chest, abdomen, femur


def test_ncap_2008_chest_deflection() -> None:
    d = 63.0
    assert risk.chest_deflection_ais3_ncap_2008(d, M50) == pytest.approx(
        _logistic(10.5456, 1.568, d**0.4612)
    )
    assert risk.chest_deflection_ais3_ncap_2008(52.0, F05) == pytest.approx(
        _logistic(10.5456, 1.7212, 52.0**0.4612)
    )
    # Same deflection is riskier for the smaller dummy.
    assert risk.chest_deflection_ais3_ncap_2008(40.0, F05) > risk.chest_deflection_ais3_ncap_2008(
        40.0, M50
    )


@pytest.mark.parametrize("body", [M50, F05])
def test_age_curve_equals_ncap_at_35_and_rises_with_age(body: Body) -> None:
    d = np.linspace(0.0, 80.0, 17)
    np.testing.assert_allclose(
        risk.chest_deflection_ais3_laituri_2005(d, 35.0, body),
        risk.chest_deflection_ais3_ncap_2008(d, body),
        rtol=1e-4,
    )
    young = risk.chest_deflection_ais3_laituri_2005(40.0, 20.0, body)
    old = risk.chest_deflection_ais3_laituri_2005(40.0, 80.0, body)
    assert old > young
    logit_gap = math.log(old / (1 - old)) - math.log(young / (1 - young))
    assert logit_gap == pytest.approx(0.05861 * 60.0)


def test_cti_curve() -> None:
    # logistic(8.224, 7.125 CTI): 50 % at CTI = 8.224 / 7.125.
    assert risk.chest_cti_ais3_kleinberger_1998(8.224 / 7.125) == pytest.approx(0.5)
    assert risk.chest_cti_ais3_kleinberger_1998(1.0) == pytest.approx(_logistic(8.224, 7.125, 1.0))


@pytest.mark.parametrize(
    ("curve", "vc25"),
    [
        (risk.chest_vc_ais4_lau_viano_1986, 1.0),
        (risk.abdomen_vc_ais5_lau_viano_1986, 1.2),
        (risk.chest_vc_ais4_viano_1989_lateral, 1.47),
        (risk.abdomen_vc_ais4_viano_1989_lateral, 1.98),
    ],
)
def test_vc_curves_pass_through_the_published_25_percent_points(curve, vc25: float) -> None:  # type: ignore[no-untyped-def]
    assert curve(vc25) == pytest.approx(0.25)
    assert curve(risk.VC_RISK_SLOPE_RATIO * vc25) == pytest.approx(0.5)
    assert np.all(np.diff(curve(np.linspace(0, 4, 50))) > 0)


def test_femur_and_joint_risk() -> None:
    assert risk.femur_ais2_ncap_2008(10.0, M50) == pytest.approx(_logistic(5.7949, 0.5196, 10.0))
    assert risk.femur_ais2_ncap_2008(6.8, F05) == pytest.approx(_logistic(5.7949, 0.7619, 6.8))
    assert risk.ncap_2008_joint_risk(0.1, 0.2, 0.3, 0.0) == pytest.approx(1 - 0.9 * 0.8 * 0.7)
    assert risk.ncap_2008_relative_risk(0.15) == pytest.approx(1.0)


# ---------------------------------------------------------------- side


def test_side_curves() -> None:
    assert risk.thorax_rib_deflection_ais3_ncap_2008_es2re(44.0) == pytest.approx(
        _logistic(5.3895, 0.0919, 44.0)
    )
    assert risk.abdomen_force_ais3_ncap_2008_es2re(2500.0) == pytest.approx(
        _logistic(6.04044, 0.002133, 2500.0)
    )
    assert risk.pelvis_force_ais3_ncap_2008_es2re(6000.0) == pytest.approx(
        _logistic(7.5969, 0.0011, 6000.0)
    )
    assert risk.pelvis_force_ais3_ncap_2008_sid_iis(5525.0) == pytest.approx(
        _logistic(6.3055, 0.00094, 5525.0)
    )
    k = risk.thorax_rib_deflection_kuppa_es2re(30.0)
    assert k[2] == pytest.approx(_logistic(2.0975, 0.0482, 30.0))
    assert k[3] == pytest.approx(_logistic(3.4335, 0.0482, 30.0))
    assert np.isnan(k[[0, 1, 4, 5]]).all()


def test_force_monotone_skips_nan() -> None:
    out = risk.force_monotone([np.nan, 0.3, 0.5, np.nan, 0.2, 0.4])
    np.testing.assert_array_equal(np.isnan(out), [True, False, False, True, False, False])
    np.testing.assert_allclose(out[[1, 2, 4, 5]], [0.3, 0.3, 0.2, 0.2])


def test_nan_inputs_are_rejected() -> None:
    with pytest.raises(ValueError, match="`hic`"):
        risk.hic_prasad_mertz_1999(float("nan"))
