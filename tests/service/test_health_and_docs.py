"""/livez, /readyz, /metrics and the OpenAPI document."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from openapi_spec_validator import validate

from service.app import create_app
from service.cases.examples import EXAMPLE_NOTIFICATIONS
from service.settings import Settings
from tests.support import ApiClient, assert_problem, summary


def test_the_documented_result_example_is_a_valid_result() -> None:
    from service.cases.examples import EXAMPLE_CASE_RESULT, EXAMPLE_STORED_CASE
    from service.cases.result import CaseResult, StoredCase

    CaseResult.model_validate(EXAMPLE_CASE_RESULT)
    StoredCase.model_validate(EXAMPLE_STORED_CASE)


def test_the_result_example_is_the_shipped_engines_answer() -> None:
    """The documented answer to the summary example is what the engine answers now
    (rounded as the example is): a model release re-derives it."""
    from datetime import UTC, datetime

    from models.triage import load_engine_models
    from service.cases.examples import EXAMPLE_CASE_RESULT
    from service.cases.notification import CrashNotificationIn
    from service.cases.service import evaluate

    body = EXAMPLE_NOTIFICATIONS["summary"]["value"]
    notification = CrashNotificationIn.model_validate(body)
    result = evaluate(
        notification, load_engine_models(), case_id=None, received_at=datetime.now(UTC)
    ).model_dump(mode="json")
    documented = EXAMPLE_CASE_RESULT
    for key in ("iss15_plus", "model", "operating_point", "outcome", "recommendation", "tier"):
        assert documented["triage"][key] == result["triage"][key], key
    for key in ("tier", "high_threshold"):
        assert documented["vehicle"][key] == result["vehicle"][key], key
    assert documented["triage"]["high_threshold"] == result["triage"]["high_threshold"]
    for opinion in ("occupant_model", "baseline"):
        got, want = documented["occupants"][0][opinion], result["occupants"][0][opinion]
        assert got["recommendation"] == want["recommendation"], opinion
        assert got["tier"] is None, opinion
        assert want["tier"] is None, opinion
    assert documented["models"]["triage_code"] == result["models"]["triage_code"], (
        "the example's triage_code checksum is the code's: copy it from the answer"
    )
    for key in ("probability", "threshold"):
        assert documented["triage"][key] == pytest.approx(result["triage"][key], rel=5e-4)
    for got, want in zip(
        documented["triage"]["probability_ci95"], result["triage"]["probability_ci95"], strict=True
    ):
        assert got == pytest.approx(want, rel=5e-4)
    assert documented["occupants"][0]["triage"] == documented["triage"]
    assert documented["models"]["field_model"] == result["models"]["field_model"]


def test_livez_and_readyz(api: ApiClient) -> None:
    assert api.client.get("/livez").json() == {"status": "ok"}
    ready = api.client.get("/readyz")
    assert ready.status_code == 200
    assert ready.json()["models"]["baseline"]["sha256"]


def test_readyz_is_503_when_the_database_is_unreachable(tmp_path: Path) -> None:
    # a closed loopback port: nothing listens there; and the spool cannot be written
    blocker = tmp_path / "not-a-directory"
    blocker.write_text("")
    settings = Settings(
        database_url="postgresql+psycopg://nobody@127.0.0.1:9/none?connect_timeout=2",
        auto_migrate=False,
        spool_path=blocker / "spool.db",
    )
    with TestClient(create_app(settings)) as client:
        assert client.get("/livez").status_code == 200, "liveness checks no dependency"
        problem = assert_problem(client.get("/readyz"), 503)
        assert "store not writable (OperationalError)" in problem["detail"]
        assert "spool failing" in problem["detail"]
        assert "127.0.0.1" not in problem["detail"], "no internal host names"


def test_a_start_without_its_store_is_alive_and_not_ready(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    """The default AACN_AUTO_MIGRATE=true on an unreachable store: no crash, one log line,
    /readyz 503 (no API key can be verified), a POST 503 to retry."""
    settings = Settings(
        database_url="postgresql+psycopg://nobody@127.0.0.1:9/none?connect_timeout=2",
        spool_path=tmp_path / "spool.db",
    )
    assert settings.auto_migrate
    with caplog.at_level("WARNING", logger="aacn_triage"), TestClient(create_app(settings)) as c:
        assert c.get("/livez").status_code == 200
        problem = assert_problem(c.get("/readyz"), 503)
        assert "no API key can be verified" in problem["detail"]
        assert "migration runs once it returns" in problem["detail"]
        posted = c.post("/v1/cases", json=summary(), headers={"Authorization": "Bearer aacn_x"})
        assert_problem(posted, 503)
        assert posted.headers["Retry-After"]
    started = [r for r in caplog.records if "the store is unreachable" in r.getMessage()]
    assert len(started) == 1
    assert started[0].exc_info is None, "one line, no traceback"


def test_metrics_count_requests_decisions_and_engine_time(api: ApiClient) -> None:
    h = api.headers("submitter")
    api.client.post("/v1/cases", json=summary(70, belted=False, airbag="absent"), headers=h)
    api.client.post("/v1/cases", json=summary(10), headers=h)
    api.client.post("/v1/cases", json=summary(10, 45.0), headers=h)  # outside LPM coverage
    api.client.post("/v1/cases", json={"bad": 1}, headers=h)
    text = api.client.get("/metrics").text
    assert 'aacn_http_requests_total{handler="/v1/cases",method="POST",status="2xx"} 3.0' in text
    assert 'aacn_http_requests_total{handler="/v1/cases",method="POST",status="4xx"} 1.0' in text
    assert 'aacn_triage_decisions_total{decision="iss15_plus",method="lpm"} 1.0' in text
    assert 'aacn_triage_decisions_total{decision="not_iss15_plus",method="lpm"} 1.0' in text
    assert 'aacn_triage_decisions_total{decision="not_iss15_plus",method="field"} 1.0' in text
    assert "aacn_engine_seconds_count 3.0" in text
    assert "/livez" not in text


def _walk_properties(schema: dict[str, Any], name: str, missing: list[str]) -> None:
    for prop, sub in schema.get("properties", {}).items():
        if "description" not in sub and "$ref" not in sub:
            missing.append(f"{name}.{prop}")


def test_openapi_document_validates_with_descriptions_and_examples(api: ApiClient) -> None:
    doc = api.client.get("/openapi.json").json()
    validate(doc)
    schemas = doc["components"]["schemas"]
    missing: list[str] = []
    for name, schema in schemas.items():
        if name in ("ValidationError", "HTTPValidationError"):
            continue
        assert schema.get("description"), f"schema {name} has no description"
        _walk_properties(schema, name, missing)
    assert not missing, f"fields without description: {missing}"
    for name in ("CrashNotificationIn", "CaseResult", "StoredCase", "CaseList", "Problem"):
        assert schemas[name].get("examples"), f"{name} has no example"
    post = doc["paths"]["/v1/cases"]["post"]
    examples = post["requestBody"]["content"]["application/json"]["examples"]
    assert set(examples) == set(EXAMPLE_NOTIFICATIONS)
    kinds = {e["value"]["crash"]["pulse"]["kind"] for e in examples.values()}
    assert kinds == {"acceleration", "delta_v", "summary"}
    assert "bearer" in str(doc["components"]["securitySchemes"]).lower()
    assert "application/problem+json" in post["responses"]["422"]["content"]
    # every operation that validates its parameters documents its 422 as a problem
    # (found by a schemathesis run: GET /v1/cases/{case_id} with a 65-character id)
    for path, ops in doc["paths"].items():
        for method, op in ops.items():
            if op.get("parameters") or op.get("requestBody"):
                content = op["responses"].get("422", {}).get("content", {})
                assert list(content) == ["application/problem+json"], (method, path)


def test_readyz_is_503_when_surrogate_artifacts_fail_verification(tmp_path: Path) -> None:
    artifacts = tmp_path / "artifacts"
    artifacts.mkdir()
    (artifacts / "manifest.json").write_text('{"files": {"x.npz": "00"}}')
    settings = Settings(database_url=f"sqlite:///{tmp_path / 'a.db'}", surrogate_dir=artifacts)
    with TestClient(create_app(settings)) as client:
        problem = assert_problem(client.get("/readyz"), 503)
        assert "models not loaded" in problem["detail"]
        assert "surrogate" in problem["detail"]
