"""VEDS (RFC 8148) notifications: mapped to the JSON notification, triaged alike, hardened.

The documents are in ``tests/service/cases/veds/`` (the two public examples, BSD-2-Clause with
their licence beside them, and documents written for these tests in their shape).
Variants for refusals are made from ``kph-frontal.xml`` by replacing one element.
"""

from __future__ import annotations

import json
import sqlite3
from datetime import UTC, datetime
from decimal import Decimal
from pathlib import Path
from typing import Any

import pytest

from service.cases import service as cases_service
from service.cases.veds import KM_PER_MILE, VEDS_MEDIA_TYPE, clock_to_pdof_deg, delta_v_to_kmh
from service.cases.veds_xml import MAX_DEPTH, MAX_ELEMENTS
from service.db.spool import Spool, SpoolEntry
from tests.support import ApiClient, assert_problem, post_case, stored_case

DOCS = Path(__file__).parent / "veds"
VEDS_31 = "http://www.veds.org/acn/3.1"


def _now() -> datetime:
    return datetime.now(UTC)


def _doc(name: str) -> bytes:
    return (DOCS / name).read_bytes()


def _post_veds(
    api: ApiClient, raw: bytes, role: str = "submitter", media_type: str = VEDS_MEDIA_TYPE
) -> Any:
    return api.client.post(
        "/v1/cases",
        content=raw,
        headers={**api.headers(role), "Content-Type": media_type},
    )


def _case_count(api: ApiClient) -> int:
    r = api.client.get("/v1/cases", headers=api.headers("auditor"))
    assert r.status_code == 200, r.text
    return len(r.json()["items"])


def _triage_part(result: dict[str, Any]) -> dict[str, Any]:
    """What the engine decided, without ids, times and the VEDS-only assumptions."""
    return {
        "triage": result["triage"],
        "occupants": result["occupants"],
        "pulse": result["pulse"],
        "assumptions": [a for a in result["assumptions"] if not a["code"].startswith("veds_")],
        "models": result["models"],
    }


def _codes(result: dict[str, Any]) -> set[str]:
    return {a["code"] for a in result["assumptions"]}


# ------------------------------------------------------------- the JSON twins

#: The JSON notification each test document means (what a JSON client would send).
JSON_TWINS: dict[str, dict[str, Any]] = {
    "kph-frontal.xml": {
        "occurred_at": "2026-11-23T08:15:30Z",
        "vehicle": {"model_year": 2010},
        "crash": {
            "pulse": {"kind": "summary", "delta_v_kmh": 32.18688, "pdof_deg": 0.0},
            "multiple_impacts": False,
            "rollover": False,
        },
        "occupants": [
            {
                "seat": "driver",
                "belted": True,
                "frontal_airbag": "deployed",
                "side_airbag": "not_deployed",
            },
            {
                "seat": "front_passenger",
                "belted": False,
                "frontal_airbag": "deployed",
                "side_airbag": "not_deployed",
            },
        ],
    },
    "kph-rollover-two-pulses.xml": {
        "occurred_at": "2026-11-23T09:02:11+01:00",
        "vehicle": {"model_year": 2012},
        "crash": {
            # the larger of the two pulses; both count as multiple impacts, two of them
            "pulse": {"kind": "summary", "delta_v_kmh": 48.3, "pdof_deg": 0.0},
            "multiple_impacts": True,
            "impact_count": 2,
            "rollover": True,
            # the most quarter turns of any pulse
            "rollover_quarter_turns": 4,
        },
        "occupants": [
            # the FRONT airbags disagree: not deployed assumed for the front row
            {
                "seat": "driver",
                "belted": True,
                "frontal_airbag": "not_deployed",
                "side_airbag": "deployed",
            },
            {
                "seat": "rear_right",
                "belted": True,
                "frontal_airbag": "absent",
                "side_airbag": "deployed",
            },
        ],
    },
}


