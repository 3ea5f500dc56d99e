"""NEMSIS v3.5.1 records of stored cases: valid, faithful, guarded.

Every record is checked against the shipped XSDs with the service's own validator,
which is shown to be real on NEMSIS's motor-vehicle-crash test case (it passes) and
on broken copies of it (they fail, naming the element). The expected codes are
written out here from the NEMSIS code lists, not taken from the mapping's tables.
"""

from __future__ import annotations

import copy
import hashlib
import json
import re
from datetime import datetime
from pathlib import Path
from typing import Any

import pytest
from lxml import etree

from models.notification import Seat
from service.auth import Role
from service.browser_session import SESSION_COOKIE
from service.cases.result import StoredCase
from service.cases.veds import VEDS_MEDIA_TYPE, clock_to_pdof_deg
from service.cli import main as cli
from service.nemsis import codes
from service.nemsis.mapping import Agency, pdof_clock_hour
from service.nemsis.service import NemsisRecordInvalid, agency_from, checked_record
from service.nemsis.validate import XSD_DIR, validate
from service.settings import Settings, get_settings
from tests.paths import VEDS_DOCS
from tests.service.pages_support import Page, csrf_token
from tests.support import ApiClient, assert_problem, example, post_case, stored_case, summary

HERE = Path(__file__).parent
MVC_CASE = HERE / "2025-EMS-3-MVC_v351.xml"
VEDS_DIR = VEDS_DOCS
NS = {"n": "http://www.nemsis.org"}
XSI_NIL = "{http://www.w3.org/2001/XMLSchema-instance}nil"
AGENCY = {"agency_state_id": "C034", "agency_number": "351-C034P2", "agency_state": "09"}


# ----------------------------------------------------------------- helpers


def _get(api: ApiClient, case_id: str, role: str = "auditor", **params: str) -> Any:
    return api.client.get(
        f"/v1/cases/{case_id}/nemsis", params={**AGENCY, **params}, headers=api.headers(role)
    )


def _record(api: ApiClient, case_id: str, role: str = "auditor") -> tuple[Any, etree._Element]:
    r = _get(api, case_id, role)
    assert r.status_code == 200, r.text
    assert r.headers["content-type"].startswith("application/xml")
    assert validate(r.content) == []
    return r, etree.fromstring(r.content)


def _text(element: etree._Element, path: str) -> str | None:
    found = element.find(path, NS)
    return None if found is None else found.text


def _texts(element: etree._Element, path: str) -> list[str | None]:
    return [e.text for e in element.findall(path, NS)]


def _not_recorded(element: etree._Element, path: str) -> bool:
    found = element.find(path, NS)
    return found is not None and found.get(XSI_NIL) == "true" and found.get("NV") == "7701003"


def _reports(tree: etree._Element) -> list[etree._Element]:
    return tree.findall("n:Header/n:PatientCareReport", NS)


def _post_veds(api: ApiClient, raw: bytes) -> dict[str, Any]:
    r = api.client.post(
        "/v1/cases",
        content=raw,
        headers={**api.headers("submitter"), "Content-Type": VEDS_MEDIA_TYPE},
    )
    assert r.status_code == 201, r.text
    result: dict[str, Any] = r.json()
    return result


# ------------------------------------------------------------- the validator


def test_nemsis_motor_vehicle_crash_test_case_passes_the_same_validator() -> None:
    assert validate(MVC_CASE.read_bytes()) == []


@pytest.mark.parametrize(
    ("old", "new", "element"),
    [
        (b"<eInjury.24>11</eInjury.24>", b"<eInjury.24>13</eInjury.24>", "eInjury.24"),
        (
            b'<eInjury.22 VelocityUnit="9921003"',
            b'<eInjury.22 VelocityUnit="9921002"',
            "eInjury.22",
        ),
        (b"<eInjury.26>2926005</eInjury.26>", b"<eInjury.26>2926006</eInjury.26>", "eInjury.26"),
        (b"<eTimes.03>2024-10-11T16:45:18-04:00</eTimes.03>", b"", "eTimes"),
        (b"<eTimes.13>2024-10-11T17:38:48-04:00", b"<eTimes.13>2024-10-11T17:38:48Z", "eTimes.13"),
    ],
    ids=["pdof-13", "unknown-velocity-unit", "unknown-seat", "mandatory-missing", "time-with-z"],
)
def test_the_validator_refuses_broken_copies_naming_the_element(
    old: bytes, new: bytes, element: str
) -> None:
    broken = MVC_CASE.read_bytes().replace(old, new)
    assert broken != MVC_CASE.read_bytes()
    errors = validate(broken)
    assert errors, "a broken document must fail"
    assert errors[0].element.split("/")[-1].startswith(element), errors


