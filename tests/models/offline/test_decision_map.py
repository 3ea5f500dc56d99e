"""The decision map reports the service's own decisions (models/decision_map.py)."""

from __future__ import annotations

import dataclasses

import pytest

from models.impact_mode import ImpactMode
from models.notification import Body
from models.offline.decision_map import MODE_PDOF_DEG, decision_rows, first_positive
from models.triage import LPM_THRESHOLDS, EngineModels, load_engine_models


@pytest.fixture(scope="module")
def models() -> EngineModels:
    return load_engine_models()


def test_rows_are_the_services_decisions_and_risk_rises_with_delta_v(
    models: EngineModels,
) -> None:
    rows = decision_rows(
        models,
        bodies=(Body.MALE_50TH,),
        restraints=(("belt + airbag", True, True),),
        delta_v_kmh=(10.0, 40.0, 80.0),
    )
    assert [r.mode for r in rows[::3]] == list(MODE_PDOF_DEG)
    for r in rows:
        assert r.method == "lpm"
        assert r.threshold == LPM_THRESHOLDS[r.mode]
        assert r.iss15_plus == (r.probability >= r.threshold)
    for k in range(0, len(rows), 3):
        p = [r.probability for r in rows[k : k + 3]]
        assert p[0] < p[1] < p[2], (rows[k].mode, p)
    frontal = [r for r in rows if r.mode is ImpactMode.FRONTAL]
    positives = [r.delta_v_kmh for r in frontal if r.iss15_plus]
    assert first_positive(frontal) == (min(positives) if positives else None)
    assert first_positive([dataclasses.replace(r, iss15_plus=False) for r in frontal]) is None
