"""The recalibration's engine (``models.field.recalibration``, ``models.field.recalibrated``)
and its loading (``RiskModel`` applies it): the minimum derived, the fit recovering a known
map with honest standard errors, thresholds mapped, the artifact checked at load."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from models.constants import Z_95
from models.field.model import canonical_content_sha256
from models.field.recalibrated import local_version, recalibrated_document
from models.field.recalibration import (
    MIN_EFFECTIVE_EVENTS,
    SE_LOGIT_REQUIRED,
    CrossValidation,
    apply_recalibration,
    compose,
    cross_validate,
    fit_recalibration,
    fold_of,
    map_threshold,
    precision_plan,
)
from models.field.risk_model import RiskModel, load_default


def _logit(p: np.ndarray) -> np.ndarray:
    return np.log(p) - np.log1p(-p)


def _draw(n: int, a: float, b: float, seed: int) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Served probabilities (logit normal around -3, sd 1.5) and outcomes of the map."""
    rng = np.random.default_rng(seed)
    p = 1.0 / (1.0 + np.exp(-rng.normal(-3.0, 1.5, n)))
    y = (rng.random(n) < apply_recalibration(p, a, b)).astype(float)
    return p, y, [f"c{i}" for i in range(n)]


def test_the_minimum_is_derived_from_the_precision() -> None:
    assert SE_LOGIT_REQUIRED == pytest.approx(math.log(1.25) / Z_95)
    assert MIN_EFFECTIVE_EVENTS == math.ceil((Z_95 / math.log(1.25)) ** 2) == 78


def test_refused_below_the_minimum_and_weights_count_by_their_effective_number() -> None:
    p = np.full(1000, 0.1)
    y = np.zeros(1000)
    y[:77] = 1
    assert precision_plan(p, y, np.ones(1000)).method == "refused"
    y[77] = 1
    assert precision_plan(p, y, np.ones(1000)).method != "refused"
    # 100 events, one of them weighing as much as the rest together: about 4 effective
    w = np.ones(1000)
    w[0] = 99.0
    y[:100] = 1
    plan = precision_plan(p, y, w)
    assert plan.effective_events == pytest.approx(198.0**2 / (99.0**2 + 99.0))
    assert plan.method == "refused"
    assert "78 effective linked ISS 15+" in plan.reason


def test_a_slope_needs_spread_in_the_events_logits() -> None:
    p, y, _ = _draw(4000, 0.0, 1.0, 1)
    assert precision_plan(p, y, np.ones_like(p)).method == "intercept_and_slope"
    flat = np.full_like(p, 0.05)  # every logit alike: the slope cannot be known
    assert precision_plan(flat, y, np.ones_like(p)).method == "intercept"


def test_the_fit_recovers_a_known_map() -> None:
    p, y, crash = _draw(20_000, -0.7, 0.8, 2)
    r = fit_recalibration(p, y, np.ones_like(p), crash, "intercept_and_slope")
    assert abs(r.intercept + 0.7) < 3 * r.intercept_se
    assert abs(r.slope - 0.8) < 3 * r.slope_se
    only = fit_recalibration(p, y, np.ones_like(p), crash, "intercept")
    assert only.slope == 1.0
    assert only.slope_se == 0.0


def test_at_the_minimum_the_intercept_is_known_to_the_stated_precision() -> None:
    """Over repeated samples of 78 expected ISS 15+ (unit weights), the intercept's spread
    is about the 0.114 the minimum was derived for (within sampling error)."""
    estimates = []
    for seed in range(200):
        rng = np.random.default_rng(seed)
        p = np.full(1560, 0.05)  # 78 expected events
        y = (rng.random(p.size) < p).astype(float)
        r = fit_recalibration(p, y, np.ones_like(p), [str(i) for i in range(p.size)], "intercept")
        estimates.append(r.intercept)
    assert 0.09 < float(np.std(estimates)) < 0.14


def test_thresholds_map_so_the_same_occupants_are_flagged() -> None:
    p = np.linspace(0.001, 0.9, 5000)
    a, b = -0.6, 1.2
    t = 0.0167
    assert np.array_equal(p >= t, apply_recalibration(p, a, b) >= map_threshold(t, a, b))
    a2, b2 = compose((a, b), (0.3, 0.9))
    both = apply_recalibration(apply_recalibration(p, a, b), 0.3, 0.9)
    assert np.allclose(apply_recalibration(p, a2, b2), both, rtol=1e-12)