def test_the_shipped_schemas_are_the_copied_release() -> None:
    provenance = (XSD_DIR / "PROVENANCE.md").read_text(encoding="utf-8")
    listed = {
        name: digest
        for digest, name in re.findall(r"^([0-9a-f]{64})  (\S+\.xsd)$", provenance, re.M)
    }
    shipped = {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in XSD_DIR.glob("*.xsd")}
    assert shipped == listed
    assert "EMSDataSet_v3.xsd" in shipped


def _enumeration(type_name: str) -> set[str]:
    for path in XSD_DIR.glob("*.xsd"):
        tree = etree.parse(str(path))
        xs = {"xs": "http://www.w3.org/2001/XMLSchema"}
        found = tree.find(f".//xs:simpleType[@name='{type_name}']", xs)
        if found is not None:
            return {e.get("value") or "" for e in found.iterfind(".//xs:enumeration", xs)}
    raise LookupError(type_name)


def test_every_code_used_is_in_the_nemsis_code_list() -> None:
    assert set(codes.SEAT_LOCATION.values()) == _enumeration("SeatLocation")
    assert set(codes.VEDS_SEAT_LOCATION.values()) == _enumeration("SeatLocation")
    assert set(codes.SEAT_ROW_LOCATION.values()) <= _enumeration("SeatRowLocation")
    assert set(codes.AIRBAG_DEPLOYMENT.values()) <= _enumeration("AirbagDeployment")
    assert set(codes.YES_NO.values()) == _enumeration("YesNoValues")
    assert set(codes.ACN_YES_NO.values()) == _enumeration("ACNYesNoType")
    assert codes.VELOCITY_UNIT_KMH in _enumeration("VelocityUnits")
    assert codes.TRIAGE_TELEMETRY_SEVERE in _enumeration("TraumaTriageCriteriaSteps3and4")
    assert codes.COMPLAINT_TRAFFIC_INCIDENT in _enumeration("DispatchReason")
    assert set(codes.SEX.values()) <= _enumeration("Sex")
    assert {codes.AGE_UNIT_YEARS, codes.AGE_UNIT_MONTHS} <= _enumeration("AgeUnits")
    assert codes.NOT_RECORDED in _enumeration("NV.NotRecorded")


def test_every_seat_of_the_contract_has_a_nemsis_seat() -> None:
    # a seat added to the wire contract (front middle, ...) must be mapped here
    assert {s.value for s in Seat} <= set(codes.SEAT_LOCATION)
    assert {s.value for s in Seat} <= set(codes.SEAT_ROW_LOCATION)


@pytest.mark.parametrize("hour", range(1, 13))
def test_the_pdof_clock_hour_inverts_the_veds_reading(hour: int) -> None:
    assert pdof_clock_hour(clock_to_pdof_deg(hour)) == hour
    assert pdof_clock_hour(clock_to_pdof_deg(hour) + 14.9) == hour
    assert pdof_clock_hour(clock_to_pdof_deg(hour) - 14.9) == hour


def test_the_documented_stored_case_has_a_valid_record_without_a_server() -> None:
    from service.cases.examples import EXAMPLE_STORED_CASE
    from service.cases.notification import EXAMPLE_NOTIFICATIONS

    # the example's notification is abridged: the documented one of the same event
    doc = {**EXAMPLE_STORED_CASE, "notification": EXAMPLE_NOTIFICATIONS["summary"]["value"]}
    record = checked_record(StoredCase.model_validate(doc), Agency("C034", "351-C034P2", "09"))
    assert validate(record.document) == []
    assert (
        record.document
        == checked_record(
            StoredCase.model_validate(copy.deepcopy(doc)), Agency("C034", "351-C034P2", "09")
        ).document
    )


# ------------------------------------------------------------- JSON cases


def _several() -> dict[str, Any]:
    """Three occupants, airbags differing by seat (one not reported: left out)."""
    body = example("summary")
    base = body["occupants"][0]
    body["crash"]["pulse"] = {"kind": "summary", "delta_v_kmh": 47.6, "pdof_deg": 80.0}
    body["occupants"] = [
        {
            **base,
            "seat": "driver",
            "belted": True,
            "frontal_airbag": "deployed",
            "side_airbag": "not_deployed",
        },  # fmt: skip
        {
            **base,
            "seat": "front_passenger",
            "belted": False,
            "frontal_airbag": "not_deployed",
            "side_airbag": "deployed",
            "age_years": 71.5,
            "sex": "female",
        },  # fmt: skip
        {**base, "seat": "rear_left", "belted": True, "frontal_airbag": "absent"},
    ]
    for unknown in ("age_years", "sex"):  # not reported for the rear passenger
        body["occupants"][2].pop(unknown, None)
    return body


