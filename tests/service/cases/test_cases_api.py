"""POST/GET /v1/cases against a real database (SQLite and PostgreSQL)."""

from __future__ import annotations

import pytest
from fastapi.responses import JSONResponse

from service.cases.examples import EXAMPLE_NOTIFICATIONS
from service.cases.result import CaseResult
from tests.support import ApiClient, assert_problem, example, summary


@pytest.mark.parametrize("kind", sorted(EXAMPLE_NOTIFICATIONS))
def test_each_documented_example_is_triaged_stored_and_read_back(
    api_any_db: ApiClient, kind: str
) -> None:
    body = example(kind)
    response = api_any_db.client.post(
        "/v1/cases", json=body, headers=api_any_db.headers("submitter")
    )
    assert response.status_code == 201, response.text
    result = response.json()
    assert response.headers["Location"] == f"/v1/cases/{result['case_id']}"
    assert response.headers["Idempotent-Replayed"] == "false"
    assert result["event_id"] == body["event_id"]
    assert len(result["occupants"]) == len(body["occupants"])
    lo, hi = result["triage"]["probability_ci95"]
    assert 0.0 <= lo < hi <= 1.0, "the interval is never degenerate"
    assert any(o["triage"] == result["triage"] for o in result["occupants"])
    # the decided probability (field model) always lies in its interval
    assert lo <= result["triage"]["probability"] <= hi
    assert result["triage"]["outcome"] == "ISS15+"
    assert result["vehicle"]["outcome"] == "anyone ISS15+"
    assert result["models"]["baseline"]["sha256"]
    assert result["models"]["field_model"]["sha256"]
    for occ in result["occupants"]:
        if occ["method"] == "lpm":  # its own P is the risk less the curves' zero-load floor
            model = occ["occupant_model"]
            assert 0.0 < occ["probability_zero_load"] < occ["probability_uncorrected"]
            assert model["probability"] < occ["probability_uncorrected"]
            assert model["outcome"] == "ISS15+"
            m_lo, m_hi = model["probability_ci95"]
            assert m_lo <= model["probability"] <= m_hi or occ["point_outside_interval"]
            assert result["models"]["risk_calibration"]["sha256"]
        else:
            assert occ["probability_uncorrected"] is None
            assert occ["occupant_model"] is None

    stored = api_any_db.client.get(
        response.headers["Location"], headers=api_any_db.headers("auditor")
    )
    assert stored.status_code == 200, stored.text
    case = stored.json()
    assert case["result"] == result, "GET returns the case exactly as answered"
    assert case["notification"] == body, "the notification is stored as received"
    assert case["client_name"] == "submitter-client"
    assert case["models"] == result["models"]


def test_case_level_triage_is_the_worst_occupant(api: ApiClient) -> None:
    body = example("delta_v")
    result = api.client.post("/v1/cases", json=body, headers=api.headers("submitter")).json()
    worst = max(o["triage"]["probability"] for o in result["occupants"])
    assert result["triage"]["probability"] == worst


def test_same_event_same_body_replays_without_storing(api_any_db: ApiClient) -> None:
    body = summary(event_id="evt-replay-1")
    h = api_any_db.headers("submitter")
    first = api_any_db.client.post("/v1/cases", json=body, headers=h)
    assert first.status_code == 201
    # same JSON document, keys in another order: the same body
    reordered = dict(reversed(list(body.items())))
    again = api_any_db.client.post("/v1/cases", json=reordered, headers=h)
    assert again.status_code == 200, again.text
    assert again.headers["Idempotent-Replayed"] == "true"
    assert again.json() == first.json()
    listing = api_any_db.client.get("/v1/cases", headers=api_any_db.headers("auditor")).json()
    assert [c["case_id"] for c in listing["items"]] == [first.json()["case_id"]]


