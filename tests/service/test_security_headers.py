"""/docs has the pages' security headers; HSTS where TLS ends."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient

from service.security_headers import HSTS_VALUE
from tests.paths import ROOT
from tests.service.browser_support import chromium  # noqa: F401  (the fixture)
from tests.support import ApiClient, console_server


def test_docs_sends_a_policy_that_allows_only_its_own_script(api: ApiClient) -> None:
    r = api.client.get("/docs")
    assert r.status_code == 200
    csp = r.headers["content-security-policy"]
    assert r.headers["x-frame-options"] == "DENY"
    assert r.headers["referrer-policy"] == "same-origin"
    assert "default-src 'none'" in csp
    assert "frame-ancestors 'none'" in csp
    nonce = re.search(r"'nonce-([^']+)'", csp)
    assert nonce is not None
    # every inline script carries the nonce; the others come from the service
    scripts = re.findall(r"<script([^>]*)>", r.text)
    assert scripts, r.text
    for attrs in scripts:
        assert f'nonce="{nonce.group(1)}"' in attrs or 'src="/docs/static/' in attrs, attrs
    for bad in ("unsafe-eval", "http:", "https:", " * ", "script-src 'self' 'unsafe-inline'"):
        assert bad not in csp
    # a fresh nonce per response
    again = api.client.get("/docs").headers["content-security-policy"]
    assert again != csp


def test_hsts_only_where_tls_ends(api: ApiClient) -> None:
    secure = TestClient(api.client.app, base_url="https://testserver")
    for path in ("/livez", "/docs", "/v1/session"):
        assert secure.get(path).headers["strict-transport-security"] == HSTS_VALUE
        assert "strict-transport-security" not in api.client.get(path).headers  # plain HTTP


@pytest.fixture
def served_base(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    with console_server(tmp_path, "--workers", "1") as (_, base, _key, _log):
        yield base


def test_swagger_ui_still_works_under_its_policy(chromium: Any, served_base: str) -> None:  # noqa: F811
    page = chromium.new_page()
    violations: list[str] = []
    page.on(
        "console",
        lambda m: violations.append(m.text) if "Content Security Policy" in m.text else None,
    )
    try:
        page.goto(served_base + "/docs", wait_until="networkidle", timeout=60_000)
        # the operations are drawn: the bundle ran, started by the nonce'd script
        page.wait_for_selector(".opblock-post", timeout=60_000)
        assert "/v1/cases" in page.locator(".opblock-post").first.inner_text()
    finally:
        page.close()
    assert violations == []