def _rollover() -> dict[str, Any]:
    body = summary(38.0, 345.0)
    body["crash"].update(rollover=True, multiple_impacts=True)
    return body


def _unbelted_minor() -> dict[str, Any]:
    body = summary(9.0, 0.0, belted=False, airbag="not_deployed")
    body["occupants"][0]["side_airbag"] = "not_deployed"
    return body


def _right_hand_drive() -> dict[str, Any]:
    body = summary(61.0, 270.0)
    body["vehicle"]["drive_side"] = "right"
    body["occupants"].append({**body["occupants"][0], "seat": "front_passenger"})
    return body


def _edr() -> dict[str, Any]:
    return example("delta_v")


#: How the narrative (eNarrative.01) names each tier.
TIER_NARRATIVE = {
    "high": "HIGH RISK",
    "moderate": "MODERATE RISK",
    "none": "NO TELEMETRY INDICATION",
}

JSON_CASES = {
    "one-occupant": lambda: summary(56.0, 0.0),
    "several-occupants-airbags-by-seat": _several,
    "rollover": _rollover,
    "unbelted-not-for-trauma-center": _unbelted_minor,
    "right-hand-drive": _right_hand_drive,
    "edr-pulse": _edr,
}


def _check_against_stored(tree: etree._Element, stored: dict[str, Any]) -> None:
    """What every record must say of its case, occupant by occupant."""
    result = stored["result"]
    occupants = stored["notification"]["occupants"]
    reports = _reports(tree)
    assert len(reports) == len(occupants) == len(result["occupants"])
    assert len({r.get("UUID") for r in reports}) == len(reports)
    for i, (pcr, decided) in enumerate(zip(reports, result["occupants"], strict=True)):
        assert _text(pcr, "n:eRecord/n:eRecord.01") == f"{stored['case_id']}-{i + 1}"
        group = pcr.find("n:eInjury/n:eInjury.CollisionGroup", NS)
        assert group is not None
        (delta_v,) = group.findall("n:eInjury.22", NS)
        assert delta_v.get("VelocityUnit") == "9921001"  # km/h
        assert abs(int(delta_v.text or "") - result["pulse"]["delta_v_kmh"]) <= 0.5
        hour = int(_text(group, "n:eInjury.24") or "")
        off = (hour % 12) * 30.0 - result["pulse"]["pdof_deg"]
        assert abs((off + 180.0) % 360.0 - 180.0) <= 15.0
        flagged, tier = decided["triage"]["iss15_plus"], decided["triage"]["tier"]
        assert flagged == (tier in ("high", "moderate"))
        assert _text(group, "n:eInjury.23") == ("9923003" if tier == "high" else "9923001")
        if flagged:
            assert _texts(pcr, "n:eInjury/n:eInjury.04") == ["2904013"]
        else:
            assert _not_recorded(pcr, "n:eInjury/n:eInjury.04")
        narrative = _text(pcr, "n:eNarrative/n:eNarrative.01") or ""
        assert TIER_NARRATIVE[tier] in narrative
        assert decided["triage"]["recommendation"] in narrative
        assert _text(group, "n:eInjury.12") == stored["event_id"]
        at = datetime.fromisoformat(_text(group, "n:eInjury.14") or "")
        assert at == datetime.fromisoformat(stored["notification"]["occurred_at"])
        seats = group.findall("n:eInjury.SeatGroup", NS)
        assert len(seats) == len(occupants)
        expected_seat = {
            "driver": "2926001",
            "front_passenger": "2926005",
            "rear_left": "2926007",
            "rear_middle": "2926009",
            "rear_right": "2926011",
        }
        for seat, occupant in zip(seats, occupants, strict=True):
            assert _text(seat, "n:eInjury.26") == expected_seat[occupant["seat"]]
            assert _text(seat, "n:eInjury.27") == "Y"
            assert _text(seat, "n:eInjury.28") == ("Y" if occupant["belted"] else "N")


@pytest.mark.parametrize("make", JSON_CASES.values(), ids=JSON_CASES.keys())
def test_the_record_of_a_json_case_is_valid_and_says_what_the_case_says(
    api: ApiClient, make: Any
) -> None:
    case_id = post_case(api, make())["case_id"]
    stored = stored_case(api, case_id)
    _, tree = _record(api, case_id)
    _check_against_stored(tree, stored)


