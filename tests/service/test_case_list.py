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
