"""The case pages in a real browser: headless Chromium driven by Playwright.

The service runs as a real process (``python -m service.cli serve`` on a free
port, a temporary SQLite file, keys made with ``keys create``), real cases are
POSTed to it, and Chromium signs in through the form like a dispatcher would
(the harness: ``tests/service/browser_support.py``). These tests are skipped, with
the reason, only when no Chromium can be started. A screenshot of each page goes to
``test-artifacts/screenshots/`` (or ``$AACN_TEST_ARTIFACTS/screenshots/``). The
quality page's: ``tests/service/outcomes/test_quality_browser.py``.
"""

from __future__ import annotations

from typing import Any

import pytest

from tests.service import browser_support
from tests.service.browser_support import Served, new_tab, screenshot_dir, shot, sign_in
from tests.service.pages_support import TIER_VERDICTS

pytestmark = pytest.mark.browser

#: The harness's fixtures (module-scoped: this module's own browser and service).
chromium = browser_support.chromium
served = browser_support.served
signed_in = browser_support.signed_in

#: The AIS 0 fill of report.css (a region not at risk).
AIS0_FILL = "rgb(236, 239, 241)"

#: The banner's border colour of each risk tier (report.css --flag, --moderate, --clear).
TIER_COLOURS = {
    "high": "rgb(165, 14, 14)",
    "moderate": "rgb(138, 70, 0)",
    "none": "rgb(11, 79, 138)",
}
#: The served case of each tier (its stored tier is checked).
TIER_CASE_NAMES = {"high": "near-side-56", "moderate": "head-injury", "none": "minor"}
#: Each tier's symbol (colour is never the only signal).
TIER_SYMBOLS = {"high": "\u25b2", "moderate": "\u25c6", "none": "\u25cf"}


def _pct(p: float) -> str:
    return f"{100 * p:.1f} %"


def test_case_page_shows_the_recommendation_and_interval_without_console_errors(
    served: Served, signed_in: Any
) -> None:
    tab = new_tab(signed_in)
    page = tab.page
    response = page.goto(served.url("head-injury"))
    assert response.status == 200
    triage = served.cases["head-injury"]["result"]["triage"]
    decision = page.locator("#decision")
    assert triage["tier"] == "moderate"
    assert decision.locator(".verdict").inner_text() == TIER_VERDICTS["moderate"]
    assert triage["recommendation"] in decision.inner_text()
    assert decision.locator(".probability").inner_text() == _pct(triage["probability"])
    low, high = triage["probability_ci95"]
    assert decision.locator(".interval").inner_text() == f"{_pct(low)} to {_pct(high)}"
    assert decision.locator(".threshold-value").inner_text() == _pct(triage["threshold"])
    assert "ISS 15+" in decision.inner_text()
    assert "US towaway crashes" in decision.inner_text()
    assert "since the crash" in decision.locator(".since").inner_text()
    # the interval is drawn as a bar against the threshold
    ci = decision.locator("svg.pbar rect.ci")
    assert ci.is_visible()
    assert float(ci.get_attribute("width") or 0) > 1
    assert decision.locator("svg.pbar line.threshold").count() == 1
    # the stylesheet loaded under the CSP: the decision is framed in its tier's colour
    border = decision.evaluate("e => getComputedStyle(e).borderTopColor")
    assert border == TIER_COLOURS["moderate"]
    shot(page, "case-head-injury")
    assert tab.problems == []
    page.close()


@pytest.mark.parametrize("tier", ["high", "moderate", "none"])
def test_the_banner_shows_each_tier_in_its_colour_symbol_and_words(
    served: Served, signed_in: Any, tier: str
) -> None:
    name = TIER_CASE_NAMES[tier]
    triage = served.cases[name]["result"]["triage"]
    assert triage["tier"] == tier, f"{name} must land in the {tier} tier"
    tab = new_tab(signed_in)
    page = tab.page
    assert page.goto(served.url(name)).status == 200
    decision = page.locator("#decision")
    assert decision.get_attribute("data-tier") == tier
    assert decision.locator(".verdict").inner_text() == TIER_VERDICTS[tier]
    assert decision.locator(".headline .symbol").inner_text() == TIER_SYMBOLS[tier]
    assert decision.locator(".recommendation").inner_text() == triage["recommendation"]
    assert "Level I" not in page.content()
    for side in ("Top", "Left"):
        colour = decision.evaluate(f"e => getComputedStyle(e).border{side}Color")
        assert colour == TIER_COLOURS[tier], (side, colour)
    verdict = decision.locator(".verdict").evaluate("e => getComputedStyle(e).color")
    assert verdict == TIER_COLOURS[tier]
    card = page.locator("#occupant-0")
    assert card.get_attribute("data-tier") == tier
    assert card.evaluate("e => getComputedStyle(e).borderLeftColor") == TIER_COLOURS[tier]
    shot(page, f"banner-{tier}")
    assert tab.problems == []
    page.close()


