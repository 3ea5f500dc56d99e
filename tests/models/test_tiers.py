"""Risk tiers of the field decision: boundaries, words, second opinions, the vehicle, and
the refusal of a high-risk threshold below an operating threshold."""

from __future__ import annotations

import dataclasses

import pytest

from models.field.versions import artifact_for_version
from models.notification import (
    AirbagState,
    Body,
    CrashNotification,
    DriveSide,
    Occupant,
    Seat,
    SummaryPulse,
)
from models.triage import (
    HIGH_RISK_THRESHOLD,
    RECOMMENDATIONS,
    EngineModels,
    ThresholdOrderError,
    Tier,
    decide,
    load_engine_models,
    recommendation,
    tier_of,
    triage,
)

#: The issue's words, exactly (the recommendation starts them with a capital and ends
#: them with a full stop).
HIGH_WORDS = "transport to the highest-level trauma center in reach"
MODERATE_WORDS = (
    "vehicle telemetry consistent with severe injury (2021 guideline, moderate risk): "
    "consider a trauma center, which need not be the highest level; EMS judgment and "
    "local protocol decide"
)
NONE_WORDS = (
    "No telemetry indication of ISS 15 or more: destination by EMS field assessment under "
    "local protocol."
)


@pytest.fixture(scope="module")
def models() -> EngineModels:
    return load_engine_models()


def _crash(
    delta_v_kmh: float, *, belted: bool = True, airbag: AirbagState = AirbagState.DEPLOYED
) -> CrashNotification:
    occupant = Occupant(
        seat=Seat.DRIVER, body=Body.MALE_50TH, belted=belted, frontal_airbag=airbag, age_years=42
    )
    return CrashNotification(
        event_id="tiers",
        vehicle_model="compact_sedan",
        drive_side=DriveSide.LEFT,
        pulse=SummaryPulse(delta_v_kmh=delta_v_kmh, pdof_deg=0.0),
        multiple_impacts=False,
        rollover=False,
        occupants=(occupant,),
    )


def _sentence(words: str) -> str:
    return words[0].upper() + words[1:] + "."


# ------------------------------------------------------------------ boundaries


@pytest.mark.parametrize(
    ("probability", "expected"),
    [
        (0.0, Tier.NONE),
        (0.0177 - 1e-12, Tier.NONE),
        (0.0177, Tier.MODERATE),  # at the operating threshold: flagged
        (0.10, Tier.MODERATE),
        (0.20 - 1e-12, Tier.MODERATE),
        (0.20, Tier.HIGH),  # at the high-risk threshold: high
        (1.0, Tier.HIGH),
    ],
)
def test_tier_boundaries_are_at_or_above(probability: float, expected: Tier) -> None:
    assert tier_of(probability, 0.0177, 0.20) is expected


def test_high_needs_the_operating_threshold_too() -> None:
    """A high tier is always flagged: above the high-risk threshold but below an operating
    threshold above it (a setting the service refuses; a stored case may carry it) is none."""
    assert tier_of(0.25, 0.30, 0.20) is Tier.NONE
    assert tier_of(0.30, 0.30, 0.20) is Tier.HIGH


def test_the_default_high_threshold_is_the_cdc_panels_20_percent() -> None:
    assert HIGH_RISK_THRESHOLD == 0.20


# ------------------------------------------------------------------ words


def test_every_tier_has_the_issues_words() -> None:
    assert recommendation(Tier.HIGH) == _sentence(HIGH_WORDS)
    assert recommendation(Tier.MODERATE) == _sentence(MODERATE_WORDS)
    assert recommendation(Tier.NONE) == NONE_WORDS
    assert set(RECOMMENDATIONS) == set(Tier)
    for words in RECOMMENDATIONS.values():
        assert "Level I" not in words


def test_second_opinions_have_no_tier_and_the_same_words(models: EngineModels) -> None:
    """The occupant models' and the baseline's decisions speak as a telemetry indication
    (the moderate tier's words) or none, and never of a Level I center."""
    flagged = decide(0.5, (0.4, 0.6), 0.1)
    clear = decide(0.05, (0.04, 0.06), 0.1)
    assert (flagged.tier, flagged.high_threshold) == (None, None)
    assert flagged.recommendation == recommendation(Tier.MODERATE)
    assert clear.recommendation == recommendation(Tier.NONE)
    answer = triage(_crash(56.0), models).occupants[0]
    for opinion in (answer.occupant_model, answer.baseline):
        assert opinion is not None
        assert opinion.tier is None
        assert opinion.recommendation == recommendation(
            Tier.MODERATE if opinion.iss15_plus else Tier.NONE
        )


