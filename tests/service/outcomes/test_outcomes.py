"""Outcome records over HTTP: role separation, every bad input, idempotency, a correction
with its history, on SQLite and PostgreSQL."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from service.outcomes.iss import POSSIBLE_ISS, possible_iss_for_mais
from tests.conftest import _api
from tests.support import ApiClient, assert_problem, example, post_case, summary


@pytest.fixture(
    scope="module", params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)]
)
def app(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ApiClient]:
    """One app per database for the module (each test posts its own cases)."""
    tmp = tmp_path_factory.mktemp("outcomes")
    if request.param == "sqlite":
        yield from _api(f"sqlite:///{tmp / 'aacn.db'}", tmp)
    else:
        yield from _api(request.getfixturevalue("postgres_url_module"), tmp)


@pytest.fixture(scope="module")
def postgres_url_module(postgres_admin_url: str) -> Iterator[str]:
    import uuid

    from sqlalchemy import create_engine, text

    name = "aacn_test_" + uuid.uuid4().hex[:12]
    admin = create_engine(postgres_admin_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    base, _ = postgres_admin_url.rsplit("/", 1)
    try:
        yield f"{base}/{name}"
    finally:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


OUTCOME = {
    "iss": 17,
    "mais": 3,
    "died": False,
    "disposition": "admitted_icu",
    "source": "trauma_registry",
    "recorded_at": "2026-12-01T10:00:00Z",
}


def _url(case_id: str, seat: str = "driver") -> str:
    return f"/v1/cases/{case_id}/occupants/{seat}/outcome"


def _write(app: ApiClient, method: str, url: str, body: Any, role: str = "registry") -> Any:
    return app.client.request(method, url, json=body, headers=app.headers(role))


def _history(app: ApiClient, case_id: str, seat: str = "driver") -> dict[str, Any]:
    r = app.client.get(_url(case_id, seat), headers=app.headers("auditor"))
    assert r.status_code == 200, r.text
    out: dict[str, Any] = r.json()
    return out


def test_the_possible_iss_values() -> None:
    # by hand: AIS 1 alone 1; two AIS 1 2; ...; 7 = 4+1+1+1 needs four regions: impossible
    assert {0, 1, 2, 3, 4, 5, 6, 8, 9, 16, 17, 75} <= POSSIBLE_ISS
    assert not {7, 15, 23, 28, 31, 76, -1} & POSSIBLE_ISS
    assert len(POSSIBLE_ISS) == 45
    assert possible_iss_for_mais(6) == {75}
    assert possible_iss_for_mais(1) == {1, 2, 3}
    assert 75 in possible_iss_for_mais(5)  # three regions at AIS 5


def test_roles_only_registry_and_admin_write_only_auditor_and_admin_read(
    app: ApiClient,
) -> None:
    case_id = post_case(app, summary())["case_id"]
    for role in ("submitter", "auditor", "metrics"):
        body = assert_problem(_write(app, "POST", _url(case_id), OUTCOME, role), 403)
        assert "registry" in body["detail"]
    assert_problem(app.client.post(_url(case_id), json=OUTCOME), 401)
    # the registry key writes outcomes and nothing else
    registry = app.headers("registry")
    assert_problem(app.client.post("/v1/cases", json=summary(), headers=registry), 403)
    assert_problem(app.client.get(f"/v1/cases/{case_id}", headers=registry), 403)
    assert_problem(app.client.get("/v1/cases", headers=registry), 403)
    assert_problem(app.client.get("/v1/quality", headers=registry), 403)
    assert_problem(app.client.get(_url(case_id), headers=registry), 403)
    r = _write(app, "POST", _url(case_id), OUTCOME)
    assert r.status_code == 201, r.text
    assert r.json()["written_by"] == "registry-client"
    assert _write(app, "PUT", _url(case_id), {**OUTCOME, "iss": 9}, "admin").status_code == 200
    assert _history(app, case_id)["current"]["written_by"] == "admin-client"


def test_a_write_is_idempotent_and_a_correction_keeps_the_history(app: ApiClient) -> None:
    case_id = post_case(app, summary())["case_id"]
    first = _write(app, "POST", _url(case_id), OUTCOME)
    assert first.status_code == 201, first.text
    assert first.headers["Idempotent-Replayed"] == "false"
    assert first.json()["revision"] == 1
    # the same content again, by POST or PUT, with 17 as 17.0 or keys reordered: a replay
    again = _write(app, "POST", _url(case_id), dict(reversed(list(OUTCOME.items()))))
    assert again.status_code == 200
    assert again.headers["Idempotent-Replayed"] == "true"
    assert again.json() == first.json()
    assert _write(app, "PUT", _url(case_id), OUTCOME).headers["Idempotent-Replayed"] == "true"
    assert len(_history(app, case_id)["history"]) == 1
    # other content by POST is a conflict, and changes nothing
    conflict = assert_problem(_write(app, "POST", _url(case_id), {**OUTCOME, "iss": 9}), 409)
    assert "PUT" in conflict["detail"]
    assert len(_history(app, case_id)["history"]) == 1
    # a correction by PUT: a new revision, the old one kept
    corrected = _write(app, "PUT", _url(case_id), {**OUTCOME, "iss": 22, "mais": 3}, "admin")
    assert corrected.status_code == 200, corrected.text
    assert corrected.json()["revision"] == 2
    record = _history(app, case_id)
    assert [h["iss"] for h in record["history"]] == [17, 22]
    assert [h["current"] for h in record["history"]] == [False, True]
    assert [h["written_by"] for h in record["history"]] == ["registry-client", "admin-client"]
    assert record["history"][0]["written_at"] <= record["history"][1]["written_at"]
    assert record["current"]["iss"] == 22
    # writing the first content back is a third revision, not a replay of the first
    back = _write(app, "PUT", _url(case_id), OUTCOME)
    assert back.status_code == 200
    assert back.json()["revision"] == 3


def test_put_writes_the_first_outcome_too(app: ApiClient) -> None:
    case_id = post_case(app, summary())["case_id"]
    r = _write(app, "PUT", _url(case_id), OUTCOME)
    assert r.status_code == 201, r.text
    assert r.headers["Location"] == _url(case_id)


def _field(body: dict[str, Any]) -> list[str]:
    return [e["field"] for e in body.get("errors") or []]


@pytest.mark.parametrize(
    ("change", "status", "field"),
    [
        ({"iss": 76}, 422, "iss"),
        ({"iss": -1}, 422, "iss"),
        ({"iss": 15}, 422, "iss"),
        ({"iss": 7}, 422, "iss"),
        ({"iss": "17"}, 422, "iss"),
        ({"mais": 7}, 422, "mais"),
        ({"iss": 17, "mais": 2}, 422, "mais"),
        ({"iss": 75, "mais": 4}, 422, "mais"),
        ({"iss": None, "disposition": "admitted_ward"}, 422, "iss"),
        ({"iss": None, "disposition": "not_transported", "died": True}, 422, "iss"),
        ({"disposition": "no_injury"}, 422, "disposition"),
        ({"disposition": "went_home"}, 422, "disposition"),
        ({"source": "rumour"}, 422, "source"),
        ({"recorded_at": "2026-12-01"}, 422, "recorded_at"),
        ({"recorded_at": "2999-01-01T00:00:00Z"}, 422, "recorded_at"),
        ({"weight": 0}, 422, "weight"),
        ({"colour": "red"}, 422, "colour"),
    ],
)
def test_each_bad_field_is_a_4xx_naming_it_and_changes_nothing(
    app: ApiClient, change: dict[str, Any], status: int, field: str
) -> None:
    case_id = post_case(app, summary())["case_id"]
    body = assert_problem(_write(app, "PUT", _url(case_id), {**OUTCOME, **change}), status)
    assert field in _field(body), body
    r = app.client.get(_url(case_id), headers=app.headers("auditor"))
    assert_problem(r, 404)  # nothing was written


def test_unknown_case_unknown_seat_and_a_seat_without_occupant(app: ApiClient) -> None:
    case_id = post_case(app, summary(seat="driver"))["case_id"]
    body = assert_problem(_write(app, "PUT", _url("no-such-case"), OUTCOME), 404)
    assert _field(body) == ["case_id"]
    body = assert_problem(_write(app, "PUT", _url(case_id, "roof"), OUTCOME), 422)
    assert _field(body) == ["seat"]
    body = assert_problem(_write(app, "PUT", _url(case_id, "rear_left"), OUTCOME), 422)
    assert _field(body) == ["seat"]
    assert "no occupant" in body["errors"][0]["reason"]
    # and nothing was written for the driver either
    assert_problem(app.client.get(_url(case_id), headers=app.headers("auditor")), 404)


def test_malformed_bodies(app: ApiClient) -> None:
    case_id = post_case(app, summary())["case_id"]
    headers = {**app.headers("registry"), "Content-Type": "application/json"}
    dup = b'{"iss": 17, "iss": 75, "source": "ems", "recorded_at": "2026-12-01T10:00:00Z"}'
    assert_problem(app.client.put(_url(case_id), content=dup, headers=headers), 400)
    assert_problem(app.client.put(_url(case_id), content=b"{", headers=headers), 400)
    text = {**app.headers("registry"), "Content-Type": "text/plain"}
    assert_problem(app.client.put(_url(case_id), content=b"{}", headers=text), 415)


def test_ems_outcomes_without_iss(app: ApiClient) -> None:
    body = example("summary")
    body["occupants"].append({**body["occupants"][0], "seat": "front_passenger"})
    case_id = post_case(app, body)["case_id"]
    ems = {"source": "ems", "recorded_at": "2026-12-01T10:00:00Z"}
    r = _write(app, "PUT", _url(case_id), {**ems, "disposition": "no_injury"})
    assert r.status_code == 201, r.text
    assert r.json()["iss"] == 0
    r = _write(
        app, "PUT", _url(case_id, "front_passenger"), {**ems, "disposition": "not_transported"}
    )
    assert r.status_code == 201, r.text
    assert r.json()["iss"] is None


def test_the_openapi_document_names_the_outcome_routes(app: ApiClient) -> None:
    doc = app.client.get("/openapi.json").json()
    ops = doc["paths"]["/v1/cases/{case_id}/occupants/{seat}/outcome"]
    assert set(ops) == {"get", "post", "put"}
    assert "/v1/quality" in doc["paths"]
