"""The field risk model as served: artifact checks, monotone risk, intervals, published levels."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from models.codehash import normalised_source, source_tree_sha256
from models.field.features import (
    BMI_RANGE,
    FEATURE_NAMES,
    FieldInputs,
    FieldMode,
    Imputation,
    design_matrix,
    field_mode,
)
from models.field.model import (
    OUTCOME,
    FieldModel,
    canonical_content_sha256,
    default_artifact_path,
    feature_code_sha256,
    load_default,
)
from models.impact_mode import ImpactMode
from models.notification import Sex
from models.units import mph_to_kmh


@pytest.fixture(scope="module")
def model() -> FieldModel:
    return load_default()


def _inputs(dv: float, mode: FieldMode = FieldMode.FRONTAL, **kw: object) -> FieldInputs:
    base: dict[str, object] = {
        "delta_v_kmh": dv,
        "mode": mode,
        "belted": True,
        "multiple_impacts": False,
        "age_years": 40.0,
    }
    base.update(kw)
    return FieldInputs(**base)  # type: ignore[arg-type]


def test_the_shipped_artifact_loads_and_names_its_outcome(model: FieldModel) -> None:
    assert model.outcome == OUTCOME == "MAIS3+"
    assert model.default_operating_point == "sens80_per_mode"
    assert set(model.operating_points) == {"sens80", "sens80_per_mode", "bahouth"}
    bahouth = model.operating_points["bahouth"].thresholds
    assert bahouth[FieldMode.FRONTAL] == 0.10
    assert bahouth[FieldMode.NEAR_SIDE] == bahouth[FieldMode.FAR_SIDE] == 0.05
    assert model.bootstrap_coefficients.shape == (200, len(FEATURE_NAMES))


@pytest.mark.parametrize("mode", list(FieldMode))
@pytest.mark.parametrize("belted", [True, False])
def test_risk_does_not_fall_as_delta_v_rises(
    model: FieldModel, mode: FieldMode, belted: bool
) -> None:
    ps = [
        model.predict(_inputs(float(v), mode, belted=belted)).probability
        for v in np.linspace(0.0, 200.0, 81)
    ]
    assert all(b >= a for a, b in zip(ps, ps[1:], strict=False))
    assert ps[-1] > ps[0]


@pytest.mark.parametrize("mode", list(FieldMode))
def test_belted_is_not_worse_than_unbelted(model: FieldModel, mode: FieldMode) -> None:
    for v in (5.0, 20.0, 40.0, 70.0, 120.0):
        belted = model.predict(_inputs(v, mode, belted=True)).probability
        unbelted = model.predict(_inputs(v, mode, belted=False)).probability
        assert belted <= unbelted, (mode, v)


def test_rollover_and_multiple_impacts_raise_the_risk(model: FieldModel) -> None:
    plain = model.predict(_inputs(30.0)).probability
    assert model.predict(_inputs(30.0, FieldMode.ROLLOVER)).probability > plain
    assert model.predict(_inputs(30.0, multiple_impacts=True)).probability > plain


def test_the_interval_holds_the_point_and_widens_off_the_data(model: FieldModel) -> None:
    for v in (2.0, 15.0, 30.0, 60.0, 150.0):
        for mode in FieldMode:
            for sex in (None, Sex.FEMALE, Sex.MALE):
                pred = model.predict(_inputs(v, mode, sex=sex))
                lo, hi = pred.ci95
                assert 0.0 <= lo <= pred.probability <= hi <= 1.0
    near = model.predict(_inputs(20.0))  # plenty of frontal rows at 20 km/h
    far = model.predict(_inputs(20.0, FieldMode.REAR))  # 3 rear positives
    assert far.logit_sd > near.logit_sd


def test_the_interval_is_the_spread_of_the_bootstrap_refits(model: FieldModel) -> None:
    pred = model.predict(_inputs(25.0, FieldMode.NEAR_SIDE, sex=Sex.FEMALE))
    x, _ = design_matrix([_inputs(25.0, FieldMode.NEAR_SIDE)], model.imputation)
    offset = 1.0 - model.female_share
    eta_b = model.bootstrap_coefficients @ x[0] + model.sex_bootstrap * offset
    sd = float(np.std(eta_b, ddof=1))
    assert pred.logit_sd == pytest.approx(sd, rel=1e-12)
    expit = lambda e: 1.0 / (1.0 + math.exp(-e))  # noqa: E731
    assert pred.ci95[0] == pytest.approx(expit(pred.logit - 1.959963984540054 * sd), rel=1e-9)


def test_women_get_the_borrowed_sex_offset(model: FieldModel) -> None:
    """Female log odds ratio borrowed from NASS-CDS 1997-2000: positive, centred."""
    assert model.sex_log_odds_ratio > 0.0
    unknown = model.predict(_inputs(30.0)).logit
    female = model.predict(_inputs(30.0, sex=Sex.FEMALE)).logit
    male = model.predict(_inputs(30.0, sex=Sex.MALE)).logit
    assert male < unknown < female
    assert female - male == pytest.approx(model.sex_log_odds_ratio)


def test_unknown_age_and_body_are_imputed_and_said(model: FieldModel) -> None:
    pred = model.predict(_inputs(30.0, age_years=None))
    assert pred.imputed == ("age_years", "bmi")
    same = model.predict(
        _inputs(
            30.0,
            age_years=model.imputation.age_years,
            stature_cm=100.0,
            mass_kg=model.imputation.bmi,
        )
    )
    assert same.imputed == ()
    assert same.probability == pytest.approx(pred.probability, rel=1e-12)


def test_body_mass_index_is_clamped_to_the_data() -> None:
    imp = Imputation(age_years=32.0, bmi=25.0)
    x, _ = design_matrix([_inputs(20.0, stature_cm=60.0, mass_kg=200.0)], imp)
    assert x[0, FEATURE_NAMES.index("bmi")] == BMI_RANGE[1]


def test_out_of_range_inputs_are_refused_naming_the_field(model: FieldModel) -> None:
    with pytest.raises(ValueError, match="delta_v_kmh"):
        model.predict(_inputs(250.0))
    with pytest.raises(ValueError, match="age_years"):
        model.predict(_inputs(20.0, age_years=float("nan")))


def test_a_reported_rollover_is_the_rollover_mode() -> None:
    assert field_mode(ImpactMode.NEAR_SIDE, rollover=True) is FieldMode.ROLLOVER
    assert field_mode(ImpactMode.NEAR_SIDE, rollover=False) is FieldMode.NEAR_SIDE


def test_crash_modes_keep_augenstein_s_order_at_30_mph(model: FieldModel) -> None:
    """At 30 mph, converted explicitly, a belted 40-year-old's risk keeps the order of
    Augenstein et al. 2003 (near side > far side > frontal > rear).

    Their levels (38.9 % frontal ...) are not held here: their population's covariates
    are not stated, and their frontal level is 5.3 times NHTSA's frontal curve in odds.
    A check of these levels within 0.12 passed on field model 1.0.0 only because it read
    48 km/h as 48 mph; the levels are now held against NHTSA's curves, and the mode
    effects against Augenstein's odds ratios (``test_published_curves.py``)."""
    delta_v_kmh = mph_to_kmh(30.0)
    got = {m: model.predict(_inputs(delta_v_kmh, m)).probability for m in FieldMode}
    order = [FieldMode.NEAR_SIDE, FieldMode.FAR_SIDE, FieldMode.FRONTAL, FieldMode.REAR]
    assert [got[m] for m in order] == sorted((got[m] for m in order), reverse=True)


