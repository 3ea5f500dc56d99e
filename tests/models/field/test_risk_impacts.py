"""Feature set 2 (the PDOF seen from the occupant's side, the impact count) and the
feature sets' checksums: older artifacts keep loading with the code they were fitted for."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from models.codehash import source_tree_sha256
from models.field import risk_features, risk_impacts
from models.field.risk_features import (
    ALL_COLUMNS,
    AirbagCode,
    RiskImputation,
    RiskInputs,
    SeatSide,
    design_columns,
    inputs_arrays,
)
from models.field.risk_impacts import (
    ALL_COLUMNS_2,
    IMPACT_COUNT_CLAMP,
    ImpactRiskInputs,
    design_columns_2,
    impact_count_values,
    inputs_arrays_2,
    relative_pdof_deg,
)
from models.field.risk_model import (
    RiskModel,
    canonical_content_sha256,
    feature_code_sha256,
    load_default,
)
from models.field.versions import artifact_for_version


def _occupant(**kw: object) -> ImpactRiskInputs:
    base: dict[str, object] = {
        "delta_v_kmh": 40.0,
        "pdof_deg": 0.0,
        "seat_row": 1,
        "seat_side": SeatSide.LEFT,
        "driver": True,
        "belted": True,
        "frontal_airbag": AirbagCode.DEPLOYED,
        "rollover": False,
        "multiple_impacts": False,
        "age_years": 40.0,
    }
    base.update(kw)
    return ImpactRiskInputs(**base)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("pdof", "side", "expected"),
    [
        (0.0, "left", 0.0),
        (90.0, "right", 90.0),  # from the right, sitting right: near side
        (90.0, "left", -90.0),  # from the right, sitting left: far side
        (270.0, "left", 90.0),  # from the left, sitting left: near side
        (270.0, "right", -90.0),
        (-90.0, "left", 90.0),  # the same direction written negative
        (90.0, "middle", -90.0),  # a middle seat: either side is the far side
        (270.0, "middle", -90.0),
        (180.0, "left", 180.0),  # from behind: 180 on every seat, never -180
        (180.0, "right", 180.0),
        (180.0, "middle", 180.0),
        (-180.0, "left", 180.0),
        (30.0, "right", 30.0),  # oblique, from the right-front
        (30.0, "left", -30.0),
        (390.0, "right", 30.0),  # whole turns removed
    ],
)
def test_the_pdof_seen_from_the_occupants_side(pdof: float, side: str, expected: float) -> None:
    got = relative_pdof_deg(np.array([pdof]), [side])
    assert got[0] == pytest.approx(expected, abs=1e-12)
    assert -180.0 < got[0] <= 180.0


def test_mirror_seats_see_mirror_crashes_alike() -> None:
    pdof = np.linspace(-720.0, 720.0, 289)
    right = relative_pdof_deg(pdof, ["right"] * pdof.size)
    left = relative_pdof_deg(-pdof, ["left"] * pdof.size)
    assert np.allclose(right, left)


def test_an_unknown_impact_count_comes_from_multiple_impacts() -> None:
    counts, imputed = impact_count_values(
        [None, None, 3, 1, 40], [False, True, True, False, True], 2.0
    )
    assert counts.tolist() == [1.0, 2.0, 3.0, 1.0, IMPACT_COUNT_CLAMP[1]]
    assert imputed == (False, True, False, False, False)


def test_feature_set_2_keeps_set_1s_columns_and_appends_two() -> None:
    assert ALL_COLUMNS_2[: len(ALL_COLUMNS)] == ALL_COLUMNS
    assert ALL_COLUMNS_2[len(ALL_COLUMNS) :] == ("pdof_relative_deg", "impact_count")
    imp = RiskImputation(40.0, 0.5, 170.0, 75.0, 4.0, 2010.0, 2014.0)
    people = [
        _occupant(pdof_deg=270.0, multiple_impacts=True),
        _occupant(pdof_deg=90.0, seat_side=SeatSide.RIGHT, driver=False, impact_count=4),
        RiskInputs(  # the plain kind: no count, a single impact is one
            delta_v_kmh=40.0,
            pdof_deg=0.0,
            seat_row=1,
            seat_side=SeatSide.MIDDLE,
            driver=False,
            belted=True,
            frontal_airbag=AirbagCode.NONE,
            rollover=False,
            multiple_impacts=False,
        ),
    ]
    a2, named = inputs_arrays_2(people, imp, 2.0)
    a1, _ = inputs_arrays(people, imp)
    x2, x1 = design_columns_2(a2), design_columns(a1)
    assert np.array_equal(x2[:, : len(ALL_COLUMNS)], x1)
    assert x2[:, -2].tolist() == [90.0, 90.0, 0.0]
    assert x2[:, -1].tolist() == [2.0, 4.0, 1.0]
    assert "impact_count" in named[0]
    assert "impact_count" not in named[1] + named[2]


def test_each_feature_set_has_its_own_code_checksum() -> None:
    set1 = source_tree_sha256([Path(risk_features.__file__)])
    set2 = source_tree_sha256([Path(risk_features.__file__), Path(risk_impacts.__file__)])
    assert feature_code_sha256(ALL_COLUMNS) == set1
    assert feature_code_sha256(ALL_COLUMNS_2) == set2
    assert set1 != set2 != feature_code_sha256()  # the default is the newest set's (3)


@pytest.mark.parametrize("version", ["3.0.0", "3.1.0"])
def test_artifacts_of_feature_set_1_still_load_and_answer(version: str) -> None:
    old = RiskModel.from_artifact(artifact_for_version(version))
    assert old.candidate_columns == ALL_COLUMNS
    assert old.document["feature_code_sha256"] == feature_code_sha256(ALL_COLUMNS)
    assert old.impact_count_imputed is None
    # the impact count is not one of their inputs: it changes nothing and is never named
    a = old.predict(_occupant(multiple_impacts=True))
    b = old.predict(_occupant(multiple_impacts=True, impact_count=6))
    assert a.probability == b.probability
    assert "impact_count" not in a.imputed


def test_an_artifact_naming_unknown_columns_is_refused(tmp_path: Path) -> None:
    doc = json.loads(artifact_for_version("3.1.0").read_text(encoding="utf-8"))
    doc["candidate_columns"] = [*doc["candidate_columns"], "made_up"]
    doc["content_sha256"] = canonical_content_sha256(doc)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(doc), encoding="utf-8")
    with pytest.raises(ValueError, match="no known feature set"):
        RiskModel.from_artifact(bad)


def test_the_shipped_model_uses_and_names_the_impact_count() -> None:
    model = load_default()
    assert model.candidate_columns[: len(ALL_COLUMNS_2)] == ALL_COLUMNS_2
    assert model.impact_count_imputed is not None
    assert 2.0 <= model.impact_count_imputed <= 6.0
    kept = {g for od in model.document["outcomes"].values() for g in od.get("tree_groups", [])}
    assert ("impact_count" in model.used_inputs) == ("impact_count" in kept)
    if "impact_count" not in kept:
        return  # nothing uses it: nothing to name (asserted above)
    guessed = model.predict(_occupant(multiple_impacts=True))
    assert "impact_count" in guessed.imputed
    told = model.predict(
        _occupant(multiple_impacts=True, impact_count=int(model.impact_count_imputed))
    )
    assert "impact_count" not in told.imputed
    assert told.probability == guessed.probability
    single = model.predict(_occupant())
    assert "impact_count" not in single.imputed
