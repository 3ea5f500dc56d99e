"""The browser tests' harness: a headless Chromium driven by Playwright, and the service
as a process of its own with keys and seven real cases.

The service runs as a real process (``python -m service.cli serve`` on a free
port, a temporary SQLite file, keys made with ``keys create``), real cases are
POSTed to it, and Chromium signs in through the form like a dispatcher would.

Chromium: ``$AACN_TEST_CHROMIUM``, else Debian's ``chromium`` on the PATH, else
a Playwright-managed build. The tests that take the ``chromium`` fixture are skipped,
with the reason, only when none of them can be started. A screenshot of each page goes
to ``test-artifacts/screenshots/`` (or ``$AACN_TEST_ARTIFACTS/screenshots/``).

A test module takes the fixtures by importing them (``chromium``, ``served``,
``signed_in``); module-scoped, each module gets its own.
"""

from __future__ import annotations

import os
import secrets
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NoReturn

import httpx2 as httpx
import pytest

from tests.paths import ROOT as REPO
from tests.service.pages_support import (
    acceleration,
    head_injury,
    minor,
    mixed_tiers,
    near_side_56,
    rear_seat_rollover,
    side_edr,
)
from tests.support import create_key, free_port, wait_ready

#: Flags for Chromium on a closed network and as root in a container: no
#: sandbox, no GPU, no background traffic (which would flood refused connections).
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def screenshot_dir() -> Path:
    """Where the screenshots go (created)."""
    base = os.environ.get("AACN_TEST_ARTIFACTS")
    path = (Path(base) if base else REPO / "test-artifacts") / "screenshots"
    path.mkdir(parents=True, exist_ok=True)
    return path


def _chromium_candidates() -> list[str | None]:
    found: list[str | None] = []
    given = os.environ.get("AACN_TEST_CHROMIUM")
    if given:
        found.append(given)
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        path = shutil.which(name)
        if path and path not in found:
            found.append(path)
    found.append(None)  # a Playwright-managed build, where `playwright install` could fetch one
    return found


#: Set (to 1) where the browser tests must run, as in CI (``.ci/run`` installs Chromium):
#: no Chromium is then a failure, not a skip.
REQUIRE_BROWSER_ENV = "AACN_REQUIRE_BROWSER"


def _no_browser(reason: str) -> NoReturn:
    """Skip, on a machine without Chromium; fail where the browser tests are required."""
    if os.environ.get(REQUIRE_BROWSER_ENV) == "1":
        pytest.fail(f"{REQUIRE_BROWSER_ENV}=1 but {reason}")
    pytest.skip(reason)


@pytest.fixture(scope="module")
def chromium() -> Iterator[Any]:
    """A running headless Chromium, or a skip (a failure where required) that says why
    none could be started."""
    try:
        from playwright.sync_api import Error, sync_playwright
    except ImportError as exc:  # playwright is in the test extra
        _no_browser(f"no Chromium can be started: the playwright package is missing ({exc})")
    manager = sync_playwright().start()
    reasons = []
    browser = None
    for exe in _chromium_candidates():
        try:
            browser = manager.chromium.launch(
                executable_path=exe, args=CHROMIUM_ARGS, headless=True, timeout=60_000
            )
            break
        except Error as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            reasons.append(f"{exe or 'Playwright-managed Chromium'}: {first}")
    if browser is None:
        manager.stop()
        _no_browser("no Chromium can be started (apt-get install chromium): " + "; ".join(reasons))
    try:
        yield browser
    finally:
        browser.close()
        manager.stop()


# ---------------------------------------------------------------- the served service


@dataclass
class Served:
    base: str
    keys: dict[str, str]
    #: the served process's database (a test may rewrite a stored case in it)
    database_url: str = ""
    #: name -> the stored case (GET /v1/cases/{id})
    cases: dict[str, dict[str, Any]] = field(default_factory=dict)

    def url(self, name: str) -> str:
        return f"{self.base}/v1/cases/{self.cases[name]['case_id']}/report"


