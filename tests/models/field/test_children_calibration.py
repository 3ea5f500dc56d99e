"""The children's calibration of the decision: served on child rows only, with its refits."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest

from models.constants import Z_95
from models.field.children_calibration import CHILDREN_CALIBRATION_TERMS, ChildrenCalibration
from models.field.model import canonical_content_sha256
from models.field.risk_children import ChildRiskInputs, Restraint
from models.field.risk_features import AirbagCode, SeatSide
from models.field.risk_model import RiskModel, load_default
from tests.models.field.inputs import occupant_inputs


@pytest.fixture(scope="module")
def model() -> RiskModel:
    return load_default()


def _occupant(**kw: object) -> ChildRiskInputs:
    """A rear-left passenger (no frontal airbag), `kw` overriding."""
    rear = {"seat_row": 2, "seat_side": SeatSide.LEFT, "frontal_airbag": AirbagCode.NONE}
    return occupant_inputs(**{**rear, **kw})


def _logit(p: float) -> float:
    return float(np.log(p) - np.log1p(-p))


def _expit(x: float) -> float:
    return float(0.5 * (1.0 + np.tanh(0.5 * x)))


def test_the_shipped_model_carries_the_childrens_calibration(model: RiskModel) -> None:
    assert model.children is not None
    assert model.children.bootstrap_coefficients.shape == (
        model.decision.n_bootstrap,
        2 + len(CHILDREN_CALIBRATION_TERMS),
    )


def test_an_adults_answer_is_bit_for_bit_the_shared_models(model: RiskModel) -> None:
    shared = dataclasses.replace(model, children=None)
    adult = _occupant()
    a, b = model.predict(adult), shared.predict(adult)
    assert a.probability == b.probability
    assert a.ci95 == b.ci95


@pytest.mark.parametrize(
    ("age_years", "restraint", "terms"),
    [
        (2.0, Restraint.CHILD_SEAT, (0.0, 0.0, 1.0)),
        (7.0, Restraint.BELTED, (1.0, 0.0, 0.0)),
        (12.0, Restraint.BELTED, (0.0, 1.0, 0.0)),
    ],
)
def test_a_childs_probability_is_the_calibration_of_the_shared_logit(
    model: RiskModel, age_years: float, restraint: Restraint, terms: tuple[float, ...]
) -> None:
    """logit P = a + b logit P_shared + c . z, by hand, for each age group and a child seat."""
    assert model.children is not None
    shared = dataclasses.replace(model, children=None)
    child = _occupant(age_years=age_years, restraint=restraint, stature_cm=None, mass_kg=None)
    # stature and mass unknown: the answer integrates them; compare rows that need none
    child = dataclasses.replace(child, stature_cm=130.0, mass_kg=30.0)
    got, base = model.predict(child), shared.predict(child)
    assert got.knowledge == base.knowledge == "child"
    c = model.children.coefficients
    want = _expit(c[0] + c[1] * _logit(base.probability) + float(np.dot(c[2:], terms)))
    assert got.probability == pytest.approx(want, rel=1e-9)
    # the interval is the spread of the refits, each through its own calibration
    cb = model.children.bootstrap_coefficients
    boot_shared = np.log(base.bootstrap_probability) - np.log1p(-base.bootstrap_probability)
    boot = cb[:, 0] + cb[:, 1] * boot_shared + cb[:, 2:] @ np.array(terms)
    sd = float(np.std(boot, ddof=1))
    eta = _logit(got.probability)
    assert got.ci95[0] == pytest.approx(min(_expit(eta - Z_95 * sd), got.probability), rel=1e-6)
    assert got.ci95[1] == pytest.approx(max(_expit(eta + Z_95 * sd), got.probability), rel=1e-6)


def test_child_donors_of_an_unknown_age_are_calibrated(model: RiskModel) -> None:
    """A rear passenger of unknown age integrates over the seat's donors, children among them."""
    unknown = _occupant(age_years=None, female=None, stature_cm=None, mass_kg=None)
    shared = dataclasses.replace(model, children=None)
    assert model.predict(unknown).probability != shared.predict(unknown).probability
    front = _occupant(
        seat_row=1,
        seat_side=SeatSide.LEFT,
        driver=True,
        age_years=None,
        female=None,
        stature_cm=None,
        mass_kg=None,
    )
    # the driver's donors are all adults: untouched
    assert model.predict(front).probability == shared.predict(front).probability


def _document_with(block: object) -> dict[str, object]:
    doc = copy.deepcopy(dict(load_default().document))
    doc["children_calibration"] = block
    doc.pop("content_sha256", None)
    doc["content_sha256"] = canonical_content_sha256(doc)
    return doc


def test_a_malformed_childrens_calibration_is_refused(model: RiskModel) -> None:
    assert model.children is not None
    good = model.children.to_document()
    RiskModel.from_document(_document_with(good))  # as shipped: loads
    short = {**good, "bootstrap_coefficients": good["bootstrap_coefficients"][:-1]}
    with pytest.raises(ValueError, match="children_calibration"):
        RiskModel.from_document(_document_with(short))
    with pytest.raises(ValueError, match="children_calibration: terms"):
        RiskModel.from_document(_document_with({**good, "terms": ["age_5_9"]}))
    nan = {**good, "coefficients": [float("nan")] * len(good["coefficients"])}
    with pytest.raises(ValueError, match="finite|JSON compliant"):
        RiskModel.from_document(_document_with(nan))


def test_the_calibration_apply_leaves_adult_rows_and_shifts_child_rows() -> None:
    """ChildrenCalibration.apply on a hand-made design: the terms and the refits."""
    cand = ("intercept", "age_0_4", "age_5_9", "age_10_15", "child_seat")
    cal = ChildrenCalibration.from_document(
        {
            "terms": list(CHILDREN_CALIBRATION_TERMS),
            "coefficients": [0.5, 2.0, -1.0, -2.0, 0.25],
            "bootstrap_coefficients": [[0.0, 1.0, 0.0, 0.0, 0.0], [1.0, 1.0, 1.0, 1.0, 1.0]],
        },
        cand,
        2,
    )
    x = np.array(
        [
            [1.0, 0.0, 0.0, 0.0, 0.0],  # adult
            [1.0, 1.0, 0.0, 0.0, 1.0],  # 0-4 in a child seat
            [1.0, 0.0, 1.0, 0.0, 0.0],  # 5-9
            [1.0, 0.0, 0.0, 1.0, 0.0],  # 10-15
        ]
    )
    eta = np.array([-3.0, -3.0, -3.0, -3.0])
    boot = np.full((4, 2), -3.0)
    e, b = cal.apply(eta, boot, x)
    assert e.tolist() == [-3.0, 0.5 - 6.0 + 0.25, 0.5 - 6.0 - 1.0, 0.5 - 6.0 - 2.0]
    assert b[0].tolist() == [-3.0, -3.0]
    assert b[1].tolist() == [-3.0, 1.0 - 3.0 + 0.0 + 0.0 + 1.0]
    assert b[2].tolist() == [-3.0, 1.0 - 3.0 + 1.0]
    assert eta.tolist() == [-3.0] * 4  # inputs untouched