def test_airbags_belts_and_seats_by_occupant(api: ApiClient) -> None:
    case_id = post_case(api, _several())["case_id"]
    r, tree = _record(api, case_id)
    driver, passenger, rear = _reports(tree)
    seats = driver.findall("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.SeatGroup", NS)
    # deployed frontal / side deployed / frontal absent, side not reported: left out
    assert [_text(s, "n:eInjury.29") for s in seats] == ["Y", "Y", None]
    assert [_text(s, "n:eInjury.28") for s in seats] == ["Y", "N", "Y"]
    assert _texts(driver, "n:eInjury/n:eInjury.08") == ["2908001"]  # front
    assert _texts(passenger, "n:eInjury/n:eInjury.08") == ["2908003"]  # side
    assert _texts(rear, "n:eInjury/n:eInjury.08") == []
    assert [_text(p, "n:eInjury/n:eInjury.06") for p in (driver, passenger, rear)] == [
        "2906001",  # front seat, left side (left-hand drive)
        "2906005",
        "2906013",  # second seat, left side
    ]
    # the passenger's age (completed years) and sex; the rear passenger's not recorded
    assert _text(passenger, "n:ePatient/n:ePatient.AgeGroup/n:ePatient.15") == "71"
    assert _text(passenger, "n:ePatient/n:ePatient.AgeGroup/n:ePatient.16") == "2516009"
    assert _text(passenger, "n:ePatient/n:ePatient.25") == "9919001"
    assert _not_recorded(rear, "n:ePatient/n:ePatient.AgeGroup/n:ePatient.15")
    assert _not_recorded(rear, "n:ePatient/n:ePatient.25")
    left_out = {s.strip() for s in r.headers["NEMSIS-Left-Out"].split(",")}
    assert {"eInjury.29", "eInjury.08", "eInjury.11"} <= left_out
    assert "eInjury.28" not in left_out
    comment = rear.xpath("comment()")[0].text
    assert "eInjury.08 (the airbags at this seat are not all reported)" in comment


def test_rollover_multiple_impacts_and_the_decision(api: ApiClient) -> None:
    case_id = post_case(api, _rollover())["case_id"]
    _, tree = _record(api, case_id)
    (pcr,) = _reports(tree)
    group = pcr.find("n:eInjury/n:eInjury.CollisionGroup", NS)
    assert _text(group, "n:eInjury.25") == "Y"
    assert _text(group, "n:eInjury.21") == "9923003"
    assert _text(group, "n:eInjury.24") == "12"  # 345 deg: nearer 12 than 11


def test_quarter_turns_alone_say_there_was_a_rollover(api: ApiClient) -> None:
    body = summary(40.0, 0.0)
    del body["crash"]["rollover"]
    body["crash"]["rollover_quarter_turns"] = 2
    r, tree = _record(api, post_case(api, body)["case_id"])
    (pcr,) = _reports(tree)
    assert _text(pcr, "n:eInjury/n:eInjury.CollisionGroup/n:eInjury.25") == "Y"
    assert "eInjury.25" not in r.headers["NEMSIS-Left-Out"]


def test_an_impact_count_alone_says_whether_there_were_multiple_impacts(api: ApiClient) -> None:
    for count, code in ((3, "9923003"), (1, "9923001")):
        body = summary(40.0, 0.0)
        del body["crash"]["multiple_impacts"]
        body["crash"]["impact_count"] = count
        _, tree = _record(api, post_case(api, body)["case_id"])
        (pcr,) = _reports(tree)
        group = pcr.find("n:eInjury/n:eInjury.CollisionGroup", NS)
        assert _text(group, "n:eInjury.21") == code, count


def test_a_case_not_for_the_trauma_center_says_no(api: ApiClient) -> None:
    result = post_case(api, _unbelted_minor())
    assert result["triage"]["iss15_plus"] is False, "precondition: a minor crash"
    _, tree = _record(api, result["case_id"])
    (pcr,) = _reports(tree)
    assert _text(pcr, "n:eInjury/n:eInjury.CollisionGroup/n:eInjury.23") == "9923001"
    assert _not_recorded(pcr, "n:eInjury/n:eInjury.04")
    assert _texts(pcr, "n:eInjury/n:eInjury.08") == ["2908007"]  # none deployed


def test_facts_the_sender_left_out_are_left_out(api: ApiClient) -> None:
    body = summary(56.0, 0.0)
    del body["vehicle"]  # drive side not said
    del body["crash"]["rollover"]
    del body["crash"]["multiple_impacts"]
    case_id = post_case(api, body)["case_id"]
    r, tree = _record(api, case_id)
    (pcr,) = _reports(tree)
    group = pcr.find("n:eInjury/n:eInjury.CollisionGroup", NS)
    for element in ("eInjury.21", "eInjury.25"):
        assert group.find(f"n:{element}", NS) is None
    assert pcr.find("n:eInjury/n:eInjury.06", NS) is None  # the driver's side unknown
    assert {"eInjury.06", "eInjury.21", "eInjury.25"} <= set(
        r.headers["NEMSIS-Left-Out"].split(", ")
    )


