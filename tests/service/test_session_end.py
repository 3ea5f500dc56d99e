"""Sign-out ends the session on the server: a kept copy of the cookie is refused."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import func, select

from service.app import create_app
from service.auth import Role, create_api_key
from service.browser_session import SESSION_COOKIE
from service.db.tables import EndedSession
from service.settings import Settings
from tests.service.pages_support import Page, csrf_token
from tests.service.test_store_outage import _database
from tests.support import ApiClient


def _browser(app: Any) -> TestClient:
    """A client that keeps cookies like a browser (https, so Secure cookies are sent)."""
    return TestClient(app, base_url="https://testserver", follow_redirects=False)


def _sign_in(client: TestClient, key: str) -> str:
    form = client.get("/v1/session", params={"next": "/v1/reports"})
    r = client.post(
        "/v1/session",
        data={"csrf_token": csrf_token(form.text), "api_key": key, "next": "/v1/reports"},
    )
    assert r.status_code == 303, r.text
    value = client.cookies.get(SESSION_COOKIE)
    assert value
    return value


def _replay(app: Any, value: str) -> int:
    """GET /v1/reports from a fresh client holding only `value` as its session cookie."""
    client = _browser(app)
    client.cookies.set(SESSION_COOKIE, value, domain="testserver.local", path="/v1")
    return int(client.get("/v1/reports").status_code)


def _logout(client: TestClient) -> Any:
    token = Page(client.get("/v1/reports").text).one("input", name="csrf_token").attrs["value"]
    return client.post("/v1/session/logout", data={"csrf_token": token})


def test_the_old_cookie_replayed_after_logout_gets_401(api: ApiClient) -> None:
    app = api.client.app
    browser, other_browser = _browser(app), _browser(app)
    old = _sign_in(browser, api.keys["auditor"])
    other = _sign_in(other_browser, api.keys["auditor"])
    assert _replay(app, old) == 200
    r = _logout(browser)
    assert r.status_code == 303
    assert _replay(app, old) == 401
    page = _browser(app)
    page.cookies.set(SESSION_COOKIE, old, domain="testserver.local", path="/v1")
    refused = page.get("/v1/reports")
    assert "Your session has ended" in refused.text
    # the sign-out ends that session only: another of the same key still holds
    assert _replay(app, other) == 200
    # signing out twice is harmless
    assert _logout(other_browser).status_code == 303
    assert _replay(app, other) == 401


def test_a_session_ended_on_one_process_is_refused_by_another(tmp_path: Path) -> None:
    url = f"sqlite:///{tmp_path / 'shared.db'}"
    secret = "s" * 40
    apps = [create_app(Settings(database_url=url, session_secret=secret)) for _ in range(2)]
    with TestClient(apps[0]), TestClient(apps[1]):
        ctx = apps[0].state.ctx
        _, key = create_api_key(ctx.sessions, name="aud", role=Role.AUDITOR)
        browser = _browser(apps[0])
        value = _sign_in(browser, key)
        assert _replay(apps[1], value) == 200
        assert _logout(browser).status_code == 303
        assert _replay(apps[1], value) == 401
        with ctx.sessions() as session:
            assert session.scalar(select(func.count()).select_from(EndedSession)) == 1


@pytest.mark.postgres
def test_a_sign_out_the_store_cannot_record_says_so(own_postgres: Any, tmp_path: Path) -> None:
    url = _database(own_postgres.admin_url)
    app = create_app(
        Settings(database_url=url, spool_path=tmp_path / "spool.db", session_secret="s" * 40)
    )
    with TestClient(app):
        _, key = create_api_key(app.state.ctx.sessions, name="aud", role=Role.AUDITOR)
        browser = _browser(app)
        _sign_in(browser, key)
        token = Page(browser.get("/v1/reports").text).one("input", name="csrf_token")
        own_postgres.pg_ctl("stop", "-m", "fast")
        try:
            r = browser.post("/v1/session/logout", data={"csrf_token": token.attrs["value"]})
            assert r.status_code == 503, r.text[:300]
            assert "Sign-out not recorded" in r.text
            assert "stays valid until" in r.text
            # the cookie is cleared in this browser all the same
            cleared = [h for h in r.headers.get_list("set-cookie") if h.startswith(SESSION_COOKIE)]
            assert cleared
            assert "Max-Age=0" in cleared[0]
        finally:
            own_postgres.pg_ctl("start")