@pytest.mark.parametrize("name", sorted(JSON_TWINS))
def test_a_veds_document_is_triaged_as_its_json_twin(api: ApiClient, name: str) -> None:
    r = _post_veds(api, _doc(name))
    assert r.status_code == 201, r.text
    veds = r.json()
    twin = post_case(api, {"event_id": f"json-twin-{name}", **JSON_TWINS[name]})
    assert _triage_part(veds) == _triage_part(twin)
    # the VEDS answer adds what the mapping assumed, in front of the engine's own
    assert "veds_vehicle_class_assumed" in _codes(veds)
    assert "inputs_integrated" in _codes(veds), "VEDS gives no occupant's age"


def test_side_airbags_go_to_the_near_side_driver_as_in_json(api: ApiClient) -> None:
    # kph-frontal.xml hit at 9 o'clock (the left: the driver's near side) with its curtain
    # airbags deployed: the driver's side airbag is deployed, as a JSON client would say
    raw = (
        _doc("kph-frontal.xml")
        .replace(b">12</veds:CrashPulsePrincipal", b">9</veds:CrashPulsePrincipal")
        .replace(b"<veds:AirbagDeployedIndicator>false", b"<veds:AirbagDeployedIndicator>true")
    )
    r = _post_veds(api, raw)
    assert r.status_code == 201, r.text
    twin = JSON_TWINS["kph-frontal.xml"]
    body = {
        **twin,
        "event_id": "json-twin-near-side",
        "crash": {**twin["crash"], "pulse": {**twin["crash"]["pulse"], "pdof_deg": 270.0}},
        "occupants": [{**o, "side_airbag": "deployed"} for o in twin["occupants"]],
    }
    veds, json_answer = r.json(), post_case(api, body)
    assert _triage_part(veds) == _triage_part(json_answer)
    assert [o["impact_mode"] for o in veds["occupants"]] == ["near_side", "far_side"]
    assert "side_airbag_not_reported" not in _codes(veds)


def test_the_mph_document_and_its_kph_twin_give_bit_identical_answers(api: ApiClient) -> None:
    # 20 MPH x 1.609344 = 32.18688 KPH exactly: the conversion is done in decimal
    # arithmetic, so both documents give the same float and the same answer (no tolerance)
    kph = _post_veds(api, _doc("kph-frontal.xml"))
    mph = _post_veds(api, _doc("mph-frontal.xml"))
    assert kph.status_code == mph.status_code == 201, (kph.text, mph.text)
    assert _triage_part(kph.json()) == _triage_part(mph.json())
    assert mph.json()["pulse"]["delta_v_kmh"] == kph.json()["pulse"]["delta_v_kmh"]


def test_unit_conversion_is_exact_and_named() -> None:
    assert Decimal("1.609344") == KM_PER_MILE
    assert delta_v_to_kmh(Decimal("20"), "MPH") == delta_v_to_kmh(Decimal("32.18688"), "KPH")
    assert delta_v_to_kmh(Decimal("-32.2"), "KPH") == 32.2
    assert delta_v_to_kmh(Decimal("100"), "MPH") == 160.9344
    assert [clock_to_pdof_deg(h) for h in (12, 3, 6, 9, 1)] == [0.0, 90.0, 180.0, 270.0, 30.0]


def test_several_pulses_and_quarter_turns_are_multiple_impacts_and_rollover(
    api: ApiClient,
) -> None:
    r = _post_veds(api, _doc("kph-rollover-two-pulses.xml"))
    assert r.status_code == 201, r.text
    result = r.json()
    codes = _codes(result)
    assert {"multiple_impacts_reported", "rollover_reported", "veds_most_severe_pulse"} <= codes
    assert "veds_airbag_ambiguous" in codes, "one FRONT airbag deployed, one not"
    assert result["pulse"]["delta_v_kmh"] == pytest.approx(48.3)
    assert {o["field_mode"] for o in result["occupants"]} == {"rollover"}
    # two pulses are two impacts the vehicle counted: no count is imputed
    assert "impact_count_imputed" not in codes
    stored = stored_case(api, result["case_id"])
    assert stored["notification"]["crash"]["impact_count"] == 2


