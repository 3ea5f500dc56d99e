"""Risk tiers over HTTP: the answer, the store, the case list, the NEMSIS record, the
refusal to start, and cases stored before tiers read back (never altered)."""

from __future__ import annotations

import copy
import json
import uuid
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from lxml import etree
from pydantic import ValidationError
from sqlalchemy import MetaData, Table, select

from models.tiers import HIGH_RISK_THRESHOLD, ThresholdOrderError
from service.app import create_app
from service.auth import Role, create_api_key
from service.db import migrate
from service.db.session import make_engine
from service.db.tables import Case, CaseOccupant
from service.nemsis.validate import validate
from service.settings import Settings
from tests.service.pages_support import TIER_CASES, TIER_VERDICTS, Page
from tests.support import ApiClient, post_case, stored_case, summary

NS = {"n": "http://www.nemsis.org"}
AGENCY = {"agency_state_id": "C034", "agency_number": "351-C034P2", "agency_state": "09"}

#: What the service answered before tiers (field and second opinions alike).
OLD_FLAGGED_WORDS = (
    "Transport to a Level I trauma center: vehicle telemetry consistent with severe injury "
    "(ISS 15 or more likely)."
)
OLD_CLEAR_WORDS = (
    "No telemetry indication of ISS 15 or more: destination by EMS field assessment under "
    "local protocol."
)


