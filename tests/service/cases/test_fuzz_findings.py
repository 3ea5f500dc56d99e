"""The fuzzing findings, one test each (each failed on the code before its fix)."""

from __future__ import annotations

import base64
import io
import json
import logging
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import text

from service.app import create_app
from service.auth import Role, create_api_key
from service.cli import main as cli
from service.logs import JsonFormatter
from service.settings import Settings, get_settings
from tests.support import ApiClient, assert_problem, example, summary

JSON = {"Content-Type": "application/json"}


def _post_text(api: ApiClient, body: str | bytes, role: str = "submitter") -> Any:
    return api.client.post("/v1/cases", content=body, headers={**api.headers(role), **JSON})


def _cursor(value: Any) -> str:
    raw = value if isinstance(value, bytes) else json.dumps(value).encode()
    return base64.urlsafe_b64encode(raw).decode().rstrip("=")


# ------------------------------------------------- 1. 500s on GET /v1/cases


@pytest.mark.parametrize(
    "query",
    [
        {"received_from": "0001-01-01T00:00:00+14:00"},
        {"received_before": "9999-12-31T23:59:59-14:00"},
        {"cursor": _cursor(["0001-01-01T00:00:00+14:00", "x"])},
        {"cursor": _cursor(b"[" * 1100 + b"]" * 1100)},
        {"cursor": _cursor(b"[" * 150 + b"]" * 150)},  # short enough for the length bound
    ],
    ids=["received_from-0001", "received_before-9999", "cursor-0001", "cursor-1100", "cursor-150"],
)
def test_extreme_list_parameters_are_422_not_500(api: ApiClient, query: dict[str, str]) -> None:
    response = api.client.get("/v1/cases", params=query, headers=api.headers("auditor"))
    problem = assert_problem(response, 422)
    assert problem["errors"][0]["field"] in query


# ------------------------------------------------------- 2. strict wire types


@pytest.mark.parametrize(
    ("path", "value"),
    [
        (("occurred_at",), 0),
        (("occurred_at",), "1"),
        (("occurred_at",), "0001-01-01T00:00:00Z"),
        (("occurred_at",), "9999-12-31T23:59:59Z"),
        (("occurred_at",), "1970-01-01T00:00:00Z"),
        (("occupants", 0, "belted"), "yes"),
        (("occupants", 0, "belted"), 1),
        (("crash", "pulse", "delta_v_kmh"), "56"),
        (("crash", "rollover"), "false"),
        (("occupants", 0, "age_years"), "42"),
    ],
)
def test_strict_wire_types_and_a_plausible_crash_time(
    api: ApiClient, path: tuple[Any, ...], value: Any
) -> None:
    body = summary()
    target: Any = body
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    problem = assert_problem(_post_text(api, json.dumps(body)), 422)
    field = ".".join(str(p) for p in path).replace(".0.", "[0].")
    assert any(e["field"] == field for e in problem["errors"]), problem


def test_a_crash_time_within_the_clock_skew_allowance_is_taken(api: ApiClient) -> None:
    from datetime import UTC, datetime, timedelta

    body = summary()
    body["occurred_at"] = (datetime.now(UTC) + timedelta(minutes=5)).isoformat()
    assert _post_text(api, json.dumps(body)).status_code == 201
    body = summary()
    body["occurred_at"] = (datetime.now(UTC) + timedelta(minutes=30)).isoformat()
    assert_problem(_post_text(api, json.dumps(body)), 422)


# ------------------------------------------------------ 3. duplicate JSON keys


def test_duplicate_keys_are_refused_and_nothing_is_stored(api: ApiClient) -> None:
    text_body = json.dumps(summary()).replace(
        '"delta_v_kmh": 56.0', '"delta_v_kmh": 500, "delta_v_kmh": 56.0'
    )
    assert text_body.count("delta_v_kmh") == 2
    problem = assert_problem(_post_text(api, text_body), 400)
    assert "duplicate key 'delta_v_kmh'" in problem["detail"]
    listing = api.client.get("/v1/cases", headers=api.headers("auditor")).json()
    assert listing["items"] == []


def test_an_overlong_integer_is_400_in_the_service_s_words(api: ApiClient) -> None:
    body = json.dumps(summary()).replace('"delta_v_kmh": 56.0', '"delta_v_kmh": ' + "9" * 5000)
    problem = assert_problem(_post_text(api, body), 400)
    assert "a number is too long: an integer of 5000 digits" in problem["detail"], problem
    assert "sys." not in json.dumps(problem), "the interpreter's words stay inside"
    # an integer Python can read is the validation's to refuse, naming the field
    body = json.dumps(summary()).replace('"delta_v_kmh": 56.0', '"delta_v_kmh": ' + "9" * 4300)
    problem = assert_problem(_post_text(api, body), 422)
    assert problem["errors"][0]["field"] == "crash.pulse.delta_v_kmh"