def test_the_rfc8148_example_is_triaged_stored_with_its_xml_and_replayed(api: ApiClient) -> None:
    raw = _doc("veds-rfc8148-example.xml")
    r = _post_veds(api, raw)
    assert r.status_code == 201, r.text
    result = r.json()
    # no incident id: the document's SHA-256 is the event id; no time: the receive time
    assert result["event_id"].startswith("veds-sha256:")
    assert {"veds_crash_time_assumed", "rollover_reported"} <= _codes(result)
    assert result["pulse"]["delta_v_kmh"] == pytest.approx(160.9344)
    stored = stored_case(api, result["case_id"])
    assert stored["source_format"] == "veds"
    assert stored["source_document"] == raw.decode("utf-8")
    mapping = stored["source_mapping"]
    assert mapping["veds_version"] == "3.1"
    assert mapping["vehicle"]["make"] == "Saab"
    assert mapping["vehicle"]["model_year"] == "2015"
    fields = {m["field"]: m for m in mapping["mapped"]}
    assert fields["crash.pulse.delta_v_kmh"]["note"].startswith("100 MPH")
    assert fields["crash.pulse.delta_v_kmh"]["element"].endswith(
        "veds:VehicleCrashPulse[1]/veds:CrashPulseChangeInVelocityMeasure/nc:MeasurePointValue"
    )
    assert {a["code"] for a in mapping["assumed"]} >= {"veds_crash_time_assumed"}
    assert {"field": "occupants[].age_years", "code": "age_imputed"} in mapping["not_in_veds"]
    assert stored["notification"]["crash"]["pulse"]["delta_v_kmh"] == pytest.approx(160.9344)
    # the same document again replays, though its crash time was the receive time
    again = _post_veds(api, raw)
    assert again.status_code == 200, again.text
    assert again.headers["Idempotent-Replayed"] == "true"
    assert again.json()["case_id"] == result["case_id"]


def test_the_veds_31_example_is_answered_for_all_its_occupants(api: ApiClient) -> None:
    """The public VEDS 3.1 example seats one occupant in the front middle (code 9) and one
    in the front passenger seat: both get the field risk model's decision on ISS 15+, their
    region risks, and the case the vehicle's P(anyone ISS 15+); the front middle occupant
    has no occupant model, and the answer says so. Its 3 quarter turns and model year 2018
    reach the field risk models."""
    r = _post_veds(api, _doc("veds-3.1-example.xml"))
    assert r.status_code == 201, r.text
    result = r.json()
    seats = [o["seat"] for o in result["occupants"]]
    assert seats == ["front_middle", "front_passenger"]
    for o in result["occupants"]:
        assert o["triage"]["outcome"] == "ISS15+"
        assert o["triage"]["model"].startswith("field_iss15@")
        assert set(o["region_risk"]) == {
            "head",
            "face",
            "neck",
            "thorax",
            "abdomen",
            "spine",
            "upper_extremity",
            "lower_extremity",
        }
    middle = result["occupants"][0]
    assert middle["method"] == "field"
    assert middle["occupant_model"] is None
    codes = {(a["code"], a["occupant"]) for a in result["assumptions"]}
    assert ("seat_without_occupant_model", 0) in codes
    assert result["vehicle"]["outcome"] == "anyone ISS15+"
    assert 0.0 < result["vehicle"]["probability"] < 1.0
    stored = stored_case(api, result["case_id"])
    assert stored["notification"]["crash"]["rollover_quarter_turns"] == 3
    assert stored["notification"]["vehicle"]["model_year"] == 2018
    assert not any(a["code"] == "quarter_turns_imputed" for a in result["assumptions"])
    assert not any(a["code"] == "model_year_imputed" for a in result["assumptions"])


def test_a_third_row_occupant_is_answered_by_the_field_risk_model(api: ApiClient) -> None:
    raw = _doc("kph-frontal.xml").replace(
        b">2</veds:VehicleSeatLocationCategoryCode>",
        b">7</veds:VehicleSeatLocationCategoryCode>",
        1,
    )
    r = _post_veds(api, raw)
    assert r.status_code == 201, r.text
    result = r.json()
    third = [o for o in result["occupants"] if o["seat"] == "third_row_middle"]
    assert len(third) == 1
    assert third[0]["triage"]["outcome"] == "ISS15+"
    assert third[0]["region_risk"]["head"]["ais_level"] == 3


