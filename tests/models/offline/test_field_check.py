"""The occupant models' triage against NASS-CDS frontal occupants (models.offline.field_check)."""

from __future__ import annotations

import numpy as np
import pytest

from models.notification import AirbagState, Body, Occupant, Seat, summary_notification
from models.offline.field_check import (
    BANDS,
    POPULATIONS,
    FieldCase,
    FieldCheck,
    RestraintEffect,
    _field_replicates,
    _markdown,
    _standardised,
    field_cases,
    lpm_probabilities,
    restraint_effects,
    run_field_check,
)
from models.triage import EngineModels, load_engine_models, triage
from tests.paths import ROOT
from tests.tolerance import assert_printed_numbers_close


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
        assert occ.occupant_model is not None
        assert occ.occupant_model.probability == p


def _effect(check: FieldCheck, population: str, contrast: str) -> RestraintEffect:
    (effect,) = [
        e for e in check.restraints if e.population == population and e.contrast == contrast
    ]
    return effect


@pytest.mark.parametrize("population", POPULATIONS)
def test_belts_lower_the_risk_in_the_field_and_in_the_models(
    check: FieldCheck, population: str
) -> None:
    effect = _effect(check, population, "belt")
    assert effect.field_ci95[1] < 0.0
    assert effect.field_recent_ci95[1] < 0.0
    assert effect.model < 0.0


def test_the_bag_protects_the_unbelted_and_not_the_belted_in_the_field_and_the_models(
    check: FieldCheck,
) -> None:
    """Pooled over sexes: the field's airbag benefit is for unbelted occupants; for
    belted ones it is not distinguishable from zero, and the models' is about nil
    (the open item of docs/lpm/notes.md: the bag can add load to a belted
    occupant whose head does not reach the wheel)."""
    unbelted = _effect(check, "all", "airbag_unbelted")
    belted = _effect(check, "all", "airbag_belted")
    assert unbelted.field_ci95[1] < 0.0
    assert unbelted.model < -0.05
    assert belted.field_ci95[1] >= 0.0  # no benefit distinguishable from zero
    assert abs(belted.model) < 0.01
    assert abs(belted.model) < abs(unbelted.model) / 5.0


def test_the_restraint_effects_are_seeded(check: FieldCheck) -> None:
    cases = field_cases()
    again = restraint_effects(cases, check.p_lpm)
    assert again == check.restraints
    other = restraint_effects(cases, check.p_lpm, replicates=200, seed=1)
    # the point estimates do not depend on the resamples
    assert [e.field for e in other] == [e.field for e in again]
    assert [e.model for e in other] == [e.model for e in again]
    for e in again:
        assert e.n_with > 0
        assert e.n_without > 0
        assert 0.0 <= e.dropped < 0.5


def _naive_standardised(y: np.ndarray, w: np.ndarray, band: np.ndarray, g: np.ndarray) -> float:
    """The documented estimator, written out row by row (the test's own reference)."""
    num = den = 0.0
    for k in np.unique(band):
        m = band == k
        m1, m0 = m & (g == 1), m & (g == 0)
        if w[m1].sum() == 0.0 or w[m0].sum() == 0.0:
            continue
        diff = np.average(y[m1], weights=w[m1]) - np.average(y[m0], weights=w[m0])
        num += w[m].sum() * diff
        den += w[m].sum()
    return num / den


def test_the_psu_bootstrap_equals_resampling_the_rows_of_the_drawn_psus() -> None:
    """Each replicate is the estimate on the rows of the drawn PSUs (each PSU's rows
    repeated as often as it was drawn), also when the compared rows lie in a
    subset of the survey's PSUs."""
    rng = np.random.default_rng(5)
    n = 400
    psu = rng.choice([2, 5, 7, 11], size=n)  # the survey has PSUs 1..12
    band = rng.integers(0, 3, size=n)
    g = rng.integers(0, 2, size=n)
    y = (rng.random(n) < 0.2 + 0.1 * band - 0.05 * g).astype(float)
    w = rng.uniform(1.0, 50.0, size=n)
    all_psus = np.arange(1, 13)
    draws = rng.multinomial(12, np.full(12, 1.0 / 12), size=25).astype(float)
    point, reps = _field_replicates(y, w, band, g, psu, draws, all_psus)
    assert point == pytest.approx(_naive_standardised(y, w, band, g))
    checked = 0
    for b in range(draws.shape[0]):
        rows = np.concatenate(
            [np.repeat(np.flatnonzero(psu == p), int(draws[b, p - 1])) for p in all_psus]
        )
        bands_here = {(k, gg) for k, gg in zip(band[rows].tolist(), g[rows].tolist(), strict=True)}
        if any((k, gg) not in bands_here for k in range(3) for gg in (0, 1)):
            # a band of the point estimate lacks a group: the replicate is dropped
            assert np.isnan(reps[b])
            continue
        assert reps[b] == pytest.approx(_naive_standardised(y[rows], w[rows], band[rows], g[rows]))
        checked += 1
    assert checked > 10


