"""Bad input gets a clear 4xx problem naming the field, never a 500."""

from __future__ import annotations

import json
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.support import ApiClient, assert_problem, example, summary


def _post(api: ApiClient, body: Any) -> Any:
    return api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))


def _fields(problem: dict[str, Any]) -> list[str]:
    return [e["field"] for e in problem.get("errors", [])]


def _acceleration(**pulse: Any) -> dict[str, Any]:
    body = example("acceleration")
    body["crash"]["pulse"].update(pulse)
    return body


@pytest.mark.parametrize(
    ("mutate", "field"),
    [
        (lambda b: b["crash"]["pulse"].update(sample_rate_hz=-1000), "crash.pulse.sample_rate_hz"),
        (lambda b: b["crash"]["pulse"].update(delta_v_kmh=250.0), "crash.pulse.delta_v_kmh"),
        (lambda b: b["crash"]["pulse"].update(pdof_deg=360.0), "crash.pulse.pdof_deg"),
        (lambda b: b["crash"]["pulse"].update(kind="teleport"), "crash.pulse"),
        (lambda b: b["occupants"][0].update(seat="roof_rack"), "occupants[0].seat"),
        (lambda b: b["occupants"][0].update(frontal_airbag="maybe"), "occupants[0].frontal_airbag"),
        (lambda b: b["occupants"][0].update(side_airbag="curtain"), "occupants[0].side_airbag"),
        (lambda b: b["occupants"][0].update(age_years=-3), "occupants[0].age_years"),
        (lambda b: b["occupants"][0].update(belted="yes"), "occupants[0].belted"),
        (lambda b: b.update(occupants=[]), "occupants"),
        (lambda b: b.update(occurred_at="2026-11-23T08:15:30"), "occurred_at"),
        (lambda b: b.update(event_id="has space"), "event_id"),
        (lambda b: b.update(surprise=1), "surprise"),
        (lambda b: b["vehicle"].update(vin="NOT-A-VIN"), "vehicle.vin"),
        (lambda b: b["vehicle"].update(model="space_shuttle"), "vehicle.model"),
    ],
)
def test_impossible_values_are_refused_naming_the_field(
    api: ApiClient, mutate: Any, field: str
) -> None:
    body = summary()
    mutate(body)
    problem = assert_problem(_post(api, body), 422)
    assert any(f.startswith(field) for f in _fields(problem)), problem
    assert all(e["reason"] for e in problem["errors"])


def test_duplicate_seats_are_refused(api: ApiClient) -> None:
    body = summary()
    body["occupants"].append(dict(body["occupants"][0]))
    problem = assert_problem(_post(api, body), 422)
    assert "each seat" in json.dumps(problem)


@pytest.mark.parametrize("token", ["NaN", "Infinity", "-Infinity", "1e999"])
def test_non_finite_numbers_are_refused(api: ApiClient, token: str) -> None:
    text = json.dumps(summary()).replace('"delta_v_kmh": 56.0', f'"delta_v_kmh": {token}')
    assert token in text
    response = api.client.post(
        "/v1/cases",
        content=text,
        headers={**api.headers("submitter"), "Content-Type": "application/json"},
    )
    problem = assert_problem(response, 422)
    assert "crash.pulse.delta_v_kmh" in _fields(problem)


def test_non_finite_sample_in_a_series_is_refused(api: ApiClient) -> None:
    body = _acceleration()
    text = json.dumps(body)
    head, tail = text.split('"longitudinal_g": [', 1)
    text = head + '"longitudinal_g": [NaN, ' + tail
    response = api.client.post(
        "/v1/cases",
        content=text,
        headers={**api.headers("submitter"), "Content-Type": "application/json"},
    )
    problem = assert_problem(response, 422)
    assert any(f.startswith("crash.pulse.longitudinal_g") for f in _fields(problem))


@pytest.mark.parametrize(
    ("pulse", "field"),
    [
        ({"longitudinal_g": [0.0, -1.0], "lateral_g": [0.0, 0.0]}, "crash.pulse.longitudinal_g"),
        ({"lateral_g": [0.0] * 10}, "crash.pulse"),
        ({"longitudinal_g": [-1.0] * 60_001, "lateral_g": [0.0] * 60_001}, "crash.pulse"),
        ({"longitudinal_g": [-900.0] * 121}, "crash.pulse"),
        ({"sample_rate_hz": 0}, "crash.pulse.sample_rate_hz"),
    ],
)
def test_series_too_short_too_long_or_inconsistent(
    api: ApiClient, pulse: dict[str, Any], field: str
) -> None:
    response = _post(api, _acceleration(**pulse))
    status = response.status_code
    assert status in (413, 422), response.text
    problem = assert_problem(response, status)
    if status == 422:
        assert any(f.startswith(field) for f in _fields(problem)), problem


def test_edr_delta_v_above_200_kmh_is_refused(api: ApiClient) -> None:
    body = example("delta_v")
    body["crash"]["pulse"]["longitudinal_kmh"][-1] = -230.0
    problem = assert_problem(_post(api, body), 422)
    assert any(f.startswith("crash.pulse") for f in _fields(problem))


def test_body_over_the_limit_is_413(api: ApiClient) -> None:
    big = "x" * (api.settings.max_body_bytes + 1)
    response = api.client.post(
        "/v1/cases",
        content=big,
        headers={**api.headers("submitter"), "Content-Type": "application/json"},
    )
    assert_problem(response, 413)


def test_malformed_json_is_400(api: ApiClient) -> None:
    response = api.client.post(
        "/v1/cases",
        content=b'{"event_id": ',
        headers={**api.headers("submitter"), "Content-Type": "application/json"},
    )
    assert_problem(response, 400)


def test_refused_requests_store_nothing(api: ApiClient) -> None:
    bad = summary()
    bad["crash"]["pulse"]["delta_v_kmh"] = 500
    assert_problem(_post(api, bad), 422)
    listing = api.client.get("/v1/cases", headers=api.headers("auditor")).json()
    assert listing["items"] == []


json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.integers()
    | st.text(max_size=8),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=8), children, max_size=4)
    ),
    max_leaves=12,
)


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    path=st.sampled_from(
        [
            ("event_id",),
            ("occurred_at",),
            ("vehicle",),
            ("crash", "pulse"),
            ("crash", "pulse", "delta_v_kmh"),
            ("crash", "pulse", "pdof_deg"),
            ("crash", "rollover"),
            ("occupants",),
            ("occupants", 0),
            ("occupants", 0, "posture_lumbar_flexion_deg"),
            ("occupants", 0, "body"),
        ]
    ),
    value=json_values,
)
def test_fuzzed_bodies_never_give_500(api: ApiClient, path: tuple[Any, ...], value: Any) -> None:
    body = summary()
    target: Any = body
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    response = _post(api, body)
    assert response.status_code < 500, response.text
    if response.status_code >= 400:
        assert_problem(response, response.status_code)
