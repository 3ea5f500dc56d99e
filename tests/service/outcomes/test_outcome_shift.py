"""Issue 50, item 5: real crashes as local outcomes, with and without a known shift.

The NASS-CDS 2011-2014 occupants of the fitted population (5,519 occupants of 3,111
crashes, 265 ISS 15+; ``models/offline/data``, in the repository) stand for a site's
linked outcomes, the served model's decided probabilities against their ISS 15+
(``models.offline.field.local_shift``). Figures are the service's own: the quality
figures (``service.outcomes.quality.figures_of``), the drift alarm
(``service.outcomes.drift``) over a window holding them all, the recalibration
(``models.field.recalibration``).

With the survey weights (as the issue asks) the data hold little information: the
weights' effective number of ISS 15+ is about 19 (the drift test's effective expected
events about 8). So, as they are, the alarm is silent; with the odds halved the quality
figures show the drop but the alarm has no power to fire (its expected z is about -1.4)
and recalibration on half the crashes is refused (about 9 effective ISS 15+ against the
78 the stated precision needs): the tests pin these facts. With unit weights, as a
registry's outcomes come, the same crashes are a population the model was not
calibrated for (NASS oversamples severe crashes: the known shift of its design): the
alarm fires, and recalibration on half the crashes brings the other half within
0.8-1.25 (checked over 20 seeded splits); once recalibrated on one half, the other half
leaves the alarm mostly silent as it is and fires it with the odds halved. Loading and
scoring the crashes: a few seconds, once per module.
"""

from __future__ import annotations

from datetime import UTC, datetime

import numpy as np
import pytest

from models.field.recalibration import (
    MIN_EFFECTIVE_EVENTS,
    apply_recalibration,
    fit_recalibration,
    precision_plan,
    weighted_ratio,
)
from models.field.risk_model import load_default
from models.offline.field.local_shift import (
    LocalOutcomes,
    crash_halves,
    decisions,
    halve_odds,
    nass_local_outcomes,
)
from models.tiers import Tier
from service.outcomes.drift import DriftSettings, drift_status
from service.outcomes.quality import LinkedOccupant, QualityGroup, figures_of

#: The drift alarm as configured by default (1 % false alarms per window), its window
#: holding every local occupant.
ALARM = DriftSettings(window=100_000, false_alarm_rate=0.01)
#: Seeded splits of the crashes for the recalibration on half.
SPLITS = range(20)


@pytest.fixture(scope="module")
def local() -> LocalOutcomes:
    return nass_local_outcomes()


def _figures(data: LocalOutcomes) -> QualityGroup:
    flagged, high = decisions(data, load_default())
    at = datetime(2026, 11, 1, tzinfo=UTC)
    occupants = [
        LinkedOccupant(
            case_id=str(c),
            received_at=at,
            month="2026-11",
            operating_point="sens85",
            tier=Tier.HIGH if h else Tier.MODERATE if f else Tier.NONE,
            flagged=bool(f),
            probability=float(p),
            crash_mode="frontal",
            age_group="adult_16_64",
            seat_row=1,
            serious=bool(y),
            weight=float(w),
        )
        for c, p, y, w, f, h in zip(
            data.crash, data.probability, data.serious, data.weight, flagged, high, strict=True
        )
    ]
    return figures_of(occupants)


def _alarm(data: LocalOutcomes) -> tuple[str, float]:
    s = drift_status(
        [bool(y) for y in data.serious], list(data.probability), list(data.weight), ALARM
    )
    assert s.z is not None
    return s.state, s.z


def test_the_data(local: LocalOutcomes) -> None:
    assert len(local) == 5519
    assert int(local.serious.sum()) == 265
    assert np.unique(local.crash).size == 3111


def test_as_they_are_the_alarm_is_silent_and_calibration_holds(local: LocalOutcomes) -> None:
    state, z = _alarm(local)
    assert state == "ok"
    assert abs(z) < 1.0
    cal = _figures(local).calibration
    assert cal.observed_over_predicted_ci95 is not None
    low, high = cal.observed_over_predicted_ci95
    assert low < 1.0 < high
    # the served model's (3.4.0) weighted predicted/observed on these crashes: docs/outcomes.md
    # gives its inverse, observed/predicted 1.05
    assert weighted_ratio(local.probability, local.serious, local.weight) == pytest.approx(
        0.952, abs=0.01
    )