def test_an_infant_s_age_is_in_months(api: ApiClient) -> None:
    body = summary(30.0, 0.0, seat="rear_right", airbag="absent")
    body["occupants"][0]["age_years"] = 0.75
    _, tree = _record(api, post_case(api, body)["case_id"])
    (pcr,) = _reports(tree)
    assert _text(pcr, "n:ePatient/n:ePatient.AgeGroup/n:ePatient.15") == "9"
    assert _text(pcr, "n:ePatient/n:ePatient.AgeGroup/n:ePatient.16") == "2516007"  # months


def test_right_hand_drive_puts_the_driver_on_the_right(api: ApiClient) -> None:
    case_id = post_case(api, _right_hand_drive())["case_id"]
    _, tree = _record(api, case_id)
    driver, passenger = _reports(tree)
    assert _text(driver, "n:eInjury/n:eInjury.06") == "2906005"
    assert _text(passenger, "n:eInjury/n:eInjury.06") == "2906001"


def test_placeholders_and_not_values(api: ApiClient) -> None:
    case_id = post_case(api, summary())["case_id"]
    r, tree = _record(api, case_id)
    (pcr,) = _reports(tree)
    assert r.headers["NEMSIS-Placeholders"].split(", ") == list(codes.PLACEHOLDERS)
    assert _text(pcr, "n:eResponse/n:eResponse.13") == "UNASSIGNED"
    assert _text(pcr, "n:eDispatch/n:eDispatch.01") == "2301069"  # traffic incident
    assert _text(tree, "n:Header/n:DemographicGroup/n:dAgency.02") == "351-C034P2"
    assert _text(pcr, "n:eResponse/n:eResponse.AgencyGroup/n:eResponse.01") == "351-C034P2"
    # every nil element says Not Recorded
    nils = [e for e in pcr.iter() if e.get(XSI_NIL) == "true"]
    assert nils
    assert all(e.get("NV") == "7701003" for e in nils)
    assert "eArrest.01" in {etree.QName(e).localname for e in nils}


def test_the_same_case_gives_the_same_bytes(api: ApiClient) -> None:
    case_id = post_case(api, _several())["case_id"]
    first, second = _get(api, case_id), _get(api, case_id, role="admin")
    assert first.content == second.content


# ------------------------------------------------------------- VEDS cases


@pytest.mark.parametrize(
    "name",
    [
        "kph-frontal.xml",
        "kph-rollover-two-pulses.xml",
        "mph-frontal.xml",
        "veds-rfc8148-example.xml",
    ],
)
def test_the_record_of_a_veds_case_is_valid_and_says_what_the_case_says(
    api: ApiClient, name: str
) -> None:
    case_id = _post_veds(api, (VEDS_DIR / name).read_bytes())["case_id"]
    stored = stored_case(api, case_id)
    _, tree = _record(api, case_id)
    for pcr, decided in zip(_reports(tree), stored["result"]["occupants"], strict=True):
        group = pcr.find("n:eInjury/n:eInjury.CollisionGroup", NS)
        pulses = group.findall("n:eInjury.22", NS)
        assert {p.get("VelocityUnit") for p in pulses} == {"9921001"}
        assert [p.get("DeltaVelocityOrdinal") for p in pulses] == [
            str(n) for n in range(1, len(pulses) + 1)
        ]
        triaged = stored["result"]["pulse"]["delta_v_kmh"]
        assert any(abs(int(p.text or "") - triaged) <= 0.5 for p in pulses)
        high = decided["triage"]["tier"] == "high"
        assert _text(group, "n:eInjury.23") == ("9923003" if high else "9923001")
        vehicle = stored["source_mapping"]["vehicle"]
        assert _text(group, "n:eInjury.18") == vehicle["make"]
        assert _text(group, "n:eInjury.20") == vehicle["model_year"]


