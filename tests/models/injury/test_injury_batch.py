"""The batch P(ISS >= 15) equals the scalar assessment, case by case."""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.injury.assessment import InjuryMeasures, assess, region_cumulative_risk
from models.injury.batch import (
    p_iss15_batch,
    p_iss_at_least_batch,
    region_cumulative_risk_batch,
)
from models.injury.scores import p_iss_at_least
from models.notification import Body
from models.surrogate.spec import MODE_OUTPUTS

#: Measures each LPM mode produces.
MODE_MEASURES = {
    m: tuple(o for o in outs if o not in ("p_iss15", "iss")) for m, outs in MODE_OUTPUTS.items()
}
#: Ranges the random measures are drawn over: from zero to well past every
#: curve's saturation (HIC 4000, Nij 4, 90 mm, 3 m/s, 150 g, CTI 2.5).
SCALES = {
    "hic15": 4000.0,
    "nij": 4.0,
    "chest_deflection_mm": 90.0,
    "chest_vc_m_s": 3.0,
    "chest_a3ms_g": 150.0,
    "chest_cti": 2.5,
    "abdomen_vc_m_s": 3.0,
}


def _random_measures(names: tuple[str, ...], n: int, seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    out = {}
    for k in names:
        v = SCALES[k] * rng.random(n) ** 2  # dense near zero, where the curves start
        v[:3] = 0.0  # exact zeros: the HIC curve's limit
        out[k] = v
    return out


@pytest.mark.parametrize("mode", list(ImpactMode))
@pytest.mark.parametrize("body", list(Body))
@pytest.mark.parametrize("age", [None, 25.0, 70.0])
def test_batch_equals_the_scalar_assessment(
    mode: ImpactMode, body: Body, age: float | None
) -> None:
    names = MODE_MEASURES[mode]
    values = _random_measures(
        names, 300, seed=zlib.crc32(f"{mode.value} {body.value} {age}".encode())
    )
    batch = p_iss15_batch(values, body, age, mode)
    cum = region_cumulative_risk_batch(values, body, age, mode)
    for i in range(batch.size):
        m = InjuryMeasures(**{k: float(v[i]) for k, v in values.items()})
        ref = assess(m, body, age, mode.value)
        assert batch[i] == pytest.approx(ref.p_iss15, rel=1e-12, abs=1e-15)
        ref_cum = region_cumulative_risk(m, body, age, mode.value)
        for region, c in ref_cum.items():
            np.testing.assert_allclose(cum[region][:, i], c, rtol=1e-14, atol=1e-15)


def test_batch_spans_the_probability_range() -> None:
    """The random sets reach both certain and unlikely ISS >= 15 (the check is not vacuous)."""
    values = _random_measures(MODE_MEASURES[ImpactMode.FRONTAL], 300, seed=1)
    p = p_iss15_batch(values, Body.MALE_50TH)
    assert p.min() < 0.05
    assert p.max() > 0.95


@pytest.mark.parametrize("threshold", [1, 9, 15, 16, 25, 50, 75])
def test_thresholds_match_the_exact_enumeration(threshold: int) -> None:
    values = _random_measures(MODE_MEASURES[ImpactMode.NEAR_SIDE], 50, seed=threshold)
    batch = p_iss_at_least_batch(values, Body.FEMALE_5TH, None, ImpactMode.NEAR_SIDE, threshold)
    for i in range(batch.size):
        m = InjuryMeasures(**{k: float(v[i]) for k, v in values.items()})
        ref = assess(m, Body.FEMALE_5TH, None, "near_side")
        assert batch[i] == pytest.approx(
            p_iss_at_least(ref.region_ais_probability, threshold), rel=1e-12, abs=1e-15
        )


def test_no_evidence_is_no_risk() -> None:
    assert p_iss15_batch({}, Body.MALE_50TH).shape == (0,)
    p = p_iss15_batch({"hic15": np.zeros(4)}, Body.MALE_50TH)
    np.testing.assert_array_equal(p, assess(InjuryMeasures(hic15=0.0), Body.MALE_50TH).p_iss15)


def test_bad_input_is_rejected() -> None:
    with pytest.raises(ValueError, match="unknown"):
        p_iss15_batch({"femur_kn": np.ones(2)}, Body.MALE_50TH)
    with pytest.raises(ValueError, match="non-negative"):
        p_iss15_batch({"hic15": np.array([1.0, -1.0])}, Body.MALE_50TH)
    with pytest.raises(ValueError, match="same number"):
        p_iss15_batch({"hic15": np.ones(2), "nij": np.ones(3)}, Body.MALE_50TH)
    with pytest.raises(ValueError, match="at most 75"):
        p_iss_at_least_batch({"hic15": np.ones(2)}, Body.MALE_50TH, threshold=76)


def test_nested_hic_levels_need_no_cumulative_minimum() -> None:
    """Up to AIS 4 the Prasad/Mertz curves are nested: the levels asked alone give
    the cumulative minimum's numbers, bit for bit (HIC 0 to far beyond any crash)."""
    from itertools import combinations

    from models.injury.batch import _hic_curves, _hic_curves_at

    rng = np.random.default_rng(5)
    hic = np.concatenate(
        [[0.0, 1e-300, 1e-9, 1.0, 200.0, 3250.0, 3740.0, 1e5, 1e12], rng.uniform(0, 20_000, 20_000)]
    )
    full = _hic_curves(hic)
    for r in range(1, 5):
        for levels in combinations(range(1, 7), r):
            got = _hic_curves_at(hic, set(levels))
            assert sorted(got) == sorted(levels) or max(levels) > 4
            for k in levels:
                assert np.array_equal(got[k], full[k]), (levels, k)