# ------------------------------------------------------------------ the artifact checks


def _rewrite(tmp_path: Path, edit: object) -> Path:
    doc = json.loads(default_artifact_path().read_text(encoding="utf-8"))
    assert callable(edit)
    edit(doc)
    path = tmp_path / "field.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def test_an_altered_artifact_is_refused(tmp_path: Path) -> None:
    def tamper(doc: dict[str, object]) -> None:
        coef = doc["coefficients"]
        assert isinstance(coef, list)
        coef[1] = coef[1] * 0.5

    with pytest.raises(ValueError, match="altered"):
        FieldModel.from_artifact(_rewrite(tmp_path, tamper))


def test_an_artifact_for_other_feature_code_is_refused(tmp_path: Path) -> None:
    def stale(doc: dict[str, object]) -> None:
        doc["feature_code_sha256"] = "0" * 64
        doc["content_sha256"] = canonical_content_sha256(doc)

    with pytest.raises(ValueError, match="stale"):
        FieldModel.from_artifact(_rewrite(tmp_path, stale))


def test_a_resealed_artifact_with_its_own_checksum_loads(tmp_path: Path) -> None:
    """The content checksum is what detects an edit, not the file's layout."""
    path = _rewrite(tmp_path, lambda doc: None)
    model = FieldModel.from_artifact(path)
    assert model.coefficients.tolist() == load_default().coefficients.tolist()


def test_feature_code_checksum_ignores_docstrings_and_layout(tmp_path: Path) -> None:
    from models.field import features

    src = Path(features.__file__).read_text(encoding="utf-8")
    assert source_tree_sha256([Path(features.__file__)]) == feature_code_sha256()
    reworded = src.replace('"""What the field risk model sees', '"""What the model sees', 1)
    reformatted = reworded.replace(
        "MIN_LOG_DELTA_V_KMH: Final[float] = 1.0", "MIN_LOG_DELTA_V_KMH : Final[float]=1.0"
    )
    assert reworded != src
    assert normalised_source(reformatted) == normalised_source(src)
    changed = src.replace(
        "MIN_LOG_DELTA_V_KMH: Final[float] = 1.0", "MIN_LOG_DELTA_V_KMH: Final[float] = 2.0"
    )
    assert changed != src
    assert normalised_source(changed) != normalised_source(src)