def test_a_veds_rollover_with_assumed_fields_leaves_them_out(api: ApiClient) -> None:
    case_id = _post_veds(api, (VEDS_DIR / "kph-rollover-two-pulses.xml").read_bytes())["case_id"]
    r, tree = _record(api, case_id)
    driver, rear = _reports(tree)
    group = driver.find("n:eInjury/n:eInjury.CollisionGroup", NS)
    assert _text(group, "n:eInjury.25") == "Y"
    assert _text(group, "n:eInjury.21") == "9923003"
    assert (_text(group, "n:eInjury.18"), _text(group, "n:eInjury.19")) == ("Ford", "Focus")
    # both pulses in the document's order, km/h: 25, then 48.3 (the one triaged)
    assert _texts(group, "n:eInjury.22") == ["25", "48"]
    assert [p.get("DeltaVelocityOrdinal") for p in group.findall("n:eInjury.22", NS)] == ["1", "2"]
    # VEDS names no drive side: the driver's side is not known; the rear right seat's is
    assert driver.find("n:eInjury/n:eInjury.06", NS) is None
    assert _text(rear, "n:eInjury/n:eInjury.06") == "2906017"
    # the FRONT airbags disagreed (frontal unknown), the side ones deployed: a deployed
    # airbag at each seat, the front one not claimed
    assert _texts(driver, "n:eInjury/n:eInjury.08") == ["2908003"]
    assert [_text(s, "n:eInjury.29") for s in group.findall("n:eInjury.SeatGroup", NS)] == [
        "Y",
        "Y",
    ]
    assert "eInjury.06" in r.headers["NEMSIS-Left-Out"]


def test_a_veds_seat_reported_empty_has_its_seat_group(api: ApiClient) -> None:
    case_id = _post_veds(api, (VEDS_DIR / "kph-frontal.xml").read_bytes())["case_id"]
    _, tree = _record(api, case_id)
    for pcr in _reports(tree):
        seats = pcr.findall("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.SeatGroup", NS)
        assert [(_text(s, "n:eInjury.26"), _text(s, "n:eInjury.27")) for s in seats] == [
            ("2926001", "Y"),  # driver
            ("2926005", "Y"),  # front passenger
            ("2926007", "N"),  # VEDS seat 3, second row left, reported empty
        ]
        delta_v = _text(pcr, "n:eInjury/n:eInjury.CollisionGroup/n:eInjury.22")
        assert delta_v == "32"  # 32.18688 km/h


def test_a_veds_belt_not_reported_is_not_written_as_unbelted(api: ApiClient) -> None:
    raw = (
        (VEDS_DIR / "kph-frontal.xml")
        .read_bytes()
        .replace(
            b"<veds:VehicleSeatbeltFastenedIndicator>true</veds:VehicleSeatbeltFastenedIndicator>",
            b"",
        )
    )
    result = _post_veds(api, raw)
    assert "belted" not in stored_case(api, result["case_id"])["notification"]["occupants"][0]
    r, tree = _record(api, result["case_id"])
    seats = _reports(tree)[0].findall("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.SeatGroup", NS)
    assert _text(seats[0], "n:eInjury.28") is None  # unknown: integrated over, not written
    assert _text(seats[1], "n:eInjury.28") == "N"
    assert "eInjury.28" in r.headers["NEMSIS-Left-Out"]


def test_a_veds_case_without_a_crash_time_has_none_in_its_record(api: ApiClient) -> None:
    case_id = _post_veds(api, (VEDS_DIR / "veds-rfc8148-example.xml").read_bytes())["case_id"]
    _, tree = _record(api, case_id)
    for pcr in _reports(tree):
        assert pcr.find("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.14", NS) is None
        assert _not_recorded(pcr, "n:eSituation/n:eSituation.01")


_YEAR_ELEMENT = "veds:Crash/veds:CrashVehicle/nc:ItemModelYearDate"


@pytest.mark.parametrize("year", ["٢٠١٠", "２０１０", "20x0", "1890"])
def test_a_veds_model_year_that_is_none_is_dropped_and_said_so(api: ApiClient, year: str) -> None:
    raw = (VEDS_DIR / "kph-frontal.xml").read_bytes()
    assert raw.count(b">2010</nc:ItemModelYearDate>") == 1
    raw = raw.replace(b">2010</nc:ItemModelYearDate>", f">{year}</nc:ItemModelYearDate>".encode())
    result = _post_veds(api, raw)  # the crash is triaged all the same
    dropped = [a for a in result["assumptions"] if a["code"] == "veds_model_year_dropped"]
    assert len(dropped) == 1, result["assumptions"]
    assert _YEAR_ELEMENT in dropped[0]["message"]
    assert year in dropped[0]["message"]
    assert "model_year_imputed" in {a["code"] for a in result["assumptions"]}
    stored = stored_case(api, result["case_id"])
    assert "vehicle" not in stored["notification"]
    assert stored["source_mapping"]["vehicle"]["model_year"] is None
    r, tree = _record(api, result["case_id"])
    for pcr in _reports(tree):
        assert pcr.find("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.20", NS) is None
    assert "eInjury.20" in r.headers["NEMSIS-Left-Out"]