def test_json_cases_say_they_came_in_as_json(api: ApiClient) -> None:
    body = {"event_id": "plain-json", **JSON_TWINS["kph-frontal.xml"]}
    stored = stored_case(api, post_case(api, body)["case_id"])
    assert stored["source_format"] == "json"
    assert stored["source_document"] is None
    assert stored["source_mapping"] is None


# ------------------------------------------------------------------ idempotency


def test_the_incident_id_is_the_event_id_per_client(api: ApiClient) -> None:
    raw = _doc("kph-frontal.xml")
    first = _post_veds(api, raw)
    assert first.status_code == 201, first.text
    assert first.json()["event_id"] == "TSP-KPH-0001"
    # the same document (re-indented: the same meaning) replays
    replay = _post_veds(api, raw.replace(b"\t", b"  "))
    assert replay.status_code == 200, replay.text
    assert replay.json()["case_id"] == first.json()["case_id"]
    # another document under the same incident id is a conflict
    other = raw.replace(b">-32.18688<", b">-40.0<")
    assert_problem(_post_veds(api, other), 409)
    # another client may use the same incident id
    assert _post_veds(api, raw, role="submitter2").status_code == 201
    assert _case_count(api) == 2


def test_a_json_body_of_the_same_meaning_replays_the_veds_case(api: ApiClient) -> None:
    first = _post_veds(api, _doc("kph-frontal.xml"))
    assert first.status_code == 201, first.text
    body = {"event_id": "TSP-KPH-0001", **JSON_TWINS["kph-frontal.xml"]}
    r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    assert r.status_code == 200, r.text
    assert r.json()["case_id"] == first.json()["case_id"]


# ---------------------------------------------------------------- refusals (422)

_PULSE = "veds:Crash/veds:CrashVehicle/veds:VehicleCrashPulse[1]"
_MEASURE = f"{_PULSE}/veds:CrashPulseChangeInVelocityMeasure"
_SEAT2 = "veds:Crash/veds:CrashVehicle/veds:VehicleSeat[2]"


@pytest.mark.parametrize(
    ("old", "new", "field", "kind"),
    [
        (b">KPH<", b">FPS<", f"{_MEASURE}/nc:MeasureUnitText", "veds_unit"),
        (
            b"<nc:MeasureUnitText>KPH</nc:MeasureUnitText>",
            b"",
            f"{_MEASURE}/nc:MeasureUnitText",
            "veds_missing",
        ),
        (b">-32.18688<", b"><", f"{_MEASURE}/nc:MeasurePointValue", "veds_missing"),
        (b">-32.18688<", b">fast<", f"{_MEASURE}/nc:MeasurePointValue", "veds_number"),
        (b">-32.18688<", b">NaN<", f"{_MEASURE}/nc:MeasurePointValue", "veds_number"),
        (b">-32.18688<", b">0<", f"{_MEASURE}/nc:MeasurePointValue", "veds_range"),
        (b">-32.18688<", b">250<", f"{_MEASURE}/nc:MeasurePointValue", "veds_range"),
        (
            b"<nc:MeasurePointValue>-32.18688</nc:MeasurePointValue>",
            b"",
            f"{_MEASURE}/nc:MeasurePointValue",
            "veds_missing",
        ),
        (
            b">12</veds:CrashPulsePrincipal",
            b">13</veds:CrashPulsePrincipal",
            f"{_PULSE}/veds:CrashPulsePrincipalDirectionOfForceValue",
            "veds_clock",
        ),
        (
            b">2</veds:VehicleSeatLocationCategoryCode>",
            b">12</veds:VehicleSeatLocationCategoryCode>",
            f"{_SEAT2}/veds:VehicleSeatLocationCategoryCode",
            "veds_seat_code",
        ),
        (
            b">2</veds:VehicleSeatLocationCategoryCode>",
            b">1</veds:VehicleSeatLocationCategoryCode>",
            f"{_SEAT2}/veds:VehicleSeatLocationCategoryCode",
            "veds_seat_repeated",
        ),
        (
            b"<veds:VehicleSeatbeltFastenedIndicator>false",
            b"<veds:VehicleSeatbeltFastenedIndicator>no",
            f"{_SEAT2}/veds:VehicleSeatbeltFastenedIndicator",
            "veds_boolean",
        ),
        (
            b">CURTAIN<",
            b">KNEE<",
            "veds:Crash/veds:CrashVehicle/veds:Airbag[3]/veds:AirbagCategoryCode",
            "veds_airbag_category",
        ),
        (
            b">TSP-KPH-0001<",
            b">TSP KPH 0001<",
            "veds:Crash/nc:ActivityIdentification/nc:IdentificationID",
            "veds_incident_id",
        ),
        (
            b">2026-11-23T08:15:30.0Z<",
            b">2026-11-23T08:15:30<",
            "veds:Crash/nc:ActivityDate/nc:DateTime",
            "value_error",
        ),
        (
            b">2026-11-23T08:15:30.0Z<",
            b">1970-01-01T00:00:00Z<",
            "veds:Crash/nc:ActivityDate/nc:DateTime",
            "value_error",
        ),
    ],
)
def test_a_document_the_notification_cannot_take_is_422_naming_the_element(
    api: ApiClient, old: bytes, new: bytes, field: str, kind: str
) -> None:
    raw = _doc("kph-frontal.xml")
    assert old in raw
    problem = assert_problem(_post_veds(api, raw.replace(old, new, 1)), 422)
    assert [(e["field"], e["type"]) for e in problem["errors"]] == [(field, kind)]
    assert _case_count(api) == 0


