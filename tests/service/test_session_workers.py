"""Sign-in on the default start: every worker of `serve` signs with one secret (issue 41).

Two worker processes of the real ``aacn-triage serve``, real HTTP on loopback, a new
connection for every request (so both workers answer): the sign-in form comes from
one worker and is posted to whichever takes the connection, and the session cookie
is read by whichever takes the next one.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import httpx2 as httpx
import pytest

from tests.paths import ROOT
from tests.service.pages_support import csrf_token
from tests.support import console_server

SIGN_INS = 20


def _cookie(response: httpx.Response, name: str) -> str:
    for header in response.headers.get_list("set-cookie"):
        cookie_name, _, rest = header.partition("=")
        if cookie_name == name:
            return rest.split(";", 1)[0]
    raise AssertionError(f"no {name} cookie in {response.headers}")


@pytest.fixture
def default_start(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[str, str]]:
    """``serve --workers 2`` with no session secret configured: (base URL, admin key)."""
    monkeypatch.delenv("AACN_SESSION_SECRET", raising=False)
    monkeypatch.delenv("AACN_SESSION_SECRET_FILE", raising=False)
    # the served processes run this checkout's code
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    with console_server(tmp_path, "--workers", "2") as (_, base, key, log):
        yield base, key
        text = log.read_text()
        assert "AACN_SESSION_SECRET is not set: this start generated one" in text


def test_twenty_of_twenty_sign_ins_on_a_default_two_worker_start(
    default_start: tuple[str, str],
) -> None:
    base, key = default_start
    ready = httpx.get(base + "/readyz", timeout=10).json()
    assert ready["session_secret"] == "file"
    signed_in = 0
    pages = 0
    for _ in range(SIGN_INS):
        # a new connection each time: a fresh client, "Connection: close"
        with httpx.Client(base_url=base, timeout=30, headers={"Connection": "close"}) as c:
            form = c.get("/v1/session", params={"next": "/v1/reports"})
            assert form.status_code == 200
            csrf = _cookie(form, "aacn_login_csrf")
        with httpx.Client(base_url=base, timeout=30, headers={"Connection": "close"}) as c:
            r = c.post(
                "/v1/session",
                data={"csrf_token": csrf_token(form.text), "api_key": key, "next": "/v1/reports"},
                headers={"Cookie": f"aacn_login_csrf={csrf}"},
            )
            signed_in += r.status_code == 303
            assert r.status_code == 303, r.text[:500]
            session = _cookie(r, "aacn_session")
        with httpx.Client(base_url=base, timeout=30, headers={"Connection": "close"}) as c:
            page = c.get("/v1/reports", headers={"Cookie": f"aacn_session={session}"})
            pages += page.status_code == 200
    assert (signed_in, pages) == (SIGN_INS, SIGN_INS)