def test_deeply_nested_bodies_are_400(api: ApiClient) -> None:
    assert_problem(_post_text(api, "[" * 5000 + "]" * 5000), 400)


# ------------------------------------------- 4. idempotency on meaning, not spelling


def _respell(body: dict[str, Any]) -> dict[str, Any]:
    again = json.loads(json.dumps(body))
    again["crash"]["pulse"]["delta_v_kmh"] = 56  # was 56.0
    again["crash"]["pulse"]["pdof_deg"] = -0.0  # was 0.0
    again["crash"]["rollover"] = False  # the default, written out or not
    again["vehicle"]["drive_side"] = "left"
    again["occurred_at"] = "2026-11-23T09:15:30+01:00"  # the same instant
    return again


def test_same_meaning_in_another_spelling_replays(api_any_db: ApiClient) -> None:
    body = summary(event_id="evt-spelling")
    body["crash"].pop("rollover", None)
    h = api_any_db.headers("submitter")
    first = api_any_db.client.post("/v1/cases", json=body, headers=h)
    assert first.status_code == 201, first.text
    respelled = _respell(body)
    assert json.dumps(respelled) != json.dumps(body)
    again = api_any_db.client.post("/v1/cases", json=respelled, headers=h)
    assert again.status_code == 200, again.text
    assert again.json()["case_id"] == first.json()["case_id"]
    other = _respell(body)
    other["crash"]["pulse"]["delta_v_kmh"] = 57
    assert_problem(api_any_db.client.post("/v1/cases", json=other, headers=h), 409)


# ------------------------------------------------------- 5. chunked bodies


def test_a_chunked_body_over_the_limit_is_413(api: ApiClient) -> None:
    chunk = b" " * 65536
    n = api.settings.max_body_bytes // len(chunk) + 2

    def chunks() -> Iterator[bytes]:
        yield from (chunk for _ in range(n))

    response = api.client.post(
        "/v1/cases", content=chunks(), headers={**api.headers("submitter"), **JSON}
    )
    assert "content-length" not in {k.lower() for k in response.request.headers}
    assert_problem(response, 413)


def test_a_chunked_body_under_the_limit_is_triaged(api: ApiClient) -> None:
    raw = json.dumps(example("summary")).encode()

    def chunks() -> Iterator[bytes]:
        for i in range(0, len(raw), 100):
            yield raw[i : i + 100]

    response = api.client.post(
        "/v1/cases", content=chunks(), headers={**api.headers("submitter"), **JSON}
    )
    assert response.status_code == 201, response.text


# ------------------------------------- 6. 415, and authentication before the body


@pytest.mark.parametrize("media", ["text/plain", "application/x-www-form-urlencoded", None])
def test_a_body_that_is_not_json_is_415(api: ApiClient, media: str | None) -> None:
    headers = api.headers("submitter")
    if media is not None:
        headers["Content-Type"] = media
    response = api.client.post("/v1/cases", content=json.dumps(summary()), headers=headers)
    assert_problem(response, 415)


def test_json_with_a_charset_is_taken(api: ApiClient) -> None:
    response = api.client.post(
        "/v1/cases",
        content=json.dumps(summary()),
        headers={**api.headers("submitter"), "Content-Type": "application/json; charset=utf-8"},
    )
    assert response.status_code == 201, response.text


def test_authentication_comes_before_the_body(api: ApiClient) -> None:
    assert_problem(api.client.post("/v1/cases", content=b'{"event_id": ', headers=JSON), 401)
    assert_problem(
        api.client.post("/v1/cases", content=b"x", headers={"Content-Type": "text/plain"}), 401
    )
    response = api.client.post(
        "/v1/cases", content=b'{"event_id": ', headers={**api.headers("auditor"), **JSON}
    )
    assert_problem(response, 403)


# --------------------------------------------------- 7. no personal data in logs

VIN = "1HGBH41JXMN109186"


@pytest.fixture
def json_log() -> Iterator[io.StringIO]:
    sink = io.StringIO()
    handler = logging.StreamHandler(sink)
    handler.setFormatter(JsonFormatter())
    root = logging.getLogger()
    old_level = root.level
    root.addHandler(handler)
    root.setLevel(logging.DEBUG)
    try:
        yield sink
    finally:
        root.removeHandler(handler)
        root.setLevel(old_level)