def test_a_case_stored_with_another_script_s_year_still_exports(
    api: ApiClient,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Cases stored before the year was checked keep whatever the document said."""
    from service.db.tables import Case

    case_id = _post_veds(api, (VEDS_DIR / "kph-frontal.xml").read_bytes())["case_id"]
    ctx = api.client.app.state.ctx  # type: ignore[attr-defined]
    with ctx.sessions.begin() as session:  # written as the mapping stored them then
        case = session.get(Case, case_id)
        mapping = copy.deepcopy(case.source_mapping)
        assert mapping["vehicle"]["model_year"] == "2010"
        mapping["vehicle"]["model_year"] = "٢٠١٠"
        case.source_mapping = mapping
    assert stored_case(api, case_id)["source_mapping"]["vehicle"]["model_year"] == "٢٠١٠"
    r, tree = _record(api, case_id)
    for pcr in _reports(tree):
        assert pcr.find("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.20", NS) is None
    assert "eInjury.20" in r.headers["NEMSIS-Left-Out"]
    monkeypatch.setenv("AACN_DATABASE_URL", api.settings.database_url)
    out = tmp_path / "records"
    get_settings.cache_clear()
    try:
        argv = ["cases", "export", "--nemsis", "--out", str(out), "--since", "2000-01-01T00:00Z"]
        agency = [f"--{k.replace('_', '-')}={v}" for k, v in AGENCY.items()]
        assert cli.main([*argv, *agency]) == 0, capsys.readouterr().err
    finally:
        get_settings.cache_clear()
    assert sorted(p.name for p in out.iterdir()) == [f"{case_id}.json", f"{case_id}.xml"]
    assert (out / f"{case_id}.xml").read_bytes() == r.content


# ----------------------------------------------------------------- access


def test_who_may_read_which_record(api_any_db: ApiClient) -> None:
    api = api_any_db  # SQLite and PostgreSQL
    case_id = post_case(api, summary())["case_id"]  # by "submitter-client"
    for role in ("auditor", "admin", "submitter"):
        assert _get(api, case_id, role).status_code == 200
    other = assert_problem(_get(api, case_id, "submitter2"), 404)
    unknown = assert_problem(_get(api, "9b2f0c58-1d7e-4f0e-8f5e-3d1c2b4a6e70", "submitter2"), 404)
    assert other["detail"] == unknown["detail"].replace(
        "9b2f0c58-1d7e-4f0e-8f5e-3d1c2b4a6e70", case_id
    ), "another client's case reads as an unknown one"
    assert_problem(_get(api, case_id, "metrics"), 403)
    no_agency = api.client.get(f"/v1/cases/{case_id}/nemsis", headers=api.headers("metrics"))
    assert_problem(no_agency, 403)  # the role is checked first
    assert_problem(api.client.get(f"/v1/cases/{case_id}/nemsis", params=AGENCY), 401)


@pytest.mark.parametrize(
    ("case_id", "status"),
    [("not-a-case", 404), ("9b2f0c58-1d7e-4f0e-8f5e-3d1c2b4a6e70", 404), ("x" * 65, 422)],
    ids=["malformed", "unknown", "too-long"],
)
def test_malformed_or_unknown_case_ids_are_problems(
    api: ApiClient, case_id: str, status: int
) -> None:
    assert_problem(_get(api, case_id), status)


def test_the_receiving_agency_is_required_and_checked(api: ApiClient) -> None:
    case_id = post_case(api, summary())["case_id"]
    r = api.client.get(f"/v1/cases/{case_id}/nemsis", headers=api.headers("auditor"))
    problem = assert_problem(r, 422)
    assert {e["field"] for e in problem["errors"]} == set(AGENCY)
    assert "AACN_NEMSIS_AGENCY_NUMBER" in json.dumps(problem)
    bad = assert_problem(_get(api, case_id, agency_state="9"), 422)
    assert bad["errors"][0]["field"] == "agency_state"
    # the settings stand in for the query
    settings = Settings(
        nemsis_agency_state_id="C034", nemsis_agency_number="351-C034P2", nemsis_agency_state="09"
    )
    assert agency_from(settings) == Agency("C034", "351-C034P2", "09")
    assert agency_from(settings, number="77").number == "77"


def test_the_case_page_links_the_record_and_its_session_opens_it(api: ApiClient) -> None:
    from fastapi.testclient import TestClient

    case_id = post_case(api, summary())["case_id"]
    page = api.client.get(f"/v1/cases/{case_id}/report", headers=api.headers("auditor"))
    link = Page(page.text).one("a", **{"class": "nemsis"})
    assert link.attrs["href"] == f"/v1/cases/{case_id}/nemsis"
    browser = TestClient(api.client.app, base_url="https://testserver", follow_redirects=False)
    form = browser.get("/v1/session")
    signed = browser.post(
        "/v1/session",
        data={"csrf_token": csrf_token(form.text), "api_key": api.keys["auditor"]},
    )
    assert signed.status_code == 303
    r = browser.get(link.attrs["href"], params=AGENCY)
    assert r.status_code == 200, r.text
    assert validate(r.content) == []
    # a copy of the cookie kept after the sign-out opens nothing
    replay = TestClient(api.client.app, base_url="https://testserver")
    kept = browser.cookies.get(SESSION_COOKIE)
    replay.cookies.set(SESSION_COOKIE, kept, domain="testserver.local", path="/v1")
    assert replay.get(link.attrs["href"], params=AGENCY).status_code == 200
    token = Page(browser.get("/v1/reports").text).one("input", name="csrf_token").attrs["value"]
    assert browser.post("/v1/session/logout", data={"csrf_token": token}).status_code == 303
    assert_problem(replay.get(link.attrs["href"], params=AGENCY), 401)


# ------------------------------------------------------- a record refused


def test_a_record_that_would_not_validate_is_refused_naming_the_element(
    api: ApiClient,
) -> None:
    stored = StoredCase.model_validate(stored_case(api, post_case(api, summary())["case_id"]))
    # a store clock 25 years ahead: NEMSIS times end at 2050
    broken = stored.model_copy(update={"received_at": datetime.fromisoformat("2051-01-01T00:00Z")})
    with pytest.raises(NemsisRecordInvalid) as refused:
        checked_record(broken, Agency("C034", "351-C034P2", "09"))
    fields = {e.field.split("/")[-1] for e in refused.value.errors or []}
    assert {"eTimes.03", "eTimes.13"} <= fields
    assert refused.value.status == 422


# ----------------------------------------------------------------- export


def test_export_writes_resumes_and_rewrites_the_same_records(
    api_any_db: ApiClient,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    api = api_any_db  # SQLite and PostgreSQL
    ids = [post_case(api, make())["case_id"] for make in (summary, _several, _rollover)]
    monkeypatch.setenv("AACN_DATABASE_URL", api.settings.database_url)
    out = tmp_path / "records"
    argv = ["cases", "export", "--nemsis", "--out", str(out), "--since", "2000-01-01T00:00Z"]
    agency = ["--agency-state-id", "C034", "--agency-number", "351-C034P2", "--agency-state", "09"]
    get_settings.cache_clear()
    try:
        assert cli.main([*argv, *agency]) == 0
        first = {p.name: p.read_bytes() for p in out.iterdir()}
        assert sorted(first) == sorted([f"{i}.xml" for i in ids] + [f"{i}.json" for i in ids])
        for case_id in ids:
            assert validate(first[f"{case_id}.xml"]) == []
            assert first[f"{case_id}.xml"] == _get(api, case_id).content
            report = json.loads(first[f"{case_id}.json"])
            assert report["case_id"] == case_id
            assert report["placeholders"] == list(codes.PLACEHOLDERS)
        assert "3 cases: 3 records written, 0 kept" in capsys.readouterr().err
        (out / f"{ids[1]}.xml").unlink()  # an interrupted run
        assert cli.main([*argv, *agency, "--resume"]) == 0
        assert "3 cases: 1 records written, 2 kept" in capsys.readouterr().err
        assert {p.name: p.read_bytes() for p in out.iterdir()} == first
        assert cli.main([*argv, *agency]) == 0  # re-run: rewritten, the same bytes
        assert {p.name: p.read_bytes() for p in out.iterdir()} == first
        later = ["cases", "export", "--nemsis", "--out", str(tmp_path / "none")]
        assert cli.main([*later, "--since", "2100-01-01T00:00Z", *agency]) == 0
        assert "0 cases" in capsys.readouterr().err
        assert cli.main(argv) == 2  # no agency
        assert "--agency-number" in capsys.readouterr().err
    finally:
        get_settings.cache_clear()


def test_deepcopy_of_examples_is_untouched() -> None:
    # the builders above must not alter the documented examples
    before = copy.deepcopy(example("summary"))
    _several()
    _rollover()
    after = example("summary")
    before.pop("event_id")
    after.pop("event_id")
    assert before == after


def test_roles_that_read_records() -> None:
    from service.nemsis.service import READERS

    assert Role.METRICS not in READERS