def test_a_new_case_is_answered_with_the_bytes_of_its_result_and_of_its_replay(
    api: ApiClient,
) -> None:
    """The 201 answer is built from the stored payload (no second dump of the result):
    byte for byte what the result model dumps, and what a replay of the stored case
    answers."""
    body = example("delta_v")
    h = api.headers("submitter")
    first = api.client.post("/v1/cases", json=body, headers=h)
    assert first.status_code == 201
    dumped = CaseResult.model_validate_json(first.content).model_dump(mode="json")
    assert list(dumped)[-2:] == ["stored", "spooled"]
    assert first.content == bytes(JSONResponse(dumped).body)
    again = api.client.post("/v1/cases", json=body, headers=h)
    assert again.status_code == 200
    assert again.content == first.content


def test_same_event_different_body_is_a_conflict(api_any_db: ApiClient) -> None:
    h = api_any_db.headers("submitter")
    assert (
        api_any_db.client.post(
            "/v1/cases", json=summary(50.0, event_id="evt-409"), headers=h
        ).status_code
        == 201
    )
    conflict = api_any_db.client.post(
        "/v1/cases", json=summary(60.0, event_id="evt-409"), headers=h
    )
    problem = assert_problem(conflict, 409)
    assert "evt-409" in problem["detail"]


def test_event_ids_are_per_client(api: ApiClient) -> None:
    body = summary(event_id="evt-shared")
    a = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    b = api.client.post("/v1/cases", json=body, headers=api.headers("submitter2"))
    assert a.status_code == b.status_code == 201
    assert a.json()["case_id"] != b.json()["case_id"]


def test_auth_missing_unknown_and_wrong_role(api: ApiClient) -> None:
    body = summary()
    assert_problem(api.client.post("/v1/cases", json=body), 401)
    assert_problem(
        api.client.post("/v1/cases", json=body, headers={"Authorization": "Bearer aacn_nope"}),
        401,
    )
    assert_problem(api.client.get("/v1/cases"), 401)
    assert_problem(api.client.post("/v1/cases", json=body, headers=api.headers("auditor")), 403)
    assert_problem(api.client.get("/v1/cases", headers=api.headers("submitter")), 403)
    # admins may do both
    created = api.client.post("/v1/cases", json=body, headers=api.headers("admin"))
    assert created.status_code == 201
    assert (
        api.client.get(created.headers["Location"], headers=api.headers("admin")).status_code == 200
    )


def test_no_key_gets_401_even_with_a_bad_body(api: ApiClient) -> None:
    assert_problem(api.client.post("/v1/cases", json={"nonsense": True}), 401)


def test_unknown_case_is_404(api: ApiClient) -> None:
    assert_problem(api.client.get("/v1/cases/nope", headers=api.headers("auditor")), 404)


def test_same_notification_gives_the_same_answer_bit_for_bit(api: ApiClient) -> None:
    h = api.headers("submitter")
    a = api.client.post("/v1/cases", json=example("acceleration"), headers=h).json()
    b = api.client.post("/v1/cases", json=example("acceleration"), headers=h).json()
    for volatile in ("case_id", "event_id", "received_at", "timings_ms"):
        a.pop(volatile)
        b.pop(volatile)
    assert a == b


def test_side_airbags_reach_the_near_side_model(api: ApiClient) -> None:
    """A near-side driver with deployed side and curtain airbags is answered by the
    near-side model with its bags; without the field the service assumes none and
    says so."""
    answers = {}
    for state in ("deployed", None):
        body = summary(30.0, 270.0)
        if state is not None:
            body["occupants"][0]["side_airbag"] = state
        response = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
        assert response.status_code == 201, response.text
        answers[state] = response.json()
    with_bags, unknown = answers["deployed"], answers[None]
    for result in (with_bags, unknown):
        assert result["occupants"][0]["impact_mode"] == "near_side"
        assert result["occupants"][0]["method"] == "lpm"
    assert any("side airbag state not reported" in a["message"] for a in unknown["assumptions"])
    assert not any("side airbag" in a["message"] for a in with_bags["assumptions"])
    bags, none = with_bags["occupants"][0], unknown["occupants"][0]
    assert bags["measures"]["hic15"] < none["measures"]["hic15"]
    assert bags["iss"]["estimate"] <= none["iss"]["estimate"]
    assert bags["triage"]["probability"] <= none["triage"]["probability"]


