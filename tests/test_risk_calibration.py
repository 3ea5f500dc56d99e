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
def test_the_service_decides_on_the_corrected_probability(
    models: EngineModels, delta_v: float, pdof: float
) -> None:
    occ = triage(_notification(delta_v, pdof), models).occupants[0]
    assert occ.method == "lpm"
    assert occ.probability_uncorrected is not None
    assert occ.probability_zero_load is not None
    assert occ.measures is not None
    measures = InjuryMeasures(**occ.measures)
    assert occ.probability_zero_load == zero_load_probability(
        measures, occ.body, 40.0, occ.impact.mode
    )
    assert occ.triage.probability == corrected_probability(
        occ.probability_uncorrected, occ.probability_zero_load
    )
    assert occ.triage.probability < occ.probability_uncorrected
    assert occ.triage.iss15_plus == (occ.triage.probability >= occ.triage.threshold)
    lo, hi = occ.triage.probability_ci95
    assert 0.0 <= lo <= hi <= 1.0


def test_the_baseline_is_not_corrected(models: EngineModels) -> None:
    """Out of coverage (PDOF 45 deg) the field-fitted baseline answers as it is."""
    occ = triage(_notification(40.0, 45.0), models).occupants[0]
    assert occ.method == "baseline"
    assert occ.probability_uncorrected is None
    assert occ.triage == occ.baseline


def test_the_correction_is_recorded_with_every_lpm_case(models: EngineModels) -> None:
    result = triage(_notification(56.0, 0.0), models)
    info = result.models["risk_calibration"]
    assert info.version == CALIBRATION_VERSION
    assert info.sha256 == calibration_sha256()
    assert len(info.sha256) == 64