# ------------------------------------------------------------------ the engine


@pytest.mark.parametrize(
    ("crash", "expected"),
    [
        (_crash(80.0, belted=False, airbag=AirbagState.ABSENT), Tier.HIGH),
        (_crash(60.0), Tier.MODERATE),  # the README's driver at 60 km/h (measured): about 4 %
        (_crash(10.0), Tier.NONE),
    ],
    ids=["high", "moderate", "none"],
)
def test_the_field_decision_has_its_tier_and_words(
    models: EngineModels, crash: CrashNotification, expected: Tier
) -> None:
    result = triage(crash, models)
    d = result.triage
    assert d.tier is expected
    assert d.high_threshold == HIGH_RISK_THRESHOLD
    assert d.iss15_plus == (expected is not Tier.NONE)
    assert d.recommendation == recommendation(expected)
    assert result.occupants[0].triage == d, "the case's decision is its worst occupant's"
    v = result.vehicle
    assert v is not None
    assert v.tier is tier_of(v.probability, d.threshold, HIGH_RISK_THRESHOLD)
    assert (v.threshold, v.high_threshold) == (d.threshold, HIGH_RISK_THRESHOLD)


def test_the_boundaries_hold_in_the_engine(models: EngineModels) -> None:
    """A probability exactly at the high-risk threshold is high, exactly at the operating
    threshold moderate (the configured thresholds moved onto one answer's probability)."""
    crash = _crash(56.0)
    p = triage(crash, models).triage.probability
    at_high = dataclasses.replace(models, high_threshold=p)
    assert triage(crash, at_high).triage.tier is Tier.HIGH
    above_high = dataclasses.replace(models, high_threshold=min(1.0, p * (1 + 1e-9)))
    assert triage(crash, above_high).triage.tier is Tier.MODERATE
    at_threshold = dataclasses.replace(models, threshold_override=p)
    decided = triage(crash, at_threshold).triage
    assert (decided.tier, decided.iss15_plus) == (Tier.MODERATE, True)
    above = dataclasses.replace(models, threshold_override=p * (1 + 1e-9))
    decided = triage(crash, above).triage
    assert (decided.tier, decided.iss15_plus) == (Tier.NONE, False)


def test_the_case_takes_the_worst_occupants_tier_and_the_vehicle_its_own(
    models: EngineModels,
) -> None:
    low = Occupant(
        seat=Seat.DRIVER,
        body=Body.MALE_50TH,
        belted=True,
        frontal_airbag=AirbagState.DEPLOYED,
        age_years=30,
    )
    high = Occupant(
        seat=Seat.FRONT_PASSENGER,
        body=Body.MALE_50TH,
        belted=False,
        frontal_airbag=AirbagState.ABSENT,
        age_years=80,
    )
    crash = dataclasses.replace(_crash(60.0), occupants=(low, high))
    result = triage(crash, models)
    tiers = [o.triage.tier for o in result.occupants]
    assert tiers[1] is Tier.HIGH, tiers
    assert tiers[0] is not Tier.HIGH, tiers
    assert result.triage == result.occupants[1].triage
    v = result.vehicle
    assert v is not None
    assert v.probability >= result.triage.probability
    assert v.tier is Tier.HIGH


# ------------------------------------------------------------------ refusal


def test_a_high_threshold_below_the_operating_point_is_refused() -> None:
    with pytest.raises(ThresholdOrderError, match="sens85"):
        load_engine_models(high_threshold=0.01, use_surrogates=False, warm=False)
    # acs_cot's threshold (about 0.005) lies below 0.01: accepted
    accepted = load_engine_models(
        high_threshold=0.01, operating_point="acs_cot", use_surrogates=False, warm=False
    )
    assert accepted.high_threshold == 0.01
    with pytest.raises(ThresholdOrderError, match="AACN_TRIAGE_THRESHOLD"):
        load_engine_models(threshold_override=0.3, use_surrogates=False, warm=False)


def test_a_per_mode_field_model_is_checked_in_every_mode() -> None:
    """Field model 2.0.0 (recalls) has thresholds per crash mode: `bahouth` has 0.10 for
    frontal and rear, 0.05 for the sides; a high-risk threshold of 0.08 lies below two."""
    with pytest.raises(ThresholdOrderError, match=r"bahouth \(frontal\)"):
        load_engine_models(
            operating_point="bahouth",
            high_threshold=0.08,
            field_artifact=artifact_for_version("2.0.0"),
            use_surrogates=False,
            warm=False,
        )
