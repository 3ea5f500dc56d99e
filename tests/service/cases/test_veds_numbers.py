"""VEDS numbers: ASCII digits only (xsd:decimal), and any precision that fits the limits."""

from __future__ import annotations

from decimal import Decimal
from pathlib import Path
from typing import Any

import pytest

from service.cases.veds import KM_PER_MILE, VEDS_MEDIA_TYPE
from tests.support import ApiClient, assert_problem, stored_case

DOCS = Path(__file__).parent / "veds"
_PULSE = "veds:Crash/veds:CrashVehicle/veds:VehicleCrashPulse[1]"
_VALUE = f"{_PULSE}/veds:CrashPulseChangeInVelocityMeasure/nc:MeasurePointValue"


def _post(api: ApiClient, raw: bytes) -> Any:
    return api.client.post(
        "/v1/cases",
        content=raw,
        headers={**api.headers("submitter"), "Content-Type": VEDS_MEDIA_TYPE},
    )


def _kph(value: str) -> bytes:
    raw = (DOCS / "kph-frontal.xml").read_bytes()
    assert b">-32.18688<" in raw
    return raw.replace(b">-32.18688<", f">{value}<".encode(), 1)


@pytest.mark.parametrize(
    "value",
    ["٤٠", "４０", "-٣٢.٥", "3２", "40.٥", "۴۰", "४०", "4" + "0" * 64],
    ids=[
        "arabic-indic",
        "fullwidth",
        "arabic-fraction",
        "mixed",
        "fraction",
        "persian",
        "devanagari",
        "overlong",
    ],
)
def test_numbers_other_than_ascii_decimals_are_refused(api: ApiClient, value: str) -> None:
    problem = assert_problem(_post(api, _kph(value)), 422)
    assert [(e["field"], e["type"]) for e in problem["errors"]] == [(_VALUE, "veds_number")]


def test_a_clock_direction_in_other_digits_is_refused(api: ApiClient) -> None:
    raw = (
        (DOCS / "kph-frontal.xml")
        .read_bytes()
        .replace(b">12</veds:CrashPulsePrincipal", ">１２</veds:CrashPulsePrincipal".encode(), 1)
    )
    problem = assert_problem(_post(api, raw), 422)
    assert [e["type"] for e in problem["errors"]] == ["veds_clock"]


def test_the_exact_kph_twin_of_a_precise_mph_value_is_taken(api: ApiClient) -> None:
    # 12 decimals in MPH give 18 in KPH: the twin used to be refused (at most 12)
    mph = Decimal("19.123456789012")
    kph = mph * KM_PER_MILE
    assert -kph.as_tuple().exponent == 18  # type: ignore[operator]
    mph_raw = (DOCS / "mph-frontal.xml").read_bytes()
    assert b"<nc:MeasurePointValue>20</nc:MeasurePointValue>" in mph_raw
    mph_raw = mph_raw.replace(
        b"<nc:MeasurePointValue>20</nc:MeasurePointValue>",
        f"<nc:MeasurePointValue>{mph}</nc:MeasurePointValue>".encode(),
        1,
    )
    a, b = _post(api, mph_raw), _post(api, _kph(f"-{kph}"))
    assert a.status_code == b.status_code == 201, (a.text, b.text)
    assert a.json()["pulse"]["delta_v_kmh"] == b.json()["pulse"]["delta_v_kmh"] == float(kph)


@pytest.mark.parametrize("value", ["40.", ".5e0"])
def test_decimal_lexical_edges(api: ApiClient, value: str) -> None:
    r = _post(api, _kph(value))
    if value == "40.":  # xsd:decimal allows a trailing point
        assert r.status_code == 201, r.text
    else:  # no exponent in xsd:decimal
        assert_problem(r, 422)


@pytest.mark.parametrize("value", ["0000000000040", "+0040.000", "-" + "0" * 60 + "40"])
def test_every_xsd_decimal_within_the_length_cap_is_taken(api: ApiClient, value: str) -> None:
    r = _post(api, _kph(value))
    assert r.status_code == 201, r.text
    assert r.json()["pulse"]["delta_v_kmh"] == 40.0


def test_a_long_decimal_beyond_the_limits_is_refused_for_its_value(api: ApiClient) -> None:
    problem = assert_problem(_post(api, _kph("1" * 13)), 422)
    assert [(e["field"], e["type"]) for e in problem["errors"]] == [(_VALUE, "veds_range")]


def test_xsd_integers_with_leading_zeros_are_taken(api: ApiClient) -> None:
    raw = (DOCS / "kph-rollover-two-pulses.xml").read_bytes()
    for written, spelled in (
        (b">12</veds:CrashPulsePrincipal", b">0012</veds:CrashPulsePrincipal"),
        (b">4</veds:CrashPulseRolloverQuarterTurns", b">+04</veds:CrashPulseRolloverQuarterTurns"),
    ):
        assert raw.count(written) == 1
        raw = raw.replace(written, spelled)
    r = _post(api, raw)
    assert r.status_code == 201, r.text
    crash = stored_case(api, r.json()["case_id"])["notification"]["crash"]
    assert (crash["pulse"]["pdof_deg"], crash["rollover_quarter_turns"]) == (0.0, 4)
