"""The zero-load correction of the occupant models' P(ISS >= 15) (models.risk_calibration)."""

from __future__ import annotations

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.injury.assessment import InjuryMeasures, assess
from models.notification import (
    AirbagState,
    Body,
    CrashNotification,
    Occupant,
    Seat,
    summary_notification,
)
from models.risk_calibration import (
    CALIBRATION_VERSION,
    calibration_sha256,
    corrected_probability,
    zero_load_probability,
)
from models.triage import EngineModels, load_engine_models, triage

FRONTAL_SET = InjuryMeasures(
    hic15=300.0, nij=0.4, chest_deflection_mm=30.0, chest_vc_m_s=0.2, chest_a3ms_g=40.0
)
REAR_SET = InjuryMeasures(hic15=100.0, nij=0.3)
SIDE_SET = InjuryMeasures(
    hic15=300.0,
    nij=0.4,
    chest_deflection_mm=30.0,
    chest_vc_m_s=0.2,
    chest_cti=0.5,
    abdomen_vc_m_s=0.3,
)


@pytest.fixture(scope="module")
def models() -> EngineModels:
    return load_engine_models()


def test_the_published_curves_have_a_floor_that_the_correction_removes() -> None:
    """The fact the correction exists for: ~5.4 % at zero load, above the side threshold."""
    p0 = zero_load_probability(SIDE_SET, Body.MALE_50TH, None, ImpactMode.NEAR_SIDE)
    assert 0.05 < p0 < 0.06, "above the side threshold 0.05"
    zero = InjuryMeasures(
        hic15=0.0,
        nij=0.0,
        chest_deflection_mm=0.0,
        chest_vc_m_s=0.0,
        chest_cti=0.0,
        abdomen_vc_m_s=0.0,
    )
    raw = assess(zero, Body.MALE_50TH, impact_mode="near_side").p_iss15
    assert raw > 0.05
    assert corrected_probability(raw, p0) == 0.0


def test_the_floor_depends_on_the_measures_present() -> None:
    """Rear reports HIC and Nij only: its floor is the head/neck region's alone."""
    p_rear = zero_load_probability(REAR_SET, Body.MALE_50TH, None, ImpactMode.REAR)
    p_frontal = zero_load_probability(FRONTAL_SET, Body.MALE_50TH, None, ImpactMode.FRONTAL)
    assert 0.0 < p_rear < p_frontal
    assert p_rear == assess(InjuryMeasures(hic15=0.0, nij=0.0), Body.MALE_50TH).p_iss15


def test_abbott_correction_properties() -> None:
    p0 = 0.0544
    grid = np.linspace(0.0, 1.0, 201)
    out = np.array([corrected_probability(p, p0) for p in grid])
    assert np.all((out >= 0.0) & (out <= 1.0))
    assert np.all(np.diff(out) >= 0.0), "order of cases is kept"
    assert corrected_probability(1.0, p0) == 1.0
    assert corrected_probability(p0, p0) == 0.0
    assert corrected_probability(0.02, p0) == 0.0, "below the floor: clipped"
    # affine above the floor: P = P0 + (1 - P0) P_load inverted
    assert corrected_probability(p0 + (1 - p0) * 0.3, p0) == pytest.approx(0.3)
    assert corrected_probability(0.3, 0.0) == 0.3, "no floor, no change"
    with pytest.raises(ValueError, match="p0"):
        corrected_probability(0.5, 1.0)


def _notification(delta_v: float, pdof: float, age: float | None = 40.0) -> CrashNotification:
    occupant = Occupant(
        seat=Seat.DRIVER,
        body=Body.MALE_50TH,
        belted=True,
        frontal_airbag=AirbagState.DEPLOYED,
        age_years=age,
    )
    return summary_notification((occupant,), delta_v, pdof, event_id="cal")


@pytest.mark.parametrize(("delta_v", "pdof"), [(56.0, 0.0), (30.0, 270.0), (45.0, 180.0)])
def test_the_occupant_models_decide_on_the_corrected_probability(
    models: EngineModels, delta_v: float, pdof: float
) -> None:
    """The occupant models' own decision (the second opinion beside the field model's)."""
    occ = triage(_notification(delta_v, pdof), models).occupants[0]
    assert occ.method == "lpm"
    model = occ.occupant_model
    assert model is not None
    assert occ.probability_uncorrected is not None
    assert occ.probability_zero_load is not None
    assert occ.measures is not None
    measures = InjuryMeasures(**occ.measures)
    assert occ.probability_zero_load == zero_load_probability(
        measures, occ.body, 40.0, occ.impact.mode
    )
    assert model.probability == corrected_probability(
        occ.probability_uncorrected, occ.probability_zero_load
    )
    assert model.probability < occ.probability_uncorrected
    assert model.iss15_plus == (model.probability >= model.threshold)
    lo, hi = model.probability_ci95
    assert 0.0 <= lo <= hi <= 1.0


def test_the_interval_is_corrected_at_the_occupants_age(models: EngineModels) -> None:
    """The surrogate runs at the occupant's age, so its interval loses that age's floor.

    Issue 21 (a): the interval's zero-load correction used the default age. At a
    high age the chest curve's floor differs from the default's; the corrected
    interval must be the surrogate's interval corrected with the occupant's own P0.
    """
    for age in (25.0, 85.0):
        occ = triage(_notification(35.0, 0.0, age=age), models).occupants[0]
        assert occ.occupant_model is not None
        assert occ.probability_zero_load is not None
        p0 = occ.probability_zero_load
        assert occ.measures is not None
        assert p0 == zero_load_probability(
            InjuryMeasures(**occ.measures), occ.body, age, occ.impact.mode
        )
        lo, hi = occ.occupant_model.probability_ci95
        # undo the correction: the uncorrected bounds are the surrogate's, which hold
        # the uncorrected point (an unflagged answer)
        raw_lo, raw_hi = lo * (1 - p0) + p0, hi * (1 - p0) + p0
        assert occ.point_outside_interval or (
            raw_lo - 1e-12 <= occ.probability_uncorrected <= raw_hi + 1e-12
        )
        assert lo <= occ.occupant_model.probability <= hi or occ.point_outside_interval


def test_the_baseline_is_not_corrected(models: EngineModels) -> None:
    """Out of coverage (PDOF 45 deg) the baseline's second opinion is its own as it is."""
    occ = triage(_notification(40.0, 45.0), models).occupants[0]
    assert occ.method == "field"
    assert occ.probability_uncorrected is None
    assert occ.occupant_model is None
    assert occ.baseline.outcome == "police_A+K"


def test_the_correction_is_recorded_with_every_lpm_case(models: EngineModels) -> None:
    result = triage(_notification(56.0, 0.0), models)
    info = result.models["risk_calibration"]
    assert info.version == CALIBRATION_VERSION
    assert info.sha256 == calibration_sha256()
    assert len(info.sha256) == 64