@pytest.mark.parametrize("pulse", [1, 2])
def test_quarter_turns_beyond_the_limit_name_their_veds_element(api: ApiClient, pulse: int) -> None:
    raw = _doc("kph-rollover-two-pulses.xml")
    written = (b">0</" if pulse == 1 else b">4</") + b"veds:CrashPulseRolloverQuarterTurnsValue>"
    assert raw.count(written) == 1
    raw = raw.replace(written, b">999</veds:CrashPulseRolloverQuarterTurnsValue>")
    problem = assert_problem(_post_veds(api, raw), 422)
    element = (
        f"veds:Crash/veds:CrashVehicle/veds:VehicleCrashPulse[{pulse}]"
        "/veds:CrashPulseRolloverQuarterTurnsValue"
    )
    assert [e["field"] for e in problem["errors"]] == [element], problem
    assert "40" in problem["errors"][0]["reason"]
    assert _case_count(api) == 0


def test_quarter_turns_follow_the_json_rule_for_the_rollover_indicator(api: ApiClient) -> None:
    """Turns with the indicator left out are a rollover; with it false they are refused."""
    raw = _doc("kph-frontal.xml").replace(
        b">0</veds:CrashPulseRolloverQuarterTurnsValue>",
        b">3</veds:CrashPulseRolloverQuarterTurnsValue>",
    )
    problem = assert_problem(_post_veds(api, raw), 422)
    assert [(e["field"], e["type"]) for e in problem["errors"]] == [
        (f"{_PULSE}/veds:CrashPulseRolloverQuarterTurnsValue", "veds_rollover_contradiction")
    ]
    assert "veds:VehicleRolloverIndicator false" in problem["errors"][0]["reason"]
    assert _case_count(api) == 0
    left_out = raw.replace(
        b"<veds:VehicleRolloverIndicator>false</veds:VehicleRolloverIndicator>", b""
    )
    r = _post_veds(api, left_out)
    assert r.status_code == 201, r.text
    assert "rollover_reported" in _codes(r.json())
    crash = stored_case(api, r.json()["case_id"])["notification"]["crash"]
    assert (crash["rollover"], crash["rollover_quarter_turns"]) == (True, 3)


def test_a_document_without_a_pulse_or_an_occupied_seat_is_422(api: ApiClient) -> None:
    raw = _doc("kph-frontal.xml")
    start, end = raw.index(b"<veds:VehicleCrashPulse>"), raw.index(b"</veds:VehicleCrashPulse>")
    no_pulse = raw[:start] + raw[end + len(b"</veds:VehicleCrashPulse>") :]
    problem = assert_problem(_post_veds(api, no_pulse), 422)
    assert problem["errors"][0]["field"] == "veds:Crash/veds:CrashVehicle/veds:VehicleCrashPulse"
    nobody = raw.replace(
        b"<veds:VehicleSeatOccupiedIndicator>true", b"<veds:VehicleSeatOccupiedIndicator>false"
    )
    problem = assert_problem(_post_veds(api, nobody), 422)
    assert problem["errors"][0]["field"] == "veds:Crash/veds:CrashVehicle/veds:VehicleSeat"
    assert _case_count(api) == 0


