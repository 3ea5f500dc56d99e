"""Tests of the shipped baseline artifact and `models.baseline.logistic`."""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from models.baseline import (
    BaselineFeatures,
    BaselineModel,
    BaselinePrediction,
    default_artifact_path,
    load_default,
)
from models.baseline.logistic import FEATURE_NAMES, MODEL_NAME, MODEL_VERSION, Z_95
from models.notification import Sex
from tests.paths import ROOT

MODEL_CARD = ROOT / "docs" / "baseline" / "MODEL_CARD.md"


@pytest.fixture(scope="module")
def model() -> BaselineModel:
    return load_default()


@pytest.fixture(scope="module")
def artifact() -> dict[str, Any]:
    doc: dict[str, Any] = json.loads(default_artifact_path().read_text(encoding="utf-8"))
    return doc


def _features(**kw: Any) -> BaselineFeatures:
    base: dict[str, Any] = {
        "delta_v_kmh": 40.0,
        "belted": True,
        "airbag_deployed": False,
        "frontal": True,
        "age_years": 40.0,
        "sex": Sex.MALE,
    }
    base.update(kw)
    return BaselineFeatures(**base)


# --------------------------------------------------------------------------- loading


def test_shipped_artifact_loads(model: BaselineModel, artifact: dict[str, Any]) -> None:
    assert model.name == MODEL_NAME == artifact["model"]["name"]
    assert model.version == MODEL_VERSION == artifact["model"]["version"]
    assert model.sha256 == hashlib.sha256(default_artifact_path().read_bytes()).hexdigest()
    assert model.feature_names == FEATURE_NAMES
    assert model.threshold == artifact["threshold"]["value"]
    assert 0.0 < model.threshold < 1.0
    assert model.coefficients.shape == (len(FEATURE_NAMES),)
    assert model.covariance.shape == (len(FEATURE_NAMES),) * 2
    assert np.array_equal(model.coefficients, artifact["coefficients"])
    assert model.data_sha256 == artifact["data"]["sha256"]
    # The shipped data file is the one the artifact was fitted on.
    from models.offline.paths import DATA_DIR

    data = DATA_DIR / artifact["data"]["file"]
    assert hashlib.sha256(data.read_bytes()).hexdigest() == model.data_sha256


def test_artifact_is_plain_sorted_json(artifact: dict[str, Any]) -> None:
    text = default_artifact_path().read_text(encoding="utf-8")
    assert text == json.dumps(artifact, sort_keys=True, indent=2, allow_nan=False) + "\n"
    for key in ("fit_date", "covariance", "standard_errors", "metrics", "features", "data"):
        assert key in artifact


def test_model_is_immutable(model: BaselineModel) -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        model.threshold = 0.5  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        model.coefficients[0] = 0.0
    with pytest.raises(ValueError, match="read-only"):
        model.covariance[0, 0] = 0.0


# --------------------------------------------------------------------------- metrics recorded


def test_recorded_metrics_are_sane(artifact: dict[str, Any]) -> None:
    m = artifact["metrics"]
    assert m["holdout_2000"]["auc"] > 0.6
    assert m["cv5"]["auc_mean"] > 0.6
    assert len(m["cv5"]["auc_folds"]) == 5
    # The threshold rule: out-of-fold under-triage within the 5 % target.
    assert m["cv5"]["under_triage"] <= 0.05
    for block in (m["holdout_2000"], m["cv5"], m["in_sample"]):
        assert 0.0 <= block["under_triage"] <= 1.0
        assert 0.0 <= block["over_triage"] <= 1.0
    counts = artifact["data"]["counts"]
    assert counts["rows_in_file"] == 17_338
    assert counts["rows_used"] == counts["rows_serious"] + counts["rows_not_serious"]


def test_model_card_quotes_the_artifact(artifact: dict[str, Any]) -> None:
    card = MODEL_CARD.read_text(encoding="utf-8")
    m = artifact["metrics"]
    assert f"{artifact['threshold']['value']:.3f}" in card
    assert f"{m['holdout_2000']['auc']:.3f}" in card
    assert f"{m['cv5']['auc_mean']:.3f}" in card
    assert f"{100 * m['cv5']['under_triage']:.1f} %" in card
    assert f"{100 * m['cv5']['over_triage']:.1f} %" in card
    assert "ISS15+" in card
    assert artifact["data"]["sha256"] in card


# --------------------------------------------------------------------------- predictions


def test_prediction_fields(model: BaselineModel) -> None:
    r = model.predict(_features())
    assert isinstance(r, BaselinePrediction)
    assert 0.0 < r.probability < 1.0
    lo, hi = r.ci95
    assert lo < r.probability < hi
    assert r.standard_error > 0.0
    assert r.linear_predictor == pytest.approx(math.log(r.probability / (1 - r.probability)))
    # Delta method on the logit.
    assert lo == pytest.approx(1 / (1 + math.exp(-(r.linear_predictor - Z_95 * r.standard_error))))
    assert hi == pytest.approx(1 / (1 + math.exp(-(r.linear_predictor + Z_95 * r.standard_error))))


