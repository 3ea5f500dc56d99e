"""GET /v1/cases: newest first, keyset pagination, filters."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest

from tests.support import ApiClient, assert_problem, summary


@pytest.fixture
def filled(api_any_db: ApiClient) -> tuple[ApiClient, list[dict]]:
    """Seven cases: frontal at rising delta-V, plus rear and side ones."""
    bodies = [summary(dv, 0.0, belted=dv < 60) for dv in (10, 25, 40, 55, 70)]
    bodies.append(summary(40, 180.0))
    bodies.append(summary(45, 270.0))  # left side: near side for the (left-hand) driver
    results = []
    for body in bodies:
        r = api_any_db.client.post("/v1/cases", json=body, headers=api_any_db.headers("submitter"))
        assert r.status_code == 201, r.text
        results.append(r.json())
    return api_any_db, results


def _get(api: ApiClient, **params: object) -> dict:
    r = api.client.get("/v1/cases", params=params, headers=api.headers("auditor"))
    assert r.status_code == 200, r.text
    return r.json()


def test_pages_walk_every_case_newest_first(filled: tuple[ApiClient, list[dict]]) -> None:
    api, results = filled
    seen: list[str] = []
    cursor = None
    while True:
        page = _get(api, limit=3, **({"cursor": cursor} if cursor else {}))
        assert len(page["items"]) <= 3
        seen += [c["case_id"] for c in page["items"]]
        cursor = page["next_cursor"]
        if cursor is None:
            break
    assert seen == [r["case_id"] for r in reversed(results)]


def test_limit_is_capped(filled: tuple[ApiClient, list[dict]]) -> None:
    api, _ = filled
    assert len(_get(api, limit=10_000)["items"]) == 7
    api.settings.page_max_limit = 3  # the app reads its settings object per request
    page = _get(api, limit=10_000)
    assert len(page["items"]) == 3
    assert page["next_cursor"] is not None


def test_filters(filled: tuple[ApiClient, list[dict]]) -> None:
    api, results = filled
    positives = {r["case_id"] for r in results if r["triage"]["iss15_plus"]}
    negatives = {r["case_id"] for r in results} - positives
    assert positives, "the fixture spans both decisions"
    assert negatives, "the fixture spans both decisions"
    assert {c["case_id"] for c in _get(api, iss15_plus=True)["items"]} == positives
    assert {c["case_id"] for c in _get(api, iss15_plus=False)["items"]} == negatives
    rear = _get(api, impact_mode="rear")["items"]
    assert [c["case_id"] for c in rear] == [results[5]["case_id"]]
    near = _get(api, impact_mode="near_side")["items"]
    assert [c["case_id"] for c in near] == [results[6]["case_id"]]
    future = (datetime.now(UTC) + timedelta(hours=1)).isoformat()
    assert _get(api, received_from=future)["items"] == []
    assert len(_get(api, received_before=future)["items"]) == 7
    middle = results[3]["received_at"]
    newer = _get(api, received_from=middle)["items"]
    assert {c["case_id"] for c in newer} == {r["case_id"] for r in results[3:]}


def test_bad_cursor_and_bad_filter_are_problems(api: ApiClient) -> None:
    h = api.headers("auditor")
    assert_problem(api.client.get("/v1/cases", params={"cursor": "garbage!"}, headers=h), 422)
    assert_problem(api.client.get("/v1/cases", params={"impact_mode": "sideways"}, headers=h), 422)
    assert_problem(api.client.get("/v1/cases", params={"limit": 0}, headers=h), 422)


@pytest.mark.parametrize(
    "value", ["0.5", "1732950000", "2026-11-23T08:15:30", "yesterday", "2026-13-40T00:00:00Z"]
)
def test_time_filters_take_rfc3339_with_an_offset_only(api: ApiClient, value: str) -> None:
    """A bare number is not a time here (pydantic would read it as a Unix time and list
    every case), nor is a time without its offset: 422 naming the filter."""
    r = api.client.get("/v1/cases", params={"received_from": value}, headers=api.headers("auditor"))
    problem = assert_problem(r, 422)
    assert [e["field"] for e in problem["errors"]] == ["received_from"]


def test_a_wrong_method_names_every_method_of_the_path(api: ApiClient) -> None:
    r = api.client.request("DELETE", "/v1/cases", headers=api.headers("admin"))
    assert_problem(r, 405)
    assert r.headers["Allow"] == "GET, POST"
