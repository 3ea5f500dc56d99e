"""The body map's two layers on the case page, through the ASGI app.

Layer one colours each AIS body region by the stored field region risk
(``occupants[].region_risk.<region> = {probability, probability_ci95, ais_level}``);
layer two is the occupant model's region AIS, labelled and stated with its measured
skill. A stored answer without ``region_risk`` renders with the first layer marked
unavailable. tests/service/pages/test_pages_browser.py drives the same page in Chromium.
"""

from __future__ import annotations

import json
from typing import Any

from service.db.tables import Case
from service.pages.regions import RISK_BANDS, SKILL_PATH, physics_skill
from tests.service.pages_support import Page, head_injury, minor, near_side_56
from tests.support import ApiClient, post_case, stored_case

#: A field region risk of each region, shaped as the wire gives it (probabilities
#: chosen to fall in every colour band).
REGION_RISK: dict[str, dict[str, Any]] = {
    "head": {"probability": 0.42, "probability_ci95": [0.30, 0.55], "ais_level": 3},
    "face": {"probability": 0.02, "probability_ci95": [0.01, 0.04], "ais_level": 2},
    "neck": {"probability": 0.004, "probability_ci95": [0.002, 0.008], "ais_level": 2},
    "thorax": {"probability": 0.12, "probability_ci95": [0.08, 0.17], "ais_level": 3},
    "abdomen": {"probability": 0.05, "probability_ci95": [0.03, 0.08], "ais_level": 3},
    "spine": {"probability": 0.03, "probability_ci95": [0.02, 0.05], "ais_level": 3},
    "upper_extremity": {"probability": 0.06, "probability_ci95": [0.04, 0.09], "ais_level": 3},
    "lower_extremity": {"probability": 0.09, "probability_ci95": [0.06, 0.13], "ais_level": 3},
}


def _page(api: ApiClient, case_id: str) -> Page:
    r = api.client.get(f"/v1/cases/{case_id}/report", headers=api.headers("auditor"))
    assert r.status_code == 200, r.text
    return Page(r.text)


def _edit_occupant(api: ApiClient, case_id: str, **fields: Any) -> None:
    """Rewrite the stored answer's first occupant (a stored shape, as an older or newer case)."""
    app: Any = api.client.app
    with app.state.ctx.sessions.begin() as session:
        case = session.get(Case, case_id)
        result = json.loads(json.dumps(case.result))
        result["occupants"][0].update(fields)
        case.result = result


def _band(p: float) -> str:
    return [css for lower, css, _ in RISK_BANDS if p >= lower][-1]


def test_each_region_is_coloured_by_its_region_risk_with_the_interval_on_hover(
    api: ApiClient,
) -> None:
    case_id = post_case(api, head_injury())["case_id"]
    _edit_occupant(api, case_id, region_risk=REGION_RISK)
    page = _page(api, case_id)
    svg = page.one("svg", within="occupant-0", **{"class": "bodymap riskmap"})
    assert "unavailable" not in svg.attrs["class"]
    assert {_band(r["probability"]) for r in REGION_RISK.values()} == {b[1] for b in RISK_BANDS}
    for region, risk in REGION_RISK.items():
        g = page.one("g", within="occupant-0", data_region=region, data_probability="*")
        assert g.attrs["class"].split() == ["region", _band(risk["probability"])]
        assert float(g.attrs["data-low"]) == risk["probability_ci95"][0]
        assert float(g.attrs["data-high"]) == risk["probability_ci95"][1]
        (title,) = [e for e in page.elements if e.tag == "title" and g.index < e.index][:1]
        text = page.text(title)
        assert f"AIS {risk['ais_level']}+" in text
        assert f"{100 * risk['probability']:.1f} %" in text
        assert f"{100 * risk['probability_ci95'][0]:.1f} %" in text
        row = page.one("tr", within="occupant-0", data_region=region, data_probability="*")
        assert row.attrs["class"] == _band(risk["probability"])
    # the neck's outcome is AIS 2+, named
    neck = page.one("tr", within="occupant-0", data_region="neck", data_probability="*")
    assert "(AIS 2+)" in page.text(neck)


def test_an_answer_without_region_risk_says_so_and_keeps_the_physics_layer(
    api: ApiClient,
) -> None:
    case_id = post_case(api, head_injury())["case_id"]
    _edit_occupant(api, case_id, region_risk=None)  # as an answer stored before region risk
    page = _page(api, case_id)
    svg = page.one("svg", within="occupant-0", **{"class": "bodymap riskmap unavailable"})
    assert "not in this answer" in svg.attrs["aria-label"]
    risk_block = page.one("div", within="occupant-0", data_layer="region-risk")
    texts = [page.text(e) for e in page.all("p", within="occupant-0") if e.index > risk_block.index]
    assert any("No field region risk in this answer" in t for t in texts)
    physics = page.one("div", within="occupant-0", data_layer="occupant-model")
    heading = [e for e in page.all("h4", within="occupant-0") if e.index > physics.index][0]
    assert page.text(heading).startswith("Occupant model (physics)")


def test_the_physics_layer_states_its_measured_skill_from_the_report(api: ApiClient) -> None:
    doc = json.loads(SKILL_PATH.read_text(encoding="utf-8"))
    case_id = post_case(api, head_injury())["case_id"]
    page = _page(api, case_id)
    (skill,) = page.all("p", within="occupant-0", data_skill="")
    text = page.text(skill)
    assert text == physics_skill().text
    for region in ("head", "thorax", "abdomen"):
        assert f"{region} {doc['auc_weighted'][region]['auc_body_map']:.2f}" in text
        assert f"delta-V alone {doc['auc_weighted'][region]['auc_delta_v']:.2f}" in text
    assert f"{doc['occupants']:,} real occupants" in text
    assert page.all("p", within="occupant-0", data_ais6="") == []


def test_an_ais_6_stored_before_the_cap_says_how_often_the_field_agreed(api: ApiClient) -> None:
    doc = json.loads(SKILL_PATH.read_text(encoding="utf-8"))
    case_id = post_case(api, minor())["case_id"]
    _edit_occupant(api, case_id, region_ais={"head_neck": 6, "face": 0, "chest": 2})
    page = _page(api, case_id)
    (note,) = page.all("p", within="occupant-0", data_ais6="")
    text = page.text(note)
    assert f"{100 * doc['curves_ais6']['real_mais5']:.0f} % had any AIS 5+ injury" in text
    assert f"{100 * doc['curves_ais6']['died']:.0f} % died" in text


def test_a_56_kmh_near_side_crash_with_side_airbags_is_never_reported_at_ais_6(
    api: ApiClient,
) -> None:
    """The issue's case: head/neck AIS 6 and ISS 75 for a near-side driver with side airbags."""
    stored = stored_case(api, post_case(api, near_side_56())["case_id"])["result"]
    occ = stored["occupants"][0]
    assert occ["impact_mode"] == "near_side"
    assert max(occ["region_ais"].values()) <= 5
    assert occ["region_ais"]["head_neck"] == 5
    assert occ["iss"]["estimate"] < 75
    ci = occ["iss"]["ci95"]
    assert ci[0] <= occ["iss"]["estimate"] <= ci[1]
    codes = {a["code"] for a in stored["assumptions"] if a.get("occupant") == 0}
    assert {"occupant_model_ais_capped", "side_beyond_tested_severity"} <= codes