def test_the_banner_summarises_each_occupants_tier(served: Served, signed_in: Any) -> None:
    result = served.cases["mixed-tiers"]["result"]
    tiers = [o["triage"]["tier"] for o in result["occupants"]]
    assert tiers == ["high", "moderate"]
    tab = new_tab(signed_in)
    page = tab.page
    page.goto(served.url("mixed-tiers"))
    decision = page.locator("#decision")
    assert decision.get_attribute("data-tier") == "high", "the worst occupant's"
    items = decision.locator(".occupant-tiers li")
    assert items.count() == 2
    for k, tier in enumerate(tiers):
        item = items.nth(k)
        assert item.get_attribute("data-tier") == tier
        assert item.is_visible()
        assert item.evaluate("e => getComputedStyle(e).color") == TIER_COLOURS[tier]
        assert f"{tier} risk" in item.inner_text()
    shot(page, "banner-occupants")
    assert tab.problems == []
    page.close()


def test_the_body_map_marks_the_head_region(served: Served, signed_in: Any) -> None:
    tab = new_tab(signed_in)
    page = tab.page
    page.goto(served.url("head-injury"))
    ais = served.cases["head-injury"]["result"]["occupants"][0]["region_ais"]
    head = page.locator("#occupant-0 svg.bodymap:not(.riskmap) g[data-region=head_neck]")
    assert head.get_attribute("data-ais") == str(ais["head_neck"])
    assert f"ais-{ais['head_neck']}" in (head.get_attribute("class") or "").split()
    assert head.locator("text.ais-label").text_content() == str(ais["head_neck"])
    skull = head.locator("circle")
    assert skull.is_visible()
    assert skull.evaluate("e => getComputedStyle(e).fill") != AIS0_FILL
    for region, level in ais.items():
        shape = page.locator(
            f"#occupant-0 svg.bodymap:not(.riskmap) g[data-region={region}] > :not(text)"
        )
        fill = shape.first.evaluate("e => getComputedStyle(e).fill")
        if region != "external":
            assert (fill == AIS0_FILL) == (level == 0), (region, level, fill)
    page.locator("#occupant-0 [data-layer=occupant-model]").screenshot(
        path=str(screenshot_dir() / "bodymap-head-injury.png")
    )
    assert tab.problems == []
    page.close()


#: The "no region risk" fill of report.css.
RISK_NA_FILL = AIS0_FILL


def _store_region_risk(served: Served, name: str, region_risk: dict[str, Any] | None) -> None:
    """Give a stored case's first occupant a field region risk, in the served database."""
    import json

    from sqlalchemy import create_engine
    from sqlalchemy.orm import Session

    from service.db.tables import Case

    engine = create_engine(served.database_url)
    try:
        with Session(engine) as session, session.begin():
            case = session.get(Case, served.cases[name]["case_id"])
            assert case is not None
            result = json.loads(json.dumps(case.result))
            result["occupants"][0]["region_risk"] = region_risk
            case.result = result
    finally:
        engine.dispose()


def test_the_body_map_shows_region_risk_first_and_the_physics_layer_labelled(
    served: Served, signed_in: Any
) -> None:
    from tests.service.pages.test_pages_regions import REGION_RISK

    occ = served.cases["head-injury"]["result"]["occupants"][0]
    given = occ.get("region_risk") or None
    tab = new_tab(signed_in)
    page = tab.page
    page.goto(served.url("head-injury"))
    risk = page.locator("#occupant-0 [data-layer=region-risk]")
    physics = page.locator("#occupant-0 [data-layer=occupant-model]")
    assert risk.locator("h4").text_content() == "Body regions at risk: field region risk"
    assert (physics.locator("h4").text_content() or "").startswith("Occupant model (physics)")
    skill = physics.locator("p[data-skill]")
    assert skill.is_visible()
    assert "real occupants" in (skill.text_content() or "")
    # the region risk layer comes first
    assert risk.bounding_box()["y"] < physics.bounding_box()["y"]
    svg = risk.locator("svg.riskmap")
    if given is None:  # an engine without the field region models: the page says so
        assert "unavailable" in (svg.get_attribute("class") or "")
        assert "No field region risk" in (risk.text_content() or "")
    shot(page, "bodymap-layers-" + ("with" if given else "without") + "-region-risk")
    # the same page with a stored region risk: every region coloured, the interval on hover
    _store_region_risk(served, "head-injury", given or REGION_RISK)
    page.goto(served.url("head-injury"))
    svg = page.locator("#occupant-0 svg.riskmap")
    assert "unavailable" not in (svg.get_attribute("class") or "")
    for region, r in (given or REGION_RISK).items():
        g = svg.locator(f"g[data-region={region}]")
        fill = g.locator("> :not(title)").first.evaluate("e => getComputedStyle(e).fill")
        assert (fill == RISK_NA_FILL) == (r["probability"] < 0.01), (region, fill)
        title = g.locator("title").text_content() or ""
        low = r["probability_ci95"][0]
        # the page writes a probability under 0.1 % as "under 0.1 %"
        assert (f"{100 * low:.1f} %" if low >= 0.001 else "under 0.1 %") in title, title
        # (the face lies on the head, the spine on the trunk: hover without the hit test)
        g.locator("> :not(title)").first.hover(force=True)
    page.locator("#occupant-0 .bodylayers").screenshot(
        path=str(screenshot_dir() / "bodymap-region-risk-and-physics.png")
    )
    _store_region_risk(served, "head-injury", given)  # as it was, for the other tests
    assert tab.problems == []
    page.close()