def test_risk_rises_with_delta_v(model: BaselineModel) -> None:
    probs = [model.predict(_features(delta_v_kmh=dv)).probability for dv in range(0, 121, 5)]
    assert all(b > a for a, b in zip(probs, probs[1:], strict=False))
    assert probs[0] < 0.05 < 0.5 < probs[-1]


@pytest.mark.parametrize("dv", [10.0, 30.0, 60.0])
@pytest.mark.parametrize("frontal", [True, False])
def test_belt_lowers_risk(model: BaselineModel, dv: float, frontal: bool) -> None:
    belted = model.predict(_features(delta_v_kmh=dv, belted=True, frontal=frontal))
    unbelted = model.predict(_features(delta_v_kmh=dv, belted=False, frontal=frontal))
    assert belted.probability < unbelted.probability


def test_ci_is_not_a_constant(model: BaselineModel) -> None:
    widths = {
        round(r.ci95[1] - r.ci95[0], 12)
        for r in (model.predict(_features(delta_v_kmh=dv)) for dv in (5.0, 20.0, 40.0, 60.0))
    }
    assert len(widths) == 4
    assert all(w > 0.0 for w in widths)


def test_uncertainty_grows_far_outside_the_data(model: BaselineModel) -> None:
    inside = model.predict(_features(delta_v_kmh=30.0))
    far = model.predict(_features(delta_v_kmh=150.0))
    assert far.standard_error > inside.standard_error
    # Beyond the largest band (55+, 62 km/h) the logit error keeps growing.
    se = [model.predict(_features(delta_v_kmh=dv)).standard_error for dv in (80, 120, 160, 200)]
    assert all(b > a for a, b in zip(se, se[1:], strict=False))
    # Even where the interval narrows (see MODEL_CARD.md, limitations), it never collapses.
    for age in (16.0, 36.0, 80.0, 110.0):
        r = model.predict(_features(age_years=age))
        assert r.standard_error > 0.1
        assert r.ci95[1] - r.ci95[0] > 0.01


def test_unknown_age_and_sex_are_imputed(model: BaselineModel) -> None:
    unknown = model.predict(_features(age_years=None, sex=None))
    x = model.encode(_features(age_years=None, sex=None))
    assert x[FEATURE_NAMES.index("age_years")] == model.impute_age_years
    assert x[FEATURE_NAMES.index("male")] == model.impute_male
    assert 0.0 < model.impute_male < 1.0
    male = model.predict(_features(age_years=None, sex=Sex.MALE)).probability
    female = model.predict(_features(age_years=None, sex=Sex.FEMALE)).probability
    assert min(male, female) < unknown.probability < max(male, female)


def test_predict_many_matches_predict(model: BaselineModel) -> None:
    rows = [
        (12.0, 1, 0, 1, 25.0, 1),
        (35.0, 0, 1, 0, 70.0, 0),
        (55.0, 1, 1, 1, float("nan"), float("nan")),
        (0.0, 0, 0, 0, 16.0, 1),
    ]
    many = model.predict_many(np.array(rows))
    for i, (dv, belt, bag, fr, age, male) in enumerate(rows):
        one = model.predict(
            BaselineFeatures(
                delta_v_kmh=dv,
                belted=bool(belt),
                airbag_deployed=bool(bag),
                frontal=bool(fr),
                age_years=None if math.isnan(age) else age,
                sex=None if math.isnan(male) else (Sex.MALE if male else Sex.FEMALE),
            )
        )
        assert many.probability[i] == pytest.approx(one.probability, rel=1e-12)
        assert many.ci95_low[i] == pytest.approx(one.ci95[0], rel=1e-12)
        assert many.ci95_high[i] == pytest.approx(one.ci95[1], rel=1e-12)
        assert many.standard_error[i] == pytest.approx(one.standard_error, rel=1e-12)


def test_predict_is_deterministic(model: BaselineModel) -> None:
    assert model.predict(_features()) == model.predict(_features())