def test_a_notification_with_second_row_occupants_is_triaged_not_refused(
    api: ApiClient,
) -> None:
    body = summary(40.0, 0.0)
    body["occupants"] += [
        {"seat": "rear_left", "age_years": 9, "belted": True, "frontal_airbag": "absent"},
        {"seat": "rear_right", "age_years": 40, "belted": False, "frontal_airbag": "absent"},
    ]
    response = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    assert response.status_code == 201, response.text
    result = response.json()
    assert [o["method"] for o in result["occupants"]] == ["lpm", "field", "field"]
    codes = [(a["code"], a["occupant"]) for a in result["assumptions"]]
    assert ("seat_without_occupant_model", 1) in codes
    assert ("seat_without_occupant_model", 2) in codes
    # the 9-year-old is in the field data (children included); its region risks are the
    # adults' models' (carried from 3.2.0): said so
    assert ("outside_field_population", 1) not in codes
    assert ("child_region_risk_extrapolated", 1) in codes
    for o in result["occupants"]:
        assert o["triage"]["outcome"] == "ISS15+"
        assert len(o["region_risk"]) == 8


def test_posture_and_seat_evidence_reach_the_answer(api: ApiClient) -> None:
    """Without posture or seat readings the answer says what it assumed; the EDR
    seat track switch narrows the seat to the forward part of the track; a reading
    is used as given. The decision (field model) does not see posture or seat; the
    occupant model's P is the mean over the spread where nothing was sensed."""
    answers = {}
    for label, extra in {
        "none": {},
        "switch": {"seat_track_foremost": True},
        "reading": {"posture_lumbar_flexion_deg": 5.8, "seat_track_mm": 0.0},
    }.items():
        body = summary(56.0, 0.0, event_id=f"evidence-{label}")
        occ = body["occupants"][0]
        for key in ("posture_lumbar_flexion_deg", "seat_track_mm", "seat_track_foremost"):
            occ.pop(key, None)
        occ.update(extra)
        response = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
        assert response.status_code == 201, response.text
        answers[label] = response.json()
    notes = {k: " ".join(a["message"] for a in v["assumptions"]) for k, v in answers.items()}
    assert "posture not sensed" in notes["none"]
    assert "seat position not sensed" in notes["none"]
    assert "seat track switch says foremost" in notes["switch"]
    assert "not sensed" not in notes["reading"]
    decided = {k: v["occupants"][0]["triage"] for k, v in answers.items()}
    assert decided["none"] == decided["switch"] == decided["reading"]
    p = {k: v["occupants"][0]["occupant_model"]["probability"] for k, v in answers.items()}
    assert p["switch"] != p["reading"]  # the run is in the forward part of the track
    measures = {k: v["occupants"][0]["measures"] for k, v in answers.items()}
    assert measures["none"] == measures["reading"]  # the direct run at the nominal inputs
    used = {k: v["occupants"][0]["sensor_inputs"] for k, v in answers.items()}
    assert used["reading"] == pytest.approx(
        {
            "posture_deg": 5.8,
            "posture_sd_deg": 2.551,
            "seat_track_mm": 0.0,
            "seat_track_sd_mm": 25.51,
        },
        abs=1e-3,
    )
    assert used["none"]["posture_sd_deg"] == pytest.approx(25.0 / 12**0.5)
    assert used["none"]["seat_track_sd_mm"] == pytest.approx(240.0 / 12**0.5)
    assert used["switch"]["seat_track_mm"] == pytest.approx(80.0)
    assert used["switch"]["seat_track_sd_mm"] == pytest.approx(80.0 / 12**0.5)
    case_id = answers["switch"]["case_id"]
    stored = api.client.get(f"/v1/cases/{case_id}", headers=api.headers("auditor")).json()
    assert stored["result"]["occupants"][0]["sensor_inputs"] == used["switch"]


def test_a_malformed_seat_switch_is_refused_naming_the_field(api: ApiClient) -> None:
    body = summary()
    body["occupants"][0]["seat_track_foremost"] = "sometimes"
    problem = assert_problem(
        api.client.post("/v1/cases", json=body, headers=api.headers("submitter")), 422
    )
    assert "seat_track_foremost" in str(problem)
