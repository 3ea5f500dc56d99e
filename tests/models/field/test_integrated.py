"""The shipped field risk model integrates unknown inputs and covers children."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from models.field.risk_children import ALL_COLUMNS_3, Restraint
from models.field.risk_features import AirbagCode, SeatSide
from models.field.risk_model import KNOWLEDGE, RiskModel, load_default
from tests.models.field.inputs import occupant_inputs


@pytest.fixture(scope="module")
def model() -> RiskModel:
    return load_default()


_adult = occupant_inputs


def test_the_shipped_model_is_feature_set_3_with_donors_and_thresholds_by_knowledge(
    model: RiskModel,
) -> None:
    assert model.candidate_columns == ALL_COLUMNS_3
    assert model.donors is not None
    for op in model.thresholds:
        assert set(model.knowledge_thresholds[op]) == set(KNOWLEDGE)


def test_an_unknown_age_is_integrated_not_the_median(model: RiskModel) -> None:
    unknown = _adult(age_years=None, female=None, stature_cm=None, mass_kg=None)
    p = model.predict(unknown)
    assert p.integrated == ("age_years", "female", "stature_cm", "mass_kg")
    assert "age_years" not in p.imputed
    assert p.knowledge == "age_unknown"
    median = dataclasses.replace(
        unknown,
        age_years=model.imputation.age_years,
        female=model.imputation.female >= 0.5,
        stature_cm=model.imputation.stature_cm,
        mass_kg=model.imputation.mass_kg,
    )
    at_median = model.predict(median)
    assert at_median.integrated == ()
    # risk is convex in age: the average over ages is not the risk at the median age
    assert p.probability != pytest.approx(at_median.probability, rel=0.02)
    assert p.probability > at_median.probability
    assert p.unknown_inputs_range95 is not None
    lo, hi = p.unknown_inputs_range95
    assert lo < p.probability < hi
    assert p.ci95[0] <= p.probability <= p.ci95[1]
    # the spread over the unknown inputs is wider than the confidence interval here
    assert hi - lo > p.ci95[1] - p.ci95[0]


def test_the_integrated_probability_is_the_mean_over_the_donors(model: RiskModel) -> None:
    unknown = _adult(age_years=None, female=None, stature_cm=None, mass_kg=None)
    x, owner, weight, _, _ = model.expanded_design([unknown])
    assert x.shape[0] > 1
    assert np.all(owner == 0)
    assert weight.sum() == pytest.approx(1.0)
    eta, _ = model._logits([model.decision], x)[0]
    mean = float(np.sum(weight / (1.0 + np.exp(-eta))))
    assert model.predict(unknown).probability == pytest.approx(mean, rel=1e-12)


def test_an_unknown_belt_is_integrated_between_belted_and_unbelted(model: RiskModel) -> None:
    belted = model.predict(
        _adult(seat_row=2, seat_side=SeatSide.LEFT, frontal_airbag=AirbagCode.NONE)
    )
    unbelted = model.predict(
        _adult(
            seat_row=2,
            seat_side=SeatSide.LEFT,
            frontal_airbag=AirbagCode.NONE,
            restraint=Restraint.NONE,
            belted=False,
        )
    )
    unknown = model.predict(
        _adult(seat_row=2, seat_side=SeatSide.LEFT, frontal_airbag=AirbagCode.NONE, restraint=None)
    )
    assert unknown.integrated == ("restraint",)
    assert belted.probability < unknown.probability < unbelted.probability


def test_a_child_in_a_child_seat_is_answered_by_the_childrens_terms(model: RiskModel) -> None:
    child = _adult(
        seat_row=2,
        seat_side=SeatSide.LEFT,
        frontal_airbag=AirbagCode.NONE,
        age_years=3.0,
        female=None,
        stature_cm=None,
        mass_kg=None,
        restraint=Restraint.CHILD_SEAT,
    )
    p = model.predict(child)
    assert p.knowledge == "child"
    assert set(p.integrated) == {"female", "stature_cm", "mass_kg"}
    assert model.threshold("sens85", "child") != model.threshold("sens85", "adult")
    adult = model.predict(dataclasses.replace(child, age_years=30.0, restraint=Restraint.BELTED))
    assert p.probability != adult.probability


def test_integration_is_deterministic(model: RiskModel) -> None:
    unknown = _adult(age_years=None, female=None, stature_cm=None, mass_kg=None, restraint=None)
    a, b = model.predict(unknown), model.predict(unknown)
    assert a.probability == b.probability
    assert a.ci95 == b.ci95
    assert a.unknown_inputs_range95 == b.unknown_inputs_range95


def test_a_measured_delta_v_reads_lower_and_widens_the_spread(model: RiskModel) -> None:
    """Read as the reconstruction it stands for (about 0.78 times), a measured delta-V
    answers below the same number taken as reconstructed; the measurement model's spread
    shows in `unknown_inputs_range95` (none when every input is known and the delta-V is
    reconstructed)."""
    from models.field.measurement import DeltaVSource, SourcedRiskInputs

    def sourced(source: DeltaVSource, **kw: object) -> SourcedRiskInputs:
        base = dataclasses.asdict(_adult(**kw))
        return SourcedRiskInputs(**{**base, "delta_v_source": source})

    assert model.measurement is not None
    rec = model.predict(sourced(DeltaVSource.RECONSTRUCTED))
    mea = model.predict(sourced(DeltaVSource.MEASURED))
    assert rec.unknown_inputs_range95 is None
    assert mea.integrated == ("delta_v_kmh",)
    assert mea.knowledge == "adult_measured"
    assert mea.probability < rec.probability
    assert mea.unknown_inputs_range95 is not None
    unknown = {"age_years": None, "female": None, "stature_cm": None, "mass_kg": None}
    rec_u = model.predict(sourced(DeltaVSource.RECONSTRUCTED, **unknown))
    mea_u = model.predict(sourced(DeltaVSource.MEASURED, **unknown))
    assert rec_u.unknown_inputs_range95 is not None
    assert mea_u.unknown_inputs_range95 is not None
    assert mea_u.integrated == (*rec_u.integrated, "delta_v_kmh")
    assert model.threshold("sens85", "adult_measured") == model.threshold("sens85", "adult")