def _fail_inserts(api: ApiClient) -> None:
    """A real database error on every case insert (SQLite's OperationalError, as from a
    read-only or full store): a trigger in the store writes to a table that is gone."""
    ctx = api.client.app.state.ctx  # type: ignore[attr-defined]
    with ctx.db_engine.begin() as conn:
        conn.execute(
            text(
                "CREATE TRIGGER refuse_cases BEFORE INSERT ON cases "
                "BEGIN INSERT INTO store_offline VALUES (1); END"
            )
        )


def _personal(age: float = 83.5) -> dict[str, Any]:
    body = summary()
    body["vehicle"]["vin"] = VIN
    body["occupants"][0]["age_years"] = age
    return body


def test_a_database_error_logs_no_notification_contents(
    api: ApiClient, json_log: io.StringIO
) -> None:
    _fail_inserts(api)
    response = api.client.post(
        "/v1/cases", json=_personal(), headers={**api.headers("submitter"), "X-Request-ID": "r-1"}
    )
    assert response.status_code == 202, response.text
    assert response.headers["X-Request-ID"] == "r-1"
    out = json_log.getvalue()
    records = [json.loads(line) for line in out.splitlines()]
    assert any(r.get("request_id") == "r-1" for r in records), out
    assert any("spool" in r["message"] for r in records), out
    for secret in (VIN, "83.5", '"sex"', "age_years"):
        assert secret not in out, f"{secret} leaked into the logs: {out}"


def test_an_unanswerable_case_is_503_and_logs_nothing_personal(
    sqlite_url: str, tmp_path: Path, json_log: io.StringIO
) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("")
    settings = Settings(database_url=sqlite_url, spool_path=blocker / "spool.db")
    app = create_app(settings)
    with TestClient(app) as client:
        _, key = create_api_key(app.state.ctx.sessions, name="c", role=Role.SUBMITTER)
        api = ApiClient(client=client, keys={"submitter": key}, settings=settings)
        _fail_inserts(api)
        response = client.post(
            "/v1/cases", json=_personal(), headers={"Authorization": f"Bearer {key}"}
        )
        problem = assert_problem(response, 503)
        assert response.headers["Retry-After"]
        assert "not answered" in problem["detail"]
    out = json_log.getvalue()
    assert "spool failed too" in out
    for secret in (VIN, "83.5", "age_years"):
        assert secret not in out, f"{secret} leaked into the logs: {out}"


def test_a_failing_row_message_is_not_logged() -> None:
    """A driver's error text can quote the row; only its type and SQLSTATE are logged."""

    class FakeDriverError(Exception):
        sqlstate = "23514"

    FakeDriverError.__module__ = "psycopg.errors"
    try:
        raise FakeDriverError(f"new row violates check; Failing row contains ({VIN}, 83.5)")
    except FakeDriverError:
        record = logging.LogRecord(
            "x", logging.ERROR, "f", 1, "boom", None, __import__("sys").exc_info()
        )
    line = JsonFormatter().format(record)
    assert VIN not in line
    assert "SQLSTATE 23514" in line


# ------------------------------------------------------------------- 8. headers


def test_security_headers(api: ApiClient) -> None:
    created = api.client.post("/v1/cases", json=summary(), headers=api.headers("submitter"))
    got = api.client.get(created.headers["Location"], headers=api.headers("auditor"))
    listing = api.client.get("/v1/cases", headers=api.headers("auditor"))
    unauth = api.client.get("/v1/cases")
    for response in (created, got, listing, unauth):
        assert response.headers["X-Content-Type-Options"] == "nosniff"
        assert response.headers["Cache-Control"] == "no-store"
        assert "server" not in response.headers
    assert api.client.get("/livez").headers["X-Content-Type-Options"] == "nosniff"


def test_docs_are_served_without_a_cdn(api: ApiClient) -> None:
    page = api.client.get("/docs")
    assert page.status_code == 200
    html = page.text
    assert "cdn" not in html.lower()
    assert "https://" not in html, "every asset is local"
    assert "http://" not in html
    for asset in ("swagger-ui-bundle.js", "swagger-ui.css"):
        assert f"/docs/static/{asset}" in html
        served = api.client.get(f"/docs/static/{asset}")
        assert served.status_code == 200
        assert len(served.content) > 10_000


