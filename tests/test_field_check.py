"""The occupant models' triage against NASS-CDS frontal occupants (models.field_check)."""

from __future__ import annotations

import numpy as np
import pytest

from models.field_check import BANDS, FieldCheck, field_cases, lpm_probabilities, run_field_check
from models.notification import Body, Occupant, summary_notification
from models.triage import EngineModels, load_engine_models, triage


@pytest.fixture(scope="module")
def models() -> EngineModels:
    return load_engine_models()


@pytest.fixture(scope="module")
def check(models: EngineModels) -> FieldCheck:
    return run_field_check(models)


def test_cases_are_the_frontal_occupants_with_a_known_outcome() -> None:
    cases = field_cases()
    assert 10_000 < len(cases) < 11_058  # frontal rows less the excluded outcomes/weights
    assert {c.band for c in cases} == set(BANDS)
    assert all(c.weight > 0.0 for c in cases)


def test_the_occupant_models_rank_real_outcomes_better_than_delta_v_alone(
    check: FieldCheck,
) -> None:
    """Belt, airbag, body and age through the occupant physics add to delta-V."""
    assert check.auc_lpm > check.auc_delta_v + 0.02
    assert check.auc_lpm > 0.7


def test_risk_rises_with_the_delta_v_band_like_the_outcome(check: FieldCheck) -> None:
    observed = [check.by_band[b][1] for b in BANDS]
    lpm = [check.by_band[b][2] for b in BANDS]
    assert all(b > a for a, b in zip(lpm, lpm[1:], strict=False))
    assert observed[-1] > observed[0]


def test_the_decision_figures_are_consistent(check: FieldCheck) -> None:
    flagged = check.p_lpm >= check.threshold
    pos = check.y == 1.0
    w = check.weight
    assert check.sensitivity == pytest.approx(w[pos & flagged].sum() / w[pos].sum())
    assert check.flagged_share == pytest.approx(w[flagged].sum() / w.sum())
    assert 0.0 < check.sensitivity < 1.0
    assert check.by_threshold[check.threshold] == pytest.approx(
        (check.flagged_share, check.sensitivity, check.over_triage)
    )
    rows = list(check.by_threshold.values())
    assert all(b[1] <= a[1] and b[2] <= a[2] for a, b in zip(rows, rows[1:], strict=False))


def test_the_probabilities_are_the_services_own(models: EngineModels) -> None:
    """The check's P equals what POST /v1/cases answers for the same occupant."""
    cases = field_cases()
    rng = np.random.default_rng(0)
    sample = [cases[i] for i in rng.choice(len(cases), size=4, replace=False)]
    expected = lpm_probabilities(sample, models)
    for case, p in zip(sample, expected, strict=True):
        occupant = Occupant(
            seat=case.seat,
            body=Body.MALE_50TH if case.male else Body.FEMALE_5TH,
            belted=case.belted,
            frontal_airbag=case.frontal_airbag,
            age_years=case.age_years,
        )
        notification = summary_notification((occupant,), case.delta_v_kmh, 0.0)
        occ = triage(notification, models).occupants[0]
        assert occ.method == "lpm"
        assert occ.triage.probability == p