def test_a_belt_not_reported_is_unknown_and_said_so(api: ApiClient) -> None:
    raw = _doc("kph-frontal.xml").replace(
        b"<veds:VehicleSeatbeltFastenedIndicator>true</veds:VehicleSeatbeltFastenedIndicator>", b""
    )
    r = _post_veds(api, raw)
    assert r.status_code == 201, r.text
    notes = [a for a in r.json()["assumptions"] if a["code"] == "veds_belt_not_reported"]
    assert [a["occupant"] for a in notes] == [0]
    stored = stored_case(api, r.json()["case_id"])
    assert "belted" not in stored["notification"]["occupants"][0]  # unknown, not unbelted
    assert "belt_unknown" in {a["code"] for a in r.json()["assumptions"]}


# ------------------------------------------------------------ hostile XML (4xx)

_ROOT_OPEN = f'<veds:AutomatedCrashNotification xmlns:veds="{VEDS_31}">'.encode()
_ROOT_CLOSE = b"</veds:AutomatedCrashNotification>"

XXE = (
    b'<?xml version="1.0"?>\n<!DOCTYPE veds:AutomatedCrashNotification '
    b'[<!ENTITY xxe SYSTEM "file:///etc/passwd">]>\n'
    + _ROOT_OPEN
    + b"<veds:Crash>&xxe;</veds:Crash>"
    + _ROOT_CLOSE
)
LAUGHS = (
    b'<?xml version="1.0"?>\n<!DOCTYPE lolz [<!ENTITY lol "lol">'
    + b"".join(
        f'<!ENTITY lol{i} "{("&lol" + (str(i - 1) if i > 1 else "") + ";") * 10}">'.encode()
        for i in range(1, 10)
    )
    + b"]>\n"
    + _ROOT_OPEN
    + b"<veds:Crash>&lol9;</veds:Crash>"
    + _ROOT_CLOSE
)
PARAMETER_ENTITY = (
    b'<?xml version="1.0"?>\n<!DOCTYPE x [<!ENTITY % remote SYSTEM "http://127.0.0.1:9/x.dtd">'
    b"%remote;]>\n" + _ROOT_OPEN + _ROOT_CLOSE
)
DEEP = _ROOT_OPEN + b"<veds:Crash>" * 100 + b"</veds:Crash>" * 100 + _ROOT_CLOSE


@pytest.mark.parametrize(
    ("raw", "kind"),
    [
        (XXE, "xml_dtd_forbidden"),
        (LAUGHS, "xml_dtd_forbidden"),
        (PARAMETER_ENTITY, "xml_dtd_forbidden"),
        (DEEP, "xml_too_deep"),
        (_ROOT_OPEN + b"<veds:Crash/>" * (MAX_ELEMENTS + 1) + _ROOT_CLOSE, "xml_too_many_elements"),
        (b"<veds:AutomatedCrashNotification", "xml_malformed"),
        (b"", "xml_empty"),
        (_ROOT_OPEN + _ROOT_CLOSE + _ROOT_OPEN + _ROOT_CLOSE, "xml_malformed"),
        ("<?xml version='1.0' encoding='UTF-16'?><a/>".encode("utf-16"), "xml_encoding"),
        (b"<?xml version='1.0' encoding='ISO-8859-1'?><a>\xe9</a>", "xml_encoding"),
    ],
    ids=[
        "external-entity",
        "entity-expansion",
        "parameter-entity",
        "100-levels",
        "too-many-elements",
        "not-well-formed",
        "empty",
        "two-roots",
        "utf-16",
        "latin-1",
    ],
)
def test_hostile_or_malformed_xml_is_400_and_nothing_is_stored(
    api: ApiClient, raw: bytes, kind: str
) -> None:
    problem = assert_problem(_post_veds(api, raw), 400)
    assert problem["type"].endswith("/malformed-xml")
    assert [e["type"] for e in problem["errors"]] == [kind]
    assert "root:" not in json.dumps(problem), "no file content leaks into the answer"
    assert _case_count(api) == 0