def test_a_band_missing_a_group_is_left_out_of_the_point_and_voids_a_replicate() -> None:
    # sums by (band, group): band 1 has no "with" rows
    swy = np.array([[1.0, 1.0], [3.0, 0.0], [2.0, 6.0]])
    sw = np.array([[10.0, 10.0], [10.0, 0.0], [10.0, 20.0]])
    # bands 0 and 2: (0.1 - 0.1) * 20 and (0.3 - 0.2) * 30, over 50
    assert _standardised(swy, sw) == pytest.approx(0.06)
    # a replicate that must use band 1 too cannot be computed
    assert np.isnan(_standardised(swy, sw, np.array([True, True, True])))
    assert _standardised(swy, sw, np.array([True, False, True])) == pytest.approx(0.06)


def test_the_restraint_differences_are_band_standardised() -> None:
    """Two bands, the restraint halving the rate in each, but worn mostly in the
    riskier band: the crude difference has the wrong sign, the standardised one not."""
    cases = []
    for band, rate in (("10-24", 0.2), ("55+", 0.6)):
        n_with, n_without = (10, 90) if band == "10-24" else (90, 10)
        for with_, n, r in ((True, n_with, rate / 2.0), (False, n_without, rate)):
            for i in range(n):
                cases.append(
                    FieldCase(
                        band=band,
                        delta_v_kmh=0.0,
                        seat=Seat.DRIVER,
                        belted=with_,
                        frontal_airbag=AirbagState.ABSENT,
                        male=True,
                        age_years=35.0,
                        serious=i < round(n * r),
                        weight=1.0,
                        psu=1 + i % 3,
                        vehicle_year=2000,
                    )
                )
    p = np.zeros(len(cases))
    (effect,) = [
        e
        for e in restraint_effects(cases, p, replicates=50)
        if e.population == "all" and e.contrast == "belt"
    ]
    y = np.array([c.serious for c in cases], dtype=float)
    belted = np.array([c.belted for c in cases])
    assert y[belted].mean() - y[~belted].mean() > 0.0  # crude: the wrong sign
    # standardised: bands of 100 occupants each, differences -0.1 and -0.3
    assert effect.field == pytest.approx(-0.2, abs=1e-12)
    assert effect.model == 0.0


def test_the_shipped_field_check_is_current(check: FieldCheck) -> None:
    """docs/field_check/field_check.md is what `python -m models.offline.field_check` writes now, to
    its printed precision: the words and counts equal, each printed figure within
    one unit of its last digit (``tests.tolerance.assert_printed_numbers_close``).

    Not byte for byte: the figures come from LPM runs and numpy on this machine,
    and other code paths (CPU, numpy's SIMD kernels, glibc, numba's target) move
    the occupants' P in the last bits (measured with ``.ci/run``'s second
    environment: at most 5e-15 relative). The figures follow by at most 3e-14
    relative, except the weighted AUCs: a last-bit change makes or breaks exact
    ties between occupants' P, and the occupant models' AUC moved from 0.75847 to
    0.75815, a third of its printed unit. A figure can so round the other way at a
    boundary, by one unit and no more; a change of the check beyond that fails."""
    shipped = (ROOT / "docs" / "field_check" / "field_check.md").read_text()
    assert_printed_numbers_close(_markdown(check), shipped, what="field_check.md")


def test_the_group_rates_partition_the_bands(check: FieldCheck) -> None:
    cases = field_cases()
    for band in BANDS:
        rows = [r for r in check.rates if r.band == band]
        assert sum(r.n for r in rows) == check.by_band[band][0]
    (one,) = [r for r in check.rates if r.group == "belt only" and r.band == "25-39"]
    sel = [
        i
        for i, c in enumerate(cases)
        if c.belted and c.frontal_airbag is AirbagState.ABSENT and c.band == "25-39"
    ]
    w = np.array([cases[i].weight for i in sel])
    assert one.field == pytest.approx(np.average([cases[i].serious for i in sel], weights=w))
    assert one.model == pytest.approx(np.average(check.p_lpm[sel], weights=w))


@pytest.mark.parametrize("group", ["belt + airbag", "belt only"])
def test_the_models_are_not_harsher_than_the_field_for_belted_occupants(
    check: FieldCheck, group: str
) -> None:
    """ISS >= 15 is narrower than the police outcome: for belted occupants the models'
    P stays below the field rate in every band (README: the frontal models are milder
    than the field). The unrestrained at 40 km/h and more are the exception, reported
    in field_check.md."""
    for r in check.rates:
        if r.group == group:
            assert r.model < r.field, r.band