def test_readyz_names_no_internal_host(api: ApiClient) -> None:
    ready = api.client.get("/readyz").json()
    assert ready["status"] == "ready"
    assert ready["store"] == "writable"
    assert "localhost" not in json.dumps(ready)
    assert "127.0.0.1" not in json.dumps(ready)


def test_metrics_behind_a_key_when_configured(sqlite_url: str, tmp_path: Path) -> None:
    settings = Settings(database_url=sqlite_url, metrics_access="key", spool_path=tmp_path / "s")
    app = create_app(settings)
    with TestClient(app) as client:
        sessions = app.state.ctx.sessions
        keys = {
            role: create_api_key(sessions, name=role.value, role=role)[1]
            for role in (Role.METRICS, Role.ADMIN, Role.SUBMITTER)
        }
        assert_problem(client.get("/metrics"), 401)
        bearer = {r: {"Authorization": f"Bearer {k}"} for r, k in keys.items()}
        assert_problem(client.get("/metrics", headers=bearer[Role.SUBMITTER]), 403)
        assert client.get("/metrics", headers=bearer[Role.METRICS]).status_code == 200
        assert client.get("/metrics", headers=bearer[Role.ADMIN]).status_code == 200
        # a metrics key reads no case
        assert_problem(client.get("/v1/cases", headers=bearer[Role.METRICS]), 403)


# ----------------------------------------------------- 9. keys revoke and rotate


@pytest.fixture
def served_db(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[ApiClient]:
    url = f"sqlite:///{tmp_path / 'keys.db'}"
    monkeypatch.setenv("AACN_DATABASE_URL", url)
    get_settings.cache_clear()
    settings = Settings(database_url=url, spool_path=tmp_path / "spool.db")
    with TestClient(create_app(settings)) as client:
        yield ApiClient(client=client, keys={}, settings=settings)
    get_settings.cache_clear()


def _create_key(name: str, capsys: pytest.CaptureFixture[str]) -> str:
    assert cli.main(["keys", "create", "--role", "submitter", "--name", name]) == 0
    return capsys.readouterr().out.strip()


def test_keys_revoke_by_name_or_id_is_enforced_at_once(
    served_db: ApiClient, capsys: pytest.CaptureFixture[str]
) -> None:
    client = served_db.client
    key_a, key_b = _create_key("center-a", capsys), _create_key("center-b", capsys)
    for key in (key_a, key_b):
        ok = client.post("/v1/cases", json=summary(), headers={"Authorization": f"Bearer {key}"})
        assert ok.status_code == 201
    assert cli.main(["keys", "revoke", "center-a"]) == 0
    assert "revoked" in capsys.readouterr().err
    h_a = {"Authorization": f"Bearer {key_a}"}
    assert_problem(client.post("/v1/cases", json=summary(), headers=h_a), 401)
    assert cli.main(["keys", "list"]) == 0
    listing = capsys.readouterr().out
    key_b_id = next(line.split("\t")[0] for line in listing.splitlines() if "center-b" in line)
    assert cli.main(["keys", "revoke", key_b_id]) == 0
    h_b = {"Authorization": f"Bearer {key_b}"}
    assert_problem(client.post("/v1/cases", json=summary(), headers=h_b), 401)
    assert cli.main(["keys", "revoke", "no-such-key"]) == 1
    for other_digits in ("²", "٢", "１"):  # digits str.isdigit takes and int() may not
        assert cli.main(["keys", "revoke", other_digits]) == 1
        assert f"no API key named or numbered {other_digits!r}" in capsys.readouterr().err


def test_keys_rotate_replaces_the_secret_at_once(
    served_db: ApiClient, capsys: pytest.CaptureFixture[str]
) -> None:
    client = served_db.client
    old = _create_key("center-r", capsys)
    body = summary(event_id="evt-before-rotation")
    first = client.post("/v1/cases", json=body, headers={"Authorization": f"Bearer {old}"})
    assert first.status_code == 201
    assert cli.main(["keys", "rotate", "center-r"]) == 0
    new = capsys.readouterr().out.strip()
    assert new.startswith("aacn_")
    assert new != old
    assert_problem(
        client.post("/v1/cases", json=summary(), headers={"Authorization": f"Bearer {old}"}), 401
    )
    # the same client: its events stay its own (idempotency across the rotation)
    again = client.post("/v1/cases", json=body, headers={"Authorization": f"Bearer {new}"})
    assert again.status_code == 200
    assert again.json()["case_id"] == first.json()["case_id"]