def test_too_deep_names_where_it_got_too_deep(api: ApiClient) -> None:
    problem = assert_problem(_post_veds(api, DEEP), 400)
    field = problem["errors"][0]["field"]
    assert field.startswith("veds:Crash/veds:Crash/")
    assert field.count("veds:Crash") == MAX_DEPTH


def test_a_10_mb_document_is_413_before_it_is_read(api: ApiClient) -> None:
    padding = b"<!-- " + b"x" * (10 * 1024 * 1024) + b" -->"
    raw = _doc("kph-frontal.xml").replace(b"<veds:Crash ", padding + b"<veds:Crash ", 1)
    assert_problem(_post_veds(api, raw), 413)
    assert _case_count(api) == 0


@pytest.mark.parametrize(
    ("raw", "root"),
    [
        (
            _doc("kph-frontal.xml").replace(VEDS_31.encode(), b"http://www.veds.org/acn/9.9"),
            "{http://www.veds.org/acn/9.9}AutomatedCrashNotification",
        ),
        (b"<AutomatedCrashNotification/>", "AutomatedCrashNotification"),
        (
            _ROOT_OPEN.replace(b"AutomatedCrash", b"Other") + b"</veds:OtherNotification>",
            "veds:OtherNotification",
        ),
    ],
    ids=["unknown-namespace", "no-namespace", "other-root"],
)
def test_a_document_that_is_not_veds_is_422_naming_its_root(
    api: ApiClient, raw: bytes, root: str
) -> None:
    problem = assert_problem(_post_veds(api, raw), 422)
    assert [(e["field"], e["type"]) for e in problem["errors"]] == [(root, "veds_root")]
    assert _case_count(api) == 0


def test_the_veds_10_namespace_is_read_too(api: ApiClient) -> None:
    raw = _doc("kph-frontal.xml").replace(VEDS_31.encode(), b"http://www.veds.org/acn/1.0")
    r = _post_veds(api, raw)
    assert r.status_code == 201, r.text
    assert stored_case(api, r.json()["case_id"])["source_mapping"]["veds_version"] == "1.0"


@pytest.mark.parametrize("media_type", ["application/xml", "text/xml", "text/plain"])
def test_veds_under_another_media_type_is_415(api: ApiClient, media_type: str) -> None:
    problem = assert_problem(_post_veds(api, _doc("kph-frontal.xml"), media_type=media_type), 415)
    assert VEDS_MEDIA_TYPE in problem["detail"]
    assert _case_count(api) == 0


def test_veds_sent_as_json_is_400_and_json_sent_as_veds_is_400(api: ApiClient) -> None:
    assert_problem(_post_veds(api, _doc("kph-frontal.xml"), media_type="application/json"), 400)
    body = json.dumps({"event_id": "x", **JSON_TWINS["kph-frontal.xml"]}).encode()
    assert_problem(_post_veds(api, body), 400)
    assert _case_count(api) == 0


def test_the_media_type_is_matched_without_case_or_parameters(api: ApiClient) -> None:
    media = "application/emergencycalldata.veds+XML; charset=utf-8"
    assert _post_veds(api, _doc("kph-frontal.xml"), media_type=media).status_code == 201


def test_a_submitter_key_is_checked_before_the_xml_is_read(api: ApiClient) -> None:
    r = api.client.post("/v1/cases", content=XXE, headers={"Content-Type": VEDS_MEDIA_TYPE})
    assert_problem(r, 401)
    assert_problem(_post_veds(api, XXE, role="auditor"), 403)


# ------------------------------------------------------------ documents, storage


def test_the_openapi_document_shows_the_xml_request_body(api: ApiClient) -> None:
    doc = api.client.get("/openapi.json").json()
    content = doc["paths"]["/v1/cases"]["post"]["requestBody"]["content"]
    assert set(content) == {"application/json", VEDS_MEDIA_TYPE}
    xml = content[VEDS_MEDIA_TYPE]
    assert xml["schema"]["type"] == "string"
    assert "AutomatedCrashNotification" in json.dumps(xml["examples"])
    stored = doc["components"]["schemas"]["StoredCase"]["properties"]
    assert {"source_format", "source_document", "source_mapping"} <= set(stored)


