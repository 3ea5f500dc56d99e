"""Everyone in the car: nine occupants, eight VEDS seats, children, unknown ages and belts."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from lxml import etree

from models.notification import Seat
from service.nemsis.validate import validate
from tests.support import ApiClient, assert_problem, example, post_case, stored_case

VEDS_DOCS = Path(__file__).parent / "veds"
NS = {"n": "http://www.nemsis.org"}
AGENCY = {"agency_state_id": "C034", "agency_number": "351-C034P2", "agency_state": "09"}
VEDS_MEDIA_TYPE = "application/EmergencyCallData.VEDS+xml"

#: Every seat the wire names, and who sits there in a full minivan.
_FAMILY: list[dict[str, Any]] = [
    {"seat": "driver", "age_years": 44, "sex": "female", "belted": True},
    {"seat": "front_passenger", "age_years": 46, "sex": "male", "belted": True},
    {"seat": "front_middle", "belted": True},
    {"seat": "rear_left", "age_years": 7, "child_restraint": "booster"},
    {"seat": "rear_middle", "age_years": 1, "child_restraint": "rear_facing_seat"},
    {"seat": "rear_right", "age_years": 12, "child_restraint": "lap_shoulder_belt"},
    {"seat": "third_row_left", "age_years": 70, "belted": False},
    {"seat": "third_row_middle"},
    {"seat": "third_row_right", "age_years": 15, "belted": True},
]


def _minivan(event_id: str | None = None) -> dict[str, Any]:
    body = example("summary", event_id=event_id)
    body["crash"]["pulse"] = {"kind": "summary", "delta_v_kmh": 45, "pdof_deg": 0}
    occupants = []
    for o in _FAMILY:
        occ = dict(o)
        occ["frontal_airbag"] = "deployed" if Seat(o["seat"]).front_row else "absent"
        occupants.append(occ)
    body["occupants"] = occupants
    return body


def test_every_seat_is_answered_nine_occupants(api: ApiClient) -> None:
    answer = post_case(api, _minivan())
    assert [o["seat"] for o in answer["occupants"]] == [o["seat"] for o in _FAMILY]
    for o in answer["occupants"]:
        t = o["triage"]
        assert 0.0 < t["probability"] < 1.0
        assert t["probability_ci95"][0] <= t["probability"] <= t["probability_ci95"][1]
    worst = max(o["triage"]["probability"] for o in answer["occupants"])
    assert answer["vehicle"]["probability"] >= worst
    stored = stored_case(api, answer["case_id"])
    assert len(stored["notification"]["occupants"]) == 9
    r = api.client.get(
        f"/v1/cases/{answer['case_id']}/nemsis", params=AGENCY, headers=api.headers("auditor")
    )
    assert r.status_code == 200, r.text
    assert validate(r.content) == []
    reports = etree.fromstring(r.content).findall("n:Header/n:PatientCareReport", NS)
    assert len(reports) == 9


def test_a_tenth_occupant_is_refused_and_a_seat_named_twice_is_named(api: ApiClient) -> None:
    body = _minivan()
    body["occupants"].append(dict(body["occupants"][0]))
    problem = assert_problem(
        api.client.post("/v1/cases", json=body, headers=api.headers("submitter")), 422
    )
    assert any(e["field"] == "occupants" for e in problem["errors"])
    twice = _minivan()
    twice["occupants"][8]["seat"] = "rear_left"
    problem = assert_problem(
        api.client.post("/v1/cases", json=twice, headers=api.headers("submitter")), 422
    )
    assert "rear_left" in str(problem["errors"])
    assert "twice" in str(problem["errors"])


def _veds_eight_seats() -> bytes:
    """The kph frontal VEDS document with seats 1-8 occupied (eight seats reported)."""
    raw = (VEDS_DOCS / "kph-frontal.xml").read_text(encoding="utf-8")
    seat = re.compile(r"\s*<veds:VehicleSeat>.*?</veds:VehicleSeat>", re.S)
    first = seat.search(raw)
    assert first is not None
    seats = "".join(
        "\n\t\t\t<veds:VehicleSeat>"
        f"<veds:VehicleSeatLocationCategoryCode>{code}</veds:VehicleSeatLocationCategoryCode>"
        "<veds:VehicleSeatOccupiedIndicator>true</veds:VehicleSeatOccupiedIndicator>"
        + (
            "<veds:VehicleSeatbeltFastenedIndicator>true</veds:VehicleSeatbeltFastenedIndicator>"
            "<veds:VehicleSeatbeltMonitoredIndicator>true</veds:VehicleSeatbeltMonitoredIndicator>"
            if code <= 2
            else ""  # rear belts not monitored: belt use unknown
        )
        + "</veds:VehicleSeat>"
        for code in range(1, 9)
    )
    without = seat.sub("", raw)
    at = first.start()
    return (without[:at] + seats + without[at:]).encode()


def test_a_veds_document_with_eight_occupied_seats_is_answered(api: ApiClient) -> None:
    r = api.client.post(
        "/v1/cases",
        content=_veds_eight_seats(),
        headers={**api.headers("submitter"), "Content-Type": VEDS_MEDIA_TYPE},
    )
    assert r.status_code == 201, r.text
    answer = r.json()
    assert len(answer["occupants"]) == 8
    codes = [(a["code"], a.get("occupant")) for a in answer["assumptions"]]
    # the rear belts are not monitored: unknown, never "unbelted"
    for i in range(2, 8):
        assert ("belt_unknown", i) in codes
        assert ("veds_belt_not_reported", i) in codes
    assert ("belt_unknown", 0) not in codes


def _child_in_seat(seat: str = "rear_left", **occupant: Any) -> dict[str, Any]:
    body = example("summary")
    body["crash"]["pulse"] = {"kind": "summary", "delta_v_kmh": 50, "pdof_deg": 0}
    child = {
        "seat": seat,
        "age_years": 3,
        "child_restraint": "forward_facing_seat",
        "frontal_airbag": "absent" if not Seat(seat).front_row else "not_deployed",
    }
    child.update(occupant)
    body["occupants"] = [child]
    return body


def test_a_child_in_a_child_seat_is_answered_by_the_childrens_model(api: ApiClient) -> None:
    answer = post_case(api, _child_in_seat())
    codes = {a["code"] for a in answer["assumptions"]}
    assert "outside_field_population" not in codes  # children are in the field data now
    t = answer["occupants"][0]["triage"]
    assert t["knowledge"] == "child_measured"  # a summary's delta-V is measured by default
    assert "pediatric" in t["recommendation"]
    stored = stored_case(api, answer["case_id"])
    assert stored["notification"]["occupants"][0]["child_restraint"] == "forward_facing_seat"


def test_a_child_in_a_front_seat_gets_no_adult_dummy_explanation(api: ApiClient) -> None:
    answer = post_case(
        api, _child_in_seat("front_passenger", age_years=8, child_restraint="booster")
    )
    occ = answer["occupants"][0]
    assert occ["method"] == "field"
    assert occ.get("occupant_model") is None
    assert ("child_without_occupant_model", 0) in {
        (a["code"], a.get("occupant")) for a in answer["assumptions"]
    }


def test_a_childs_restraint_that_contradicts_the_belt_is_refused(api: ApiClient) -> None:
    body = _child_in_seat(child_restraint="none", belted=True)
    problem = assert_problem(
        api.client.post("/v1/cases", json=body, headers=api.headers("submitter")), 422
    )
    assert "child_restraint" in str(problem["errors"])


def test_an_adult_of_unknown_age_is_integrated_not_taken_at_the_median(api: ApiClient) -> None:
    body = example("summary")
    occ = body["occupants"][0]
    for key in ("age_years", "sex", "stature_cm", "mass_kg", "body"):
        occ.pop(key, None)
    unknown = post_case(api, body)
    t = unknown["occupants"][0]["triage"]
    assert t["knowledge"] == "age_unknown_measured"
    lo, hi = t["unknown_inputs_range95"]
    assert lo < t["probability"] < hi
    assert t["probability_ci95"][0] <= t["probability"] <= t["probability_ci95"][1]
    codes = {a["code"] for a in unknown["assumptions"]}
    assert "inputs_integrated" in codes
    assert "age_imputed" not in codes
    median = example("summary")
    median["occupants"][0].update(age_years=39, sex="male", stature_cm=175, mass_kg=78)
    median["crash"]["pulse"]["delta_v_source"] = "reconstructed"
    body["crash"]["pulse"]["delta_v_source"] = "reconstructed"
    body["event_id"] = "test-unknown-age-reconstructed"
    unknown_rec = post_case(api, body)["occupants"][0]["triage"]
    at_median = post_case(api, median)["occupants"][0]["triage"]
    assert at_median["knowledge"] == "adult"
    assert unknown_rec["knowledge"] == "age_unknown"
    assert unknown_rec["probability"] != at_median["probability"]


def _nemsis(api: ApiClient, case_id: str) -> etree._Element:
    r = api.client.get(f"/v1/cases/{case_id}/nemsis", params=AGENCY, headers=api.headers("auditor"))
    assert r.status_code == 200, r.text
    assert validate(r.content) == []
    return etree.fromstring(r.content).findall("n:Header/n:PatientCareReport", NS)[0]


def test_the_pediatric_criterion_and_the_child_restraint_reach_ems(api: ApiClient) -> None:
    """eInjury.04 2904029 for a child of 0-9 unrestrained or in an unsecured seat (with the
    guideline's words in the recommendation), eInjury.07 the child restraint's kind."""
    loose = post_case(api, _child_in_seat(age_years=5, child_restraint="none"))
    t = loose["occupants"][0]["triage"]
    assert "unrestrained or in an unsecured child seat" in t["recommendation"]
    pcr = _nemsis(api, loose["case_id"])
    criteria = [e.text for e in pcr.findall("n:eInjury/n:eInjury.04", NS)]
    assert "2904029" in criteria
    assert [e.text for e in pcr.findall("n:eInjury/n:eInjury.07", NS)] == ["2907015"]
    booster = post_case(api, _child_in_seat(age_years=7, child_restraint="booster"))
    assert "unsecured" not in booster["occupants"][0]["triage"]["recommendation"]
    pcr = _nemsis(api, booster["case_id"])
    assert "2904029" not in [e.text for e in pcr.findall("n:eInjury/n:eInjury.04", NS)]
    assert [e.text for e in pcr.findall("n:eInjury/n:eInjury.07", NS)] == ["2907001"]
    unsecured = post_case(
        api,
        _child_in_seat(
            age_years=2, child_restraint="rear_facing_seat", child_restraint_unsecured=True
        ),
    )
    pcr = _nemsis(api, unsecured["case_id"])
    assert "2904029" in [e.text for e in pcr.findall("n:eInjury/n:eInjury.04", NS)]
    assert [e.text for e in pcr.findall("n:eInjury/n:eInjury.07", NS)] == ["2907009"]
