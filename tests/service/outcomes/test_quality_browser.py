"""The quality page in a real browser: headless Chromium driven by Playwright, the
service as a process of its own (``tests/service/browser_support.py``); outcomes are
linked over the API by the registry key and the auditor reads the page."""

from __future__ import annotations

from typing import Any

import httpx2 as httpx
import pytest

from tests.service import browser_support
from tests.service.browser_support import Served, new_tab, shot

pytestmark = pytest.mark.browser

#: The harness's fixtures (module-scoped: this module's own browser and service).
chromium = browser_support.chromium
served = browser_support.served
signed_in = browser_support.signed_in


def test_the_quality_page_for_the_auditor(served: Served, signed_in: Any) -> None:
    """Outcomes linked over the API by the registry key, the auditor reads the quality page:
    figures, the drift alarm, the reliability plot, the filters; no console errors."""
    registry = {"Authorization": f"Bearer {served.keys['registry']}"}
    for name, iss, mais in (("head-injury", 17, 3), ("minor", 4, 2)):
        case = served.cases[name]
        seat = case["result"]["occupants"][0]["seat"]
        r = httpx.put(
            f"{served.base}/v1/cases/{case['case_id']}/occupants/{seat}/outcome",
            json={
                "iss": iss,
                "mais": mais,
                "died": False,
                "disposition": "admitted_ward",
                "source": "trauma_registry",
                "recorded_at": "2026-12-01T10:00:00Z",
            },
            headers=registry,
            timeout=30,
        )
        assert r.status_code == 201, r.text
    tab = new_tab(signed_in)
    page = tab.page
    response = page.goto(f"{served.base}/v1/quality/report")
    assert response.status == 200
    assert page.locator("h1").inner_text() == "Triage quality against linked outcomes"
    assert page.locator("#drift h2").inner_text() == "Drift alarm: insufficient"
    assert "Too few linked outcomes" in page.locator("#drift").inner_text()
    overall = page.locator("#overall").inner_text()
    assert f"{len(served.cases)} cases" in overall
    plot = page.locator("#overall svg.reliability")
    assert plot.is_visible()
    assert plot.locator("circle.point").count() == 2  # two linked occupants, two groups
    shot(page, "quality")
    page.select_option("select[name=crash_mode]", "frontal")
    page.click("#filters button[type=submit]")
    page.wait_for_url("**/v1/quality/report?*crash_mode=frontal*")
    assert page.locator("select[name=crash_mode]").input_value() == "frontal"
    assert tab.problems == []
    page.close()