def test_a_56_kmh_near_side_case_shows_no_ais_6_and_says_why(
    served: Served, signed_in: Any
) -> None:
    """The body map's case: a 56 km/h near-side crash with the side airbags deployed."""
    tab = new_tab(signed_in)
    page = tab.page
    page.goto(served.url("near-side-56"))
    head = page.locator("#occupant-0 svg.bodymap:not(.riskmap) g[data-region=head_neck]")
    assert head.get_attribute("data-ais") == "5"
    capped = page.locator("#occupant-0 li[data-code=occupant_model_ais_capped]")
    assert capped.is_visible()
    assert "cannot represent AIS 6" in (capped.text_content() or "")
    assert page.locator("#occupant-0 li[data-code=side_beyond_tested_severity]").is_visible()
    assert page.locator("#occupant-0 p[data-skill]").is_visible()
    shot(page, "case-near-side-56kmh-side-airbags")
    assert tab.problems == []
    page.close()


def test_every_case_page_shows_the_stored_numbers(served: Served, signed_in: Any) -> None:
    tab = new_tab(signed_in)
    page = tab.page
    for name, stored in served.cases.items():
        assert page.goto(served.url(name)).status == 200
        result = stored["result"]
        data = page.eval_on_selector("#decision", "e => ({...e.dataset})")
        assert float(data["probability"]) == result["triage"]["probability"]
        assert [float(data["ciLow"]), float(data["ciHigh"])] == result["triage"]["probability_ci95"]
        assert float(data["threshold"]) == result["triage"]["threshold"]
        cards = page.eval_on_selector_all("section.occupant", "es => es.map(e => ({...e.dataset}))")
        assert len(cards) == len(result["occupants"])
        for card, occ in zip(cards, result["occupants"], strict=True):
            assert card["seat"] == occ["seat"]
            assert float(card["probability"]) == occ["triage"]["probability"]
            assert [float(card["ciLow"]), float(card["ciHigh"])] == occ["triage"][
                "probability_ci95"
            ]
        models = page.eval_on_selector_all(
            "#audit tr[data-model]", "es => es.map(e => [e.dataset.model, e.dataset.version])"
        )
        assert dict(models) == {k: v["version"] for k, v in stored["models"].items()}
        assert page.locator("#audit .client").inner_text() == stored["client_name"]
        assert page.locator("#crash svg.plot polyline").count() >= 1
        assert page.locator("#crash svg.car g.pdof").get_attribute("data-pdof-deg") == str(
            result["pulse"]["pdof_deg"]
        )
        shot(page, f"case-{name}")
    assert tab.problems == []
    page.close()