def _decisions(result: dict[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """Every decision of a result with its place: the field decisions and second opinions."""
    out = [("triage", result["triage"])]
    for i, o in enumerate(result["occupants"]):
        out.append((f"occupants[{i}].triage", o["triage"]))
        for opinion in ("occupant_model", "baseline"):
            if o.get(opinion) is not None:
                out.append((f"occupants[{i}].{opinion}", o[opinion]))
    return out


# ------------------------------------------------------------------ the answer


@pytest.mark.parametrize("tier", ["high", "moderate", "none"])
def test_the_answer_carries_each_tier_and_never_level_one(api: ApiClient, tier: str) -> None:
    r = api.client.post("/v1/cases", json=TIER_CASES[tier](), headers=api.headers("submitter"))
    assert r.status_code == 201, r.text
    assert "Level I" not in r.text
    result = r.json()
    assert result["triage"]["tier"] == tier
    for place, d in _decisions(result):
        if place.endswith("triage"):
            assert d["high_threshold"] == HIGH_RISK_THRESHOLD, place
            p, t = d["probability"], d["threshold"]
            want = "high" if p >= max(t, 0.2) else "moderate" if p >= t else "none"
            assert d["tier"] == want, place
            assert d["iss15_plus"] == (want != "none"), place
        else:  # second opinions have no tier
            assert d["tier"] is None, place
            assert d["high_threshold"] is None, place
    v = result["vehicle"]
    p, t = v["probability"], result["triage"]["threshold"]
    assert (v["threshold"], v["high_threshold"]) == (t, HIGH_RISK_THRESHOLD)
    assert v["tier"] == ("high" if p >= 0.2 else "moderate" if p >= t else "none")
    # stored beside the operating threshold, and as columns for the list
    stored = stored_case(api, result["case_id"])
    assert stored["result"]["triage"] == result["triage"]
    assert stored["tiers_derived"] is False
    with api.client.app.state.ctx.sessions() as session:
        row = session.get(Case, result["case_id"])
        assert (row.tier, row.high_threshold) == (tier, HIGH_RISK_THRESHOLD)
        assert [o.tier for o in row.occupants] == [o["triage"]["tier"] for o in result["occupants"]]


def test_the_high_threshold_is_configurable_and_stored(sqlite_url: str, tmp_path: Path) -> None:
    """At 0.025 a 56 km/h frontal crash (P about 0.03 measured, moderate at the default) is
    high."""
    settings = Settings(
        database_url=sqlite_url, spool_path=tmp_path / "spool.db", high_risk_threshold=0.025
    )
    with TestClient(create_app(settings)) as client:
        _, key = create_api_key(client.app.state.ctx.sessions, name="s", role=Role.SUBMITTER)
        r = client.post("/v1/cases", json=summary(56.0), headers={"Authorization": f"Bearer {key}"})
        assert r.status_code == 201, r.text
        triage = r.json()["triage"]
        assert 0.025 <= triage["probability"] < 0.2
        assert (triage["tier"], triage["high_threshold"]) == ("high", 0.025)
        with client.app.state.ctx.sessions() as session:
            row = session.get(Case, r.json()["case_id"])
            assert (row.tier, row.high_threshold) == ("high", 0.025)


# ------------------------------------------------------------------ refusal to start


def test_a_high_threshold_below_the_override_is_refused_by_the_settings(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    with pytest.raises(ValidationError, match="high_risk_threshold"):
        Settings(triage_threshold=0.3)
    assert Settings(triage_threshold=0.1, high_risk_threshold=0.1).high_risk_threshold == 0.1
    monkeypatch.setenv("AACN_HIGH_RISK_THRESHOLD", "0.25")
    assert Settings().high_risk_threshold == 0.25


def test_a_high_threshold_below_the_operating_point_stops_the_start(
    sqlite_url: str, tmp_path: Path
) -> None:
    """sens85's threshold is about 0.018: 0.01 is refused, the app does not start."""
    settings = Settings(
        database_url=sqlite_url, spool_path=tmp_path / "spool.db", high_risk_threshold=0.01
    )
    with pytest.raises(ThresholdOrderError, match="sens85"):
        with TestClient(create_app(settings)):
            pass


def test_serve_with_workers_refuses_before_starting_them(
    sqlite_url: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: Any
) -> None:
    from service.cli.main import main
    from service.settings import get_settings

    monkeypatch.setenv("AACN_DATABASE_URL", sqlite_url)
    monkeypatch.setenv("AACN_HIGH_RISK_THRESHOLD", "0.01")
    monkeypatch.setenv("AACN_SPOOL_PATH", str(tmp_path / "spool.db"))
    get_settings.cache_clear()
    try:
        assert main(["serve", "--workers", "2", "--port", "9"]) == 2
    finally:
        get_settings.cache_clear()
    assert "high-risk threshold 0.0100" in capsys.readouterr().err


# ------------------------------------------------------------------ NEMSIS


@pytest.mark.parametrize("tier", ["high", "moderate", "none"])
def test_the_nemsis_record_follows_the_tier(api: ApiClient, tier: str) -> None:
    """Both flagged tiers carry eInjury.04 2904013; eInjury.23 (high probability of injury)
    says yes for the high tier alone; the narrative names the tier."""
    case_id = post_case(api, TIER_CASES[tier]())["case_id"]
    r = api.client.get(f"/v1/cases/{case_id}/nemsis", params=AGENCY, headers=api.headers("auditor"))
    assert r.status_code == 200, r.text
    assert validate(r.content) == []
    (pcr,) = etree.fromstring(r.content).findall("n:Header/n:PatientCareReport", NS)
    criteria = pcr.find("n:eInjury/n:eInjury.04", NS)
    assert criteria is not None
    assert (criteria.text == "2904013") == (tier != "none")
    high = pcr.find("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.23", NS)
    assert high is not None
    assert high.text == ("9923003" if tier == "high" else "9923001")
    narrative = pcr.find("n:eNarrative/n:eNarrative.01", NS)
    assert narrative is not None
    assert narrative.text is not None
    named = {"high": "HIGH RISK", "moderate": "MODERATE RISK", "none": "NO TELEMETRY INDICATION"}
    assert named[tier] in narrative.text
    assert [w for t, w in named.items() if t != tier and w in narrative.text] == []
    assert "Level I" not in r.text


# ------------------------------------------------------------------ stored before tiers


def _old_result(api: ApiClient, body: dict[str, Any]) -> dict[str, Any]:
    """The answer to `body` as the service stored it before tiers: no tier, no high-risk
    threshold, the vehicle without thresholds, and the words of that time."""
    result = copy.deepcopy(post_case(api, body))
    for _, d in _decisions(result):
        d.pop("tier")
        d.pop("high_threshold")
        d["recommendation"] = OLD_FLAGGED_WORDS if d["iss15_plus"] else OLD_CLEAR_WORDS
    for key in ("tier", "threshold", "high_threshold"):
        result["vehicle"].pop(key)
    result.pop("stored")
    result.pop("spooled")
    return result


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def old_store(
    request: pytest.FixtureRequest, api: ApiClient, tmp_path: Path
) -> tuple[str, dict[str, dict[str, Any]]]:
    """A store at revision 0004 (before tiers) holding one case of each tier, as that
    schema held them; returns its URL and the stored results by tier."""
    url = (
        f"sqlite:///{tmp_path / 'old.db'}"
        if request.param == "sqlite"
        else str(request.getfixturevalue("postgres_url"))
    )
    migrate.upgrade(url, "0004")
    olds = {tier: _old_result(api, make()) for tier, make in TIER_CASES.items()}
    engine = make_engine(url)
    try:
        meta = MetaData()
        cases = Table("cases", meta, autoload_with=engine)
        occupants = Table("case_occupants", meta, autoload_with=engine)
        assert "tier" not in cases.c, "revision 0004 has no tiers"
        sqlite = engine.dialect.name == "sqlite"
        with engine.begin() as conn:
            for n, (tier, result) in enumerate(olds.items()):
                result["case_id"] = case_id = str(uuid.uuid4())
                at = datetime(2026, 12, 1, 8, n, tzinfo=UTC)
                at = at.replace(tzinfo=None) if sqlite else at
                conn.execute(
                    cases.insert().values(
                        id=case_id,
                        event_id=f"old-{tier}",
                        client_name="old-center",
                        received_at=at,
                        stored_at=at,
                        spooled_at=None,
                        request_sha256="0" * 64,
                        notification={"event_id": f"old-{tier}", "occupants": []},
                        result=result,
                        models=result["models"],
                        source_format="json",
                        engine_version=result["engine_version"],
                        iss15_plus=result["triage"]["iss15_plus"],
                        probability=result["triage"]["probability"],
                    )
                )
                for i, o in enumerate(result["occupants"]):
                    conn.execute(
                        occupants.insert().values(
                            case_id=case_id,
                            position=i,
                            seat=o["seat"],
                            impact_mode=o["impact_mode"],
                            method=o["method"],
                            iss15_plus=o["triage"]["iss15_plus"],
                            probability=o["triage"]["probability"],
                        )
                    )
    finally:
        engine.dispose()
    return url, olds


def test_cases_stored_before_tiers_read_back_with_derived_tiers(
    old_store: tuple[str, dict[str, dict[str, Any]]], tmp_path: Path
) -> None:
    url, olds = old_store
    settings = Settings(database_url=url, spool_path=tmp_path / "spool2.db")
    with TestClient(create_app(settings)) as client:  # migrates to head at start
        assert migrate.current_revision(url) == migrate.head_revision()
        _, key = create_api_key(client.app.state.ctx.sessions, name="a", role=Role.AUDITOR)
        audit = {"Authorization": f"Bearer {key}"}
        for tier, old in olds.items():
            r = client.get(f"/v1/cases/{old['case_id']}", headers=audit)
            assert r.status_code == 200, r.text
            stored = r.json()
            assert stored["tiers_derived"] is True
            triage = stored["result"]["triage"]
            assert (triage["tier"], triage["high_threshold"]) == (tier, HIGH_RISK_THRESHOLD)
            # the words stay those it was answered with
            assert triage["recommendation"] == old["triage"]["recommendation"]
            for i, o in enumerate(stored["result"]["occupants"]):
                assert o["triage"]["tier"] is not None, i
                assert o["baseline"]["tier"] is None, i
            vehicle = stored["result"]["vehicle"]
            assert vehicle["threshold"] == old["triage"]["threshold"]
            assert vehicle["tier"] in ("high", "moderate", "none")
            # the list derives the tier in SQL, the filter finds it
            listed = client.get("/v1/cases", params={"tier": tier}, headers=audit).json()
            assert [c["case_id"] for c in listed["items"]] == [old["case_id"]]
            assert listed["items"][0]["tier"] == tier
            # the page shows the derived tier and says so
            page = Page(client.get(f"/v1/cases/{old['case_id']}/report", headers=audit).text)
            decision = page.one(id="decision")
            assert decision.attrs["data-tier"] == tier
            assert (
                page.text(page.by_class("verdict", within="decision")[0]) == (TIER_VERDICTS[tier])
            )
            assert page.by_class("tiers-derived", within="decision")
            # the NEMSIS record follows the derived tier and says it was derived
            r = client.get(f"/v1/cases/{old['case_id']}/nemsis", params=AGENCY, headers=audit)
            assert r.status_code == 200, r.text
            (pcr,) = etree.fromstring(r.content).findall("n:Header/n:PatientCareReport", NS)
            high = pcr.find("n:eInjury/n:eInjury.CollisionGroup/n:eInjury.23", NS)
            assert high is not None
            assert high.text == ("9923003" if tier == "high" else "9923001")
            narrative = pcr.find("n:eNarrative/n:eNarrative.01", NS)
            assert narrative is not None
            assert "stored before risk tiers" in (narrative.text or "")
    # the stored records were never altered
    engine = make_engine(url)
    try:
        from sqlalchemy.orm import Session

        with Session(engine) as session:
            for old in olds.values():
                row = session.get(Case, old["case_id"])
                assert row is not None
                assert json.dumps(row.result, sort_keys=True) == json.dumps(old, sort_keys=True)
                assert (row.tier, row.high_threshold) == (None, None)
                occupants = session.scalars(
                    select(CaseOccupant).where(CaseOccupant.case_id == row.id)
                ).all()
                assert {o.tier for o in occupants} == {None}
    finally:
        engine.dispose()