def test_halved_odds_show_in_the_quality_figures(local: LocalOutcomes) -> None:
    before = _figures(local).calibration.observed_over_predicted
    assert before is not None
    for seed in range(5):
        shifted = halve_odds(local, seed)
        kept = int(shifted.serious.sum())
        assert 0.4 * 265 < kept < 0.6 * 265
        after = _figures(shifted).calibration.observed_over_predicted
        assert after is not None
        assert after < 0.8 * before  # halved odds: about half the ISS 15+ observed
        state, z = _alarm(shifted)
        assert z < 0  # the direction: predicted too high


def test_with_survey_weights_the_data_cannot_carry_the_alarm_or_a_recalibration(
    local: LocalOutcomes,
) -> None:
    """The facts behind the silence (module docstring): the weights leave few events."""
    w, p = local.weight, local.probability
    effective_expected = np.sum(w * p) ** 2 / np.sum(w * w * p * (1 - p))
    assert effective_expected < 10  # halved odds: expected z = -0.5 sqrt(this) > -1.6
    plan = precision_plan(p, local.serious, w)
    assert plan.method == "refused"
    assert plan.effective_events < MIN_EFFECTIVE_EVENTS / 3
    shifted = halve_odds(local, 0)
    a, _ = crash_halves(shifted, 0)
    half = shifted.subset(a)
    assert precision_plan(half.probability, half.serious, half.weight).method == "refused"


def test_unit_weights_the_alarm_fires_and_recalibration_on_half_fixes_the_other(
    local: LocalOutcomes,
) -> None:
    data = local.unweighted()
    state, z = _alarm(data)
    assert state == "alarm"  # NASS's sample is not the population the model speaks for
    assert z > 5
    assert weighted_ratio(data.probability, data.serious, data.weight) < 0.7
    inside = []
    for seed in SPLITS:
        a, b = crash_halves(data, seed)
        train, test = data.subset(a), data.subset(b)
        plan = precision_plan(train.probability, train.serious, train.weight)
        assert plan.method == "intercept_and_slope"
        fit = fit_recalibration(
            train.probability, train.serious, train.weight, list(train.crash), plan.method
        )
        before = weighted_ratio(test.probability, test.serious, test.weight)
        after = weighted_ratio(
            apply_recalibration(test.probability, fit.intercept, fit.slope),
            test.serious,
            test.weight,
        )
        assert before < 0.75
        inside.append(0.8 <= after <= 1.25)
    assert np.mean(inside) >= 0.8


def test_unit_weights_after_recalibration_silent_as_they_are_and_fires_on_halved_odds(
    local: LocalOutcomes,
) -> None:
    """A site that recalibrated on one half of its outcomes (unit weights) receives the
    other half: as they are the alarm is mostly silent, with the odds halved it fires.
    Observed over the 20 splits: silent in 18, fires in 19 (the 2 false alarms are above
    the nominal 1 %: the recalibration's own error and the crashes' clustering, which the
    test's variance does not hold)."""
    data = local.unweighted()
    silent = fired = 0
    for seed in SPLITS:
        a, b = crash_halves(data, seed)
        train, test = data.subset(a), data.subset(b)
        plan = precision_plan(train.probability, train.serious, train.weight)
        fit = fit_recalibration(
            train.probability, train.serious, train.weight, list(train.crash), plan.method
        )
        served = LocalOutcomes(
            apply_recalibration(test.probability, fit.intercept, fit.slope),
            test.serious,
            test.weight,
            test.crash,
            test.age_years,
        )
        silent += _alarm(served)[0] == "ok"
        state, z = _alarm(halve_odds(served, seed))
        fired += state == "alarm" and z < 0
    assert silent >= 16
    assert fired >= 17
