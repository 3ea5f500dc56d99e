"""The field-calibrated decision through the HTTP contract: stored, named, verified."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from models.field.risk_model import canonical_content_sha256, default_artifact_path, load_default
from service.app import create_app
from service.settings import Settings
from tests.support import ApiClient, assert_problem, summary


def test_every_stored_case_records_the_field_model(api_any_db: ApiClient) -> None:
    field = load_default()
    body = summary(35.0, 0.0)
    response = api_any_db.client.post(
        "/v1/cases", json=body, headers=api_any_db.headers("submitter")
    )
    assert response.status_code == 201, response.text
    result = response.json()
    info = result["models"]["field_model"]
    assert info == {"version": field.version, "sha256": field.sha256}
    assert field.sha256 == hashlib.sha256(default_artifact_path().read_bytes()).hexdigest()
    occ = result["occupants"][0]
    assert occ["triage"]["model"] == f"{field.name}@{field.version}"
    assert occ["triage"]["outcome"] == "ISS15+"
    assert occ["triage"]["operating_point"] == "sens85"
    assert occ["triage"]["threshold"] == field.threshold("sens85")
    assert result["vehicle"]["model"] == f"{field.name}@{field.version}"
    assert result["vehicle"]["heldout_auc"] == field.vehicle_heldout_auc
    assert set(occ["region_risk"]) == set(field.regions)
    assert occ["field_mode"] == "frontal"
    stored = api_any_db.client.get(
        f"/v1/cases/{result['case_id']}", headers=api_any_db.headers("auditor")
    )
    assert stored.status_code == 200
    assert stored.json()["models"]["field_model"] == info
    assert stored.json()["result"] == result


def test_the_decision_responds_to_what_the_field_data_know(api: ApiClient) -> None:
    """Belt, rollover, multiple impacts and age move the decided probability."""

    def p(**changes: object) -> float:
        body = summary(30.0, 0.0)
        crash = body["crash"]
        occ = body["occupants"][0]
        for key, value in changes.items():
            if key in ("rollover", "multiple_impacts"):
                crash[key] = value
            else:
                occ[key] = value
        r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
        assert r.status_code == 201, r.text
        return float(r.json()["occupants"][0]["triage"]["probability"])

    base = p()
    assert p(belted=False) > base
    assert p(rollover=True) > base
    assert p(multiple_impacts=True) > base
    assert p(age_years=80) > p(age_years=20)


def test_the_impact_count_is_read_checked_and_named_when_imputed(api: ApiClient) -> None:
    field = load_default()

    def post(**crash: object) -> dict[str, object]:
        body = summary(45.0, 270.0)
        body["crash"].pop("multiple_impacts")  # the example says false: the count alone
        body["crash"].update(crash)
        r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
        assert r.status_code == 201, r.text
        return dict(r.json())

    def codes(result: dict[str, object]) -> set[str]:
        return {a["code"] for a in result["assumptions"]}  # type: ignore[attr-defined]

    guessed = post(multiple_impacts=True)
    counted = post(impact_count=int(field.impact_count_imputed or 2))  # implies multiple
    single = post(impact_count=1)
    assert "multiple_impacts_reported" in codes(counted)
    assert "impact_count_imputed" not in codes(counted) | codes(single)
    uses_count = "impact_count" in field.used_inputs
    assert ("impact_count_imputed" in codes(guessed)) == uses_count
    p = [float(r["occupants"][0]["triage"]["probability"]) for r in (guessed, counted)]  # type: ignore[index]
    assert p[0] == p[1], "the imputed count is the count sent"
    assert "multiple_impacts_reported" not in codes(single)
    # contradictions and impossible counts are refused, naming the field
    for crash, said in (
        ({"impact_count": 3, "multiple_impacts": False}, "impact_count 3 contradicts"),
        ({"impact_count": 1, "multiple_impacts": True}, "impact_count 1 contradicts"),
        ({"impact_count": 0}, "impact_count"),
        ({"impact_count": 2.5}, "impact_count"),
    ):
        body = summary(45.0, 270.0)
        body["crash"].update(crash)
        r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
        problem = assert_problem(r, 422)
        assert said in json.dumps(problem), problem


def test_quarter_turns_imply_a_rollover_and_contradict_an_explicit_false(api: ApiClient) -> None:
    """One rule with VEDS: turns above 0 are a rollover; never silently dropped."""
    body = summary(34.0, 0.0, event_id="turns-imply-rollover")
    body["crash"].pop("rollover")  # the example says false
    body["crash"]["rollover_quarter_turns"] = 8
    r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    assert r.status_code == 201, r.text
    implied = r.json()
    assert "rollover_reported" in {a["code"] for a in implied["assumptions"]}
    assert implied["occupants"][0]["field_mode"] == "rollover"
    # said outright it is the same notification: the same answer, replayed
    said = json.loads(json.dumps(body))
    said["crash"]["rollover"] = True
    again = api.client.post("/v1/cases", json=said, headers=api.headers("submitter"))
    assert again.status_code == 200, again.text
    assert again.json()["case_id"] == implied["case_id"]
    other = summary(34.0, 0.0)
    other["crash"].update(rollover=True, rollover_quarter_turns=8)
    rolled = api.client.post("/v1/cases", json=other, headers=api.headers("submitter")).json()
    p = [o["occupants"][0]["triage"]["probability"] for o in (implied, rolled)]
    assert p[0] == p[1]
    # an explicit false with turns is refused, naming the field; nothing stored
    body["crash"]["rollover"] = False
    body["event_id"] = "turns-contradict-rollover"
    r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    problem = assert_problem(r, 422)
    assert [e["field"] for e in problem["errors"]] == ["crash.rollover_quarter_turns"]
    assert "8 quarter turns contradict rollover false" in problem["errors"][0]["reason"]
    body["crash"]["rollover_quarter_turns"] = 0  # no turn: false stands
    assert (
        api.client.post("/v1/cases", json=body, headers=api.headers("submitter")).status_code == 201
    )


@pytest.mark.parametrize("operating_point", ["acs_cot", "sens85"])
def test_the_operating_point_is_configurable(tmp_path: Path, operating_point: str) -> None:
    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'a.db'}", operating_point=operating_point
    )
    with TestClient(create_app(settings)) as client:
        assert client.get("/readyz").status_code == 200
        from service.auth import Role, create_api_key

        _, key = create_api_key(
            client.app.state.ctx.sessions,  # type: ignore[attr-defined]
            name="c",
            role=Role.SUBMITTER,
        )
        r = client.post(
            "/v1/cases", json=summary(30.0, 0.0), headers={"Authorization": f"Bearer {key}"}
        )
        assert r.status_code == 201, r.text
        triage = r.json()["occupants"][0]["triage"]
        assert triage["operating_point"] == operating_point
        expected = load_default().threshold(operating_point)
        assert triage["threshold"] == expected
        if operating_point == "acs_cot":
            assert expected < load_default().threshold("sens85")


def test_an_unknown_operating_point_leaves_the_service_not_ready(tmp_path: Path) -> None:
    settings = Settings(database_url=f"sqlite:///{tmp_path / 'a.db'}", operating_point="nope")
    with TestClient(create_app(settings)) as client:
        problem = assert_problem(client.get("/readyz"), 503)
        assert "operating point" in json.dumps(problem)


def _copy(tmp_path: Path, edit: object) -> Path:
    doc = json.loads(default_artifact_path().read_text(encoding="utf-8"))
    assert callable(edit)
    edit(doc)
    path = tmp_path / "field.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    return path


def test_readyz_is_503_on_an_altered_field_artifact(tmp_path: Path) -> None:
    def tamper(doc: dict[str, object]) -> None:
        doc["imputation"] = {"age_years": 80.0, "bmi": 25.0}

    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'a.db'}", field_artifact=_copy(tmp_path, tamper)
    )
    with TestClient(create_app(settings)) as client:
        problem = assert_problem(client.get("/readyz"), 503)
        assert "altered" in json.dumps(problem)


def test_readyz_is_503_on_a_stale_field_artifact(tmp_path: Path) -> None:
    def stale(doc: dict[str, object]) -> None:
        doc["feature_code_sha256"] = hashlib.sha256(b"other feature code").hexdigest()
        doc["content_sha256"] = canonical_content_sha256(doc)

    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'a.db'}", field_artifact=_copy(tmp_path, stale)
    )
    with TestClient(create_app(settings)) as client:
        problem = assert_problem(client.get("/readyz"), 503)
        assert "stale" in json.dumps(problem)


def test_enumerations_and_assumption_codes_are_in_the_openapi_document(api: ApiClient) -> None:
    from models.assumptions import DESCRIPTIONS, AssumptionCode

    doc = api.client.get("/openapi.json").json()
    schemas = doc["components"]["schemas"]
    assert set(schemas["Method"]["enum"]) == {"lpm", "field"}
    assert set(schemas["IntervalMethod"]["enum"]) == {"pce_bootstrap", "lpm_sensor_box"}
    assert set(schemas["ImpactMode"]["enum"]) == {"frontal", "rear", "near_side", "far_side"}
    assert set(schemas["FieldMode"]["enum"]) >= {"rollover"}
    assert set(schemas["AssumptionCode"]["enum"]) == {c.value for c in AssumptionCode}
    assert set(DESCRIPTIONS) == set(AssumptionCode), "every code is documented"


def test_assumptions_carry_codes_an_integrator_can_act_on(api: ApiClient) -> None:
    body = summary(30.0, 0.0)
    occ = body["occupants"][0]
    for key in ("age_years", "posture_lumbar_flexion_deg", "seat_track_mm", "body"):
        occ.pop(key, None)
    body["crash"]["rollover"] = True
    r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    assert r.status_code == 201, r.text
    codes = {(a["code"], a["occupant"]) for a in r.json()["assumptions"]}
    assert ("rollover_reported", None) in codes
    assert ("inputs_integrated", 0) in codes  # an unknown age is integrated over, not imputed
    assert ("age_imputed", 0) not in codes
    assert ("body_unknown", 0) in codes
    assert ("posture_not_sensed", 0) in codes
    assert ("seat_position_not_sensed", 0) in codes
    for a in r.json()["assumptions"]:
        assert a["message"]


def test_the_readme_example_answers_over_http_as_the_readme_says(api: ApiClient) -> None:
    """The README's generated block answers its example through the engine directly
    (models/offline/field/readme.py); the real HTTP path gives the same decision."""
    import json

    from models.offline.field.readme import README_EXAMPLE, example_answer

    doc = json.loads(default_artifact_path().read_text(encoding="utf-8"))
    expected = example_answer(doc)
    r = api.client.post("/v1/cases", json=README_EXAMPLE, headers=api.headers("submitter"))
    assert r.status_code == 201, r.text
    got = r.json()["triage"]
    for key in ("probability", "probability_ci95", "threshold", "model", "operating_point"):
        assert got[key] == expected[key], key
    assert got["recommendation"] == expected["recommendation"]
    assert got["tier"] == expected["tier"]


def test_the_readme_tier_examples_answer_over_http_as_the_readme_says(api: ApiClient) -> None:
    """Each tier's example of the README's generated block, through the real HTTP path."""
    import json

    from models.offline.field.readme import TIER_EXAMPLES, example_answer

    doc = json.loads(default_artifact_path().read_text(encoding="utf-8"))
    expected = example_answer(doc)["tiers"]
    for tier, body in TIER_EXAMPLES.items():
        r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
        assert r.status_code == 201, r.text
        got = r.json()["triage"]
        assert got["tier"] == expected[tier]["tier"] == tier
        for key in ("probability", "probability_ci95", "threshold", "recommendation"):
            assert got[key] == expected[tier][key], (tier, key)