@pytest.mark.parametrize(
    ("kw", "field"),
    [
        ({"delta_v_kmh": -1.0}, "delta_v_kmh"),
        ({"delta_v_kmh": float("nan")}, "delta_v_kmh"),
        ({"delta_v_kmh": 250.0}, "delta_v_kmh"),
        ({"delta_v_kmh": "40"}, "delta_v_kmh"),
        ({"age_years": float("inf")}, "age_years"),
        ({"age_years": -3.0}, "age_years"),
        ({"belted": 1}, "belted"),
        ({"sex": "male"}, "sex"),
    ],
)
def test_bad_features_are_refused(model: BaselineModel, kw: dict[str, Any], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        model.predict(_features(**kw))


@pytest.mark.parametrize(
    ("X", "field"),
    [
        (np.zeros((2, 5)), "shape"),
        (np.array([[-5.0, 1, 0, 1, 30, 1]]), "delta_v_kmh"),
        (np.array([[20.0, 0.5, 0, 1, 30, 1]]), "belted"),
        (np.array([[20.0, 1, 0, 1, 300, 1]]), "age_years"),
        (np.array([[20.0, 1, 0, 1, 30, 2]]), "male"),
    ],
)
def test_bad_matrix_is_refused(model: BaselineModel, X: np.ndarray, field: str) -> None:
    with pytest.raises(ValueError, match=field):
        model.predict_many(X)


# --------------------------------------------------------------------------- malformed


def _mutations() -> list[tuple[str, Callable[[dict[str, Any]], Any], str]]:
    def set_(path: list[Any], value: Any) -> Callable[[dict[str, Any]], Any]:
        def f(doc: dict[str, Any]) -> None:
            obj = doc
            for p in path[:-1]:
                obj = obj[p]
            obj[path[-1]] = value

        return f

    def delete(key: str) -> Callable[[dict[str, Any]], Any]:
        return lambda doc: doc.pop(key)

    def asymmetric(doc: dict[str, Any]) -> None:
        doc["covariance"][0][1] += 1.0

    def not_psd(doc: dict[str, Any]) -> None:
        doc["covariance"][0][1] = doc["covariance"][1][0] = 1e3

    return [
        ("schema", set_(["schema"], "something/else"), "schema"),
        ("no coefficients", delete("coefficients"), "coefficients"),
        ("short coefficients", set_(["coefficients"], [0.0, 1.0]), "coefficients"),
        ("string coefficient", set_(["coefficients", 1], "0.07"), r"coefficients\[1\]"),
        ("nan coefficient", set_(["coefficients", 2], float("nan")), r"coefficients\[2\]"),
        ("feature order", set_(["feature_names", 1], "belted"), "feature_names"),
        ("cov shape", set_(["covariance"], [[1.0]]), "covariance"),
        ("cov asymmetric", asymmetric, "symmetric"),
        ("cov diagonal", set_(["covariance", 3, 3], -1.0), "diagonal"),
        ("cov not psd", not_psd, "semi-definite"),
        ("threshold high", set_(["threshold", "value"], 1.5), "threshold"),
        ("threshold missing", set_(["threshold"], {}), "threshold.value"),
        ("imputation", set_(["imputation", "male"], 3.0), "imputation.male"),
        ("model name", set_(["model", "name"], ""), "model.name"),
        ("no fit date", delete("fit_date"), "fit_date"),
    ]


@pytest.mark.parametrize(
    ("label", "mutate", "match"), _mutations(), ids=[m[0] for m in _mutations()]
)
def test_malformed_artifact_raises(
    tmp_path: Path,
    artifact: dict[str, Any],
    label: str,
    mutate: Callable[[dict[str, Any]], Any],
    match: str,
) -> None:
    doc = copy.deepcopy(artifact)
    mutate(doc)
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(ValueError, match=match):
        BaselineModel.from_artifact(path)


@pytest.mark.parametrize("content", [b"", b"{not json", b"[1, 2]", b"\xff\xfe"])
def test_non_json_artifact_raises(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "bad.json"
    path.write_bytes(content)
    with pytest.raises(ValueError, match="malformed baseline artifact"):
        BaselineModel.from_artifact(path)


def test_valid_copy_loads_with_its_own_checksum(tmp_path: Path, artifact: dict[str, Any]) -> None:
    path = tmp_path / "copy.json"
    path.write_text(json.dumps(artifact), encoding="utf-8")
    m = BaselineModel.from_artifact(path)
    assert m.sha256 == hashlib.sha256(path.read_bytes()).hexdigest()
    assert m.predict(_features()) == load_default().predict(_features())


def test_one_occupant_prediction_is_the_design_rows_bit_for_bit(model: BaselineModel) -> None:
    """predict's scalar logistic gives the numbers of the vectorised path on its own row."""
    from models.baseline.logistic import _expit, _expit_one

    x = np.concatenate([np.linspace(-800.0, 800.0, 4001), [0.0, -0.0, 1e-300]])
    assert np.array_equal(_expit(x), np.array([_expit_one(float(v)) for v in x]))
    for dv, age, sex in [(0.0, None, None), (37.5, 81.0, Sex.FEMALE), (150.0, 16.0, Sex.MALE)]:
        f = BaselineFeatures(
            delta_v_kmh=dv,
            belted=dv < 50,
            airbag_deployed=True,
            frontal=dv > 10,
            age_years=age,
            sex=sex,
        )
        one = model.predict(f)
        row = model._predict_design(model.encode(f)[None, :])
        assert one.probability == float(row.probability[0])
        assert one.ci95 == (float(row.ci95_low[0]), float(row.ci95_high[0]))
        assert one.linear_predictor == float(row.linear_predictor[0])
        assert one.standard_error == float(row.standard_error[0])