@pytest.fixture(scope="module")
def served(chromium: Any, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Served]:
    """The service as a process of its own, with keys and seven real cases."""
    tmp = tmp_path_factory.mktemp("served")
    env = {
        **os.environ,
        "AACN_DATABASE_URL": f"sqlite:///{tmp / 'served.db'}",
        "AACN_SESSION_SECRET": secrets.token_urlsafe(32),
        "AACN_LOG_LEVEL": "WARNING",
    }
    cli = [sys.executable, "-m", "service.cli"]

    def key(role: str, name: str) -> str:
        return create_key(cli, env, role, name, timeout_s=180.0)

    keys = {
        "auditor": key("auditor", "ems-supervisor"),
        "submitter": key("submitter", "call-center-north"),
        "registry": key("registry", "county-trauma-registry"),
    }
    port = free_port()
    log = tmp / "server.log"
    with log.open("w") as sink:
        server = subprocess.Popen(
            [*cli, "serve", "--port", str(port)], env=env, stdout=sink, stderr=subprocess.STDOUT
        )
    base = f"http://127.0.0.1:{port}"
    try:
        wait_ready(base, server, log, timeout_s=180)  # a cold start on a busy machine
        out = Served(base=base, keys=keys, database_url=env["AACN_DATABASE_URL"])
        submit = {"Authorization": f"Bearer {keys['submitter']}"}
        audit = {"Authorization": f"Bearer {keys['auditor']}"}
        makers: dict[str, Callable[[], dict[str, Any]]] = {
            "head-injury": head_injury,
            "minor": minor,
            "side-edr": side_edr,
            "rear-seat-rollover": rear_seat_rollover,
            "acceleration": acceleration,
            "near-side-56": near_side_56,
            "mixed-tiers": mixed_tiers,
        }
        for name, make in makers.items():
            r = httpx.post(base + "/v1/cases", json=make(), headers=submit, timeout=60)
            assert r.status_code == 201, r.text
            got = httpx.get(base + r.headers["location"], headers=audit, timeout=30)
            out.cases[name] = got.json()
        head = out.cases["head-injury"]["result"]["occupants"][0]["region_ais"]["head_neck"]
        assert head >= 2, "the head-injury case must have head/neck AIS 2 or more"
        yield out
    finally:
        server.terminate()
        server.wait(timeout=30)


# ---------------------------------------------------------------- pages


@dataclass
class Tab:
    """A page and the problems it reported (console errors, page errors, failed loads)."""

    page: Any
    problems: list[str]


def new_tab(context: Any) -> Tab:
    page = context.new_page()
    problems: list[str] = []
    page.on(
        "console",
        lambda m: problems.append(f"console {m.type}: {m.text}") if m.type == "error" else None,
    )
    page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
    # a load cut short by the next navigation (net::ERR_ABORTED) is not a fault of the page
    page.on(
        "requestfailed",
        lambda r: (
            problems.append(f"failed: {r.url} {r.failure}")
            if "ERR_ABORTED" not in str(r.failure)
            else None
        ),
    )
    page.on(
        "response",
        lambda r: (
            problems.append(f"{r.status}: {r.url}")
            if r.status >= 400 and r.request.resource_type != "document"
            else None
        ),
    )
    return Tab(page, problems)


def sign_in(tab: Tab, base: str, key: str) -> None:
    """Sign in through the form, as a person would."""
    tab.page.goto(f"{base}/v1/session")
    tab.page.fill("#api_key", key)
    tab.page.click("#login button[type=submit]")
    tab.page.wait_for_url(f"{base}/v1/reports")


@pytest.fixture(scope="module")
def signed_in(chromium: Any, served: Served) -> Iterator[Any]:
    """A browser context that signed in with the auditor key."""
    context = chromium.new_context(viewport={"width": 1280, "height": 900})
    tab = new_tab(context)
    sign_in(tab, served.base, served.keys["auditor"])
    assert tab.problems == []
    tab.page.close()
    try:
        yield context
    finally:
        context.close()


def shot(page: Any, name: str) -> Path:
    path = screenshot_dir() / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    assert path.stat().st_size > 1000
    return path