def test_the_case_page_says_the_case_came_in_as_veds(api: ApiClient) -> None:
    veds_id = _post_veds(api, _doc("kph-frontal.xml")).json()["case_id"]
    json_id = post_case(api, {"event_id": "page-json", **JSON_TWINS["kph-frontal.xml"]})["case_id"]
    page = api.client.get(f"/v1/cases/{veds_id}/report", headers=api.headers("auditor"))
    assert page.status_code == 200, page.text
    assert 'data-source-format="veds"' in page.text
    assert "VEDS 3.1" in page.text
    assert "Toyota Yaris 2010" in page.text
    plain = api.client.get(f"/v1/cases/{json_id}/report", headers=api.headers("auditor"))
    assert 'data-source-format="json"' in plain.text


@pytest.mark.postgres
def test_a_veds_case_round_trips_through_postgresql(api_any_db: ApiClient) -> None:
    api = api_any_db
    raw = _doc("kph-rollover-two-pulses.xml")
    r = _post_veds(api, raw)
    assert r.status_code == 201, r.text
    stored = stored_case(api, r.json()["case_id"])
    assert stored["source_format"] == "veds"
    assert stored["source_document"] == raw.decode("utf-8")
    assert stored["source_mapping"]["vehicle"]["make"] == "Ford"
    assert stored["result"] == {**r.json(), "stored": True, "spooled": False}


def test_a_spooled_veds_case_is_stored_with_its_document(api: ApiClient) -> None:
    """The spool keeps the source: the replayer stores the XML and the mapping too."""
    ctx = api.client.app.state.ctx  # type: ignore[attr-defined]
    first = _post_veds(api, _doc("kph-frontal.xml"))
    stored = stored_case(api, first.json()["case_id"])
    spool = Spool(Path(api.settings.resolved_spool_path()).with_name("other-spool.db"))
    entry = SpoolEntry(
        seq=None,
        client_name="submitter-client",
        event_id="spooled-veds",
        request_sha256=stored["request_sha256"],
        case_id="00000000-0000-4000-8000-000000000001",
        received_at=_now(),
        spooled_at=_now(),
        notification=stored["notification"],
        result={**stored["result"], "case_id": "00000000-0000-4000-8000-000000000001"},
        source={
            "format": "veds",
            "document": stored["source_document"],
            "mapping": stored["source_mapping"],
        },
    )
    assert spool.put(entry) is entry
    (waiting,) = spool.oldest(10)
    assert waiting.source == entry.source
    cases_service.store_spooled(ctx, waiting)
    again = stored_case(api, "00000000-0000-4000-8000-000000000001")
    assert again["source_format"] == "veds"
    assert again["source_document"] == stored["source_document"]
    assert again["source_mapping"] == stored["source_mapping"]


def test_a_spool_file_from_before_veds_gains_its_source_column(tmp_path: Path) -> None:
    path = tmp_path / "old-spool.db"
    with sqlite3.connect(path) as conn:
        conn.execute(
            "CREATE TABLE spool (seq INTEGER PRIMARY KEY AUTOINCREMENT, client_name TEXT NOT "
            "NULL, event_id TEXT NOT NULL, request_sha256 TEXT NOT NULL, case_id TEXT NOT NULL,"
            " received_at TEXT NOT NULL, spooled_at TEXT NOT NULL, notification TEXT NOT NULL,"
            " result TEXT NOT NULL, UNIQUE (client_name, event_id))"
        )
        conn.execute(
            "INSERT INTO spool (client_name, event_id, request_sha256, case_id, received_at, "
            "spooled_at, notification, result) VALUES ('c', 'e', 'h', 'id', ?, ?, '{}', '{}')",
            (_now().isoformat(), _now().isoformat()),
        )
    conn.close()
    (old,) = Spool(path).oldest(10)
    assert old.event_id == "e"
    assert old.source is None