def test_the_case_list_filters(served: Served, signed_in: Any) -> None:
    tab = new_tab(signed_in)
    page = tab.page
    page.goto(f"{served.base}/v1/reports")

    def listed() -> list[str]:
        return page.eval_on_selector_all("tr[data-case-id]", "es => es.map(e => e.dataset.caseId)")

    ids = {name: c["case_id"] for name, c in served.cases.items()}
    assert sorted(listed()) == sorted(ids.values())
    shot(page, "list-all")
    page.select_option("select[name=iss15_plus]", "false")
    page.click("#filters button[type=submit]")
    page.wait_for_url("**iss15_plus=false**")
    not_flagged = [
        c["case_id"] for c in served.cases.values() if not c["result"]["triage"]["iss15_plus"]
    ]
    assert ids["minor"] in not_flagged
    assert len(not_flagged) < len(ids), "the flagged cases are filtered out"
    assert sorted(listed()) == sorted(not_flagged)
    shot(page, "list-filtered-no-indication")
    page.select_option("select[name=iss15_plus]", "")
    page.select_option("select[name=tier]", "high")
    page.click("#filters button[type=submit]")
    page.wait_for_url("**tier=high**")
    high = [c["case_id"] for c in served.cases.values() if c["result"]["triage"]["tier"] == "high"]
    assert sorted(high) == sorted([ids["near-side-56"], ids["mixed-tiers"]])
    assert sorted(listed()) == sorted(high)
    rows = page.locator("tr[data-case-id]")
    for k in range(rows.count()):
        assert rows.nth(k).locator("td[data-label=Decision]").inner_text().strip() == (
            "\u25b2 High risk"
        )
    shot(page, "list-filtered-high-risk")
    page.select_option("select[name=tier]", "")
    page.select_option("select[name=iss15_plus]", "")
    page.select_option("select[name=impact_mode]", "near_side")
    page.click("#filters button[type=submit]")
    page.wait_for_url("**impact_mode=near_side**")
    assert sorted(listed()) == sorted([ids["side-edr"], ids["near-side-56"], ids["mixed-tiers"]])
    shot(page, "list-filtered-near-side")
    page.click(f"tr[data-case-id='{ids['side-edr']}'] a")
    page.wait_for_url(served.url("side-edr"))
    assert page.locator("#occupant-1").get_attribute("data-seat") == "front_passenger"
    assert tab.problems == []
    page.close()


def test_an_unauthenticated_visit_is_refused(chromium: Any, served: Served) -> None:
    context = chromium.new_context()
    tab = new_tab(context)
    page = tab.page
    stored = served.cases["head-injury"]
    response = page.goto(served.url("head-injury"))
    assert response.status == 401
    assert page.locator("#login").is_visible()
    html = page.content()
    assert stored["event_id"] not in html
    assert _pct(stored["result"]["triage"]["probability"]) not in html
    assert page.locator("#decision").count() == 0
    shot(page, "refused-sign-in")
    # the only console error is the refused document itself
    assert all("401" in p for p in tab.problems), tab.problems
    # signing in from that form leads back to the case
    tab.problems.clear()
    page.fill("#api_key", served.keys["auditor"])
    page.click("#login button[type=submit]")
    page.wait_for_url(served.url("head-injury"))
    assert page.locator("#decision .verdict").inner_text() == TIER_VERDICTS["moderate"]
    assert tab.problems == []
    context.close()


def test_a_submitter_key_cannot_sign_in(chromium: Any, served: Served) -> None:
    context = chromium.new_context()
    tab = new_tab(context)
    tab.page.goto(f"{served.base}/v1/session")
    tab.page.fill("#api_key", served.keys["submitter"])
    tab.page.click("#login button[type=submit]")
    assert "auditor or admin" in tab.page.locator("#login p[role=alert]").inner_text()
    assert tab.page.locator("#plain-http").count() == 0, "127.0.0.1 keeps Secure cookies"
    assert not [c for c in context.cookies() if c["name"] == "aacn_session"]
    context.close()


def test_small_screen_and_print(chromium: Any, served: Served) -> None:
    context = chromium.new_context(
        viewport={"width": 390, "height": 844}, device_scale_factor=2, is_mobile=True
    )
    tab = new_tab(context)
    page = tab.page
    sign_in(tab, served.base, served.keys["auditor"])
    for name in ("head-injury", "side-edr"):
        page.goto(served.url(name))
        width = page.evaluate("[document.documentElement.scrollWidth, window.innerWidth]")
        assert width[0] <= width[1], f"horizontal scroll on a small screen: {width}"
        assert page.locator("#occupant-0 svg.riskmap").is_visible()
        assert page.locator("#occupant-0 svg.bodymap:not(.riskmap)").is_visible()
        shot(page, f"case-{name}-small-screen")
    page.emulate_media(media="print")
    page.goto(served.url("head-injury"))
    assert page.locator(".topbar nav").is_hidden()
    assert page.locator("#decision").is_visible()
    shot(page, "case-head-injury-print")
    page.pdf(path=str(screenshot_dir() / "case-head-injury.pdf"))
    assert tab.problems == []
    context.close()


def test_logout_ends_the_session(chromium: Any, served: Served) -> None:
    context = chromium.new_context()
    tab = new_tab(context)
    page = tab.page
    sign_in(tab, served.base, served.keys["auditor"])
    cookie = next(c for c in context.cookies() if c["name"] == "aacn_session")
    assert cookie["httpOnly"]
    assert cookie["secure"]
    assert cookie["sameSite"] == "Strict"
    page.click(".topbar button[type=submit]")
    page.wait_for_url(f"{served.base}/v1/session**")
    assert page.goto(served.url("minor")).status == 401
    context.close()