def test_folds_are_by_crash_and_deterministic() -> None:
    assert fold_of("case-1", 5) == fold_of("case-1", 5)
    p, y, _ = _draw(3000, -0.8, 1.0, 3)
    crash = [f"k{i // 3}" for i in range(p.size)]  # three occupants a crash
    cv = cross_validate(p, y, np.ones_like(p), crash, "intercept_and_slope")
    assert cv == cross_validate(p, y, np.ones_like(p), crash, "intercept_and_slope")
    assert cv.improves
    assert abs(cv.recalibrated_ratio - 1.0) < abs(cv.served_ratio - 1.0)


def _recalibrated(served: RiskModel, a: float, b: float) -> dict[str, object]:
    p, y, crash = _draw(2000, a, b, 4)
    plan = precision_plan(p, y, np.ones_like(p))
    fit = fit_recalibration(p, y, np.ones_like(p), crash, "intercept_and_slope")
    return recalibrated_document(
        served.document,
        version=local_version(served.version, "test-site", []),
        site="test-site",
        recalibration=fit,
        plan=plan,
        cross_validation=CrossValidation(5, 1.0, 1.0, 0.1, 0.1),
        occupants=crash,
        cases=len(crash),
    )


def test_versions_and_the_loader_refuses_an_altered_recalibration(tmp_path: Path) -> None:
    served = load_default()
    assert local_version("3.3.0+local.a.2", "a", ["3.3.0+local.a.1", "3.3.0+local.a.2"]) == (
        "3.3.0+local.a.3"
    )
    with pytest.raises(ValueError, match="lower-case"):
        local_version("3.3.0", "A site", [])
    doc = _recalibrated(served, -0.5, 1.0)
    model = RiskModel.from_document(doc)
    assert model.version == f"{served.version}+local.test-site.1"
    assert model.recalibration == (doc["recalibration"]["intercept"], doc["recalibration"]["slope"])  # type: ignore[index]
    path = tmp_path / "field_iss15-local.json"
    altered = json.loads(json.dumps(doc))
    altered["recalibration"]["intercept"] = 0.0
    path.write_text(json.dumps(altered))
    with pytest.raises(ValueError, match="altered"):
        RiskModel.from_artifact(path)
    altered["recalibration"]["slope"] = -1.0
    altered["content_sha256"] = canonical_content_sha256(altered)
    path.write_text(json.dumps(altered))
    with pytest.raises(ValueError, match="positive slope"):
        RiskModel.from_artifact(path)


def test_the_loader_applies_it_to_rows_deterministically() -> None:
    served = load_default()
    doc = _recalibrated(served, -0.5, 1.0)
    model = RiskModel.from_document(doc)
    a, b = model.recalibration or (0.0, 1.0)
    x = np.zeros((4, len(served.candidate_columns)))
    x[:, 0] = 1.0
    x[:, served.candidate_columns.index("delta_v_kmh")] = [20.0, 40.0, 60.0, 80.0]
    before = served.decision_probability(x)
    after = model.decision_probability(x)
    assert np.allclose(after, apply_recalibration(before, a, b), rtol=1e-12)
    assert np.array_equal(after, RiskModel.from_document(doc).decision_probability(x))


def test_a_recalibrated_model_recalibrated_again_composes() -> None:
    served = load_default()
    first = RiskModel.from_document(_recalibrated(served, -0.5, 1.0))
    second = RiskModel.from_document(_recalibrated(first, 0.4, 0.9))
    assert (
        second.version == f"{served.version}+local.test-site.1"
    )  # numbered against the given list
    fa, fb = first.recalibration or (0.0, 1.0)
    doc = second.document["recalibration"]
    sa, sb = doc["fitted"]["intercept"], doc["fitted"]["slope"]
    assert doc["fitted"]["on_version"] == first.version
    x = np.zeros((3, len(served.candidate_columns)))
    x[:, 0] = 1.0
    x[:, served.candidate_columns.index("delta_v_kmh")] = [30.0, 50.0, 70.0]
    twice = apply_recalibration(apply_recalibration(served.decision_probability(x), fa, fb), sa, sb)
    assert np.allclose(second.decision_probability(x), twice, rtol=1e-10)
    t = served.thresholds["sens85"]
    assert second.thresholds["sens85"] == pytest.approx(
        map_threshold(map_threshold(t, fa, fb), sa, sb), rel=1e-12
    )
