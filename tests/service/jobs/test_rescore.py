"""`aacn-triage cases rescore`: the model recall report.

A database holds cases decided by a retired field model, submitted through the
real HTTP path: 1.0.0 (fitted on mph read as km/h), recalled with its refit
2.0.0; and 2.0.0 (MAIS 3+), recalled with the shipped ISS 15+ model 3.0.0 (issue
38). The report lists the cases whose decision the other version changes, with
the old and new probability and decision, writes them as CSV, and leaves every
stored record as it was.
"""

from __future__ import annotations

import csv
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import select

from models.field.model import WITHDRAWN_VERSIONS
from models.field.risk_model import load_default
from models.field.versions import artifact_for_version, artifact_versions
from models.triage import load_engine_models
from service.cases.veds import VEDS_MEDIA_TYPE
from service.cli import main as cli
from service.db.tables import Case, CaseOccupant
from service.jobs.rescore import CSV_COLUMNS, rescore
from service.settings import get_settings
from tests.conftest import _api
from tests.paths import VEDS_DOCS
from tests.support import ApiClient, summary

#: Delta-V of the stored cases, km/h: from a low-speed crash to a severe one, so
#: that the retired model (which read 40 km/h as 40 mph) flags some that the
#: shipped one does not.
DELTA_V_KMH = (15.0, 25.0, 35.0, 40.0, 45.0, 55.0, 70.0, 90.0)

RETIRED = "1.0.0"
#: The MAIS 3+ refit, retired as the decision by the ISS 15+ model 3.0.0.
MAIS3 = "2.0.0"

#: VEDS test documents (tests/service/cases/veds/).
VEDS_DIR = VEDS_DOCS


@pytest.fixture
def mais3_api(sqlite_url: str, tmp_path: Path) -> Iterator[ApiClient]:
    """The service as it ran with field model 2.0.0 (MAIS 3+)."""
    yield from _api(sqlite_url, tmp_path, field_artifact=artifact_for_version(MAIS3))


@pytest.fixture
def old_api(sqlite_url: str, tmp_path: Path) -> Iterator[ApiClient]:
    """The service as it ran with the retired field model."""
    yield from _api(
        sqlite_url,
        tmp_path,
        field_artifact=artifact_for_version(RETIRED),
        allow_withdrawn_field_model=True,
    )


def _snapshot(api: ApiClient) -> list[tuple[Any, ...]]:
    sessions = api.client.app.state.ctx.sessions  # type: ignore[attr-defined]
    with sessions() as session:
        cases = [
            (c.id, c.event_id, c.result, c.models, c.probability, c.iss15_plus, c.notification)
            for c in session.scalars(select(Case).order_by(Case.id))
        ]
        occupants = [
            (o.case_id, o.position, o.probability, o.iss15_plus)
            for o in session.scalars(select(CaseOccupant).order_by(CaseOccupant.case_id))
        ]
    return [*cases, *occupants]


def _submit_cases(api: ApiClient) -> dict[str, dict[str, Any]]:
    """The summary notifications of DELTA_V_KMH, and one VEDS document."""
    out = {}
    for i, dv in enumerate(DELTA_V_KMH):
        body = summary(dv, belted=i % 3 != 0, event_id=f"recall-{i}")
        r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
        assert r.status_code == 201, r.text
        out[r.json()["case_id"]] = r.json()
    r = api.client.post(
        "/v1/cases",
        content=(VEDS_DIR / "mph-frontal.xml").read_bytes(),
        headers={**api.headers("submitter"), "Content-Type": VEDS_MEDIA_TYPE},
    )
    assert r.status_code == 201, r.text
    out[r.json()["case_id"]] = r.json()
    return out


def test_every_version_is_shipped_and_the_default_is_the_iss15_model() -> None:
    versions = artifact_versions()
    assert RETIRED in versions
    assert MAIS3 in versions
    assert load_default().version in versions
    assert load_default().version not in (RETIRED, MAIS3)
    assert load_default().outcome == "ISS15+"
    with pytest.raises(LookupError, match="shipped"):
        artifact_for_version("0.0.1")


def test_the_withdrawn_version_is_not_served(tmp_path: Path) -> None:
    """1.0.0 is withdrawn: configured as the field model, the service is not ready and
    says why (a recall may still load it)."""
    from fastapi.testclient import TestClient

    from service.app import create_app
    from service.settings import Settings

    assert RETIRED in WITHDRAWN_VERSIONS
    settings = Settings(
        database_url=f"sqlite:///{tmp_path / 'a.db'}",
        spool_path=tmp_path / "spool.db",
        field_artifact=artifact_for_version(RETIRED),
    )
    with TestClient(create_app(settings)) as client:
        ready = client.get("/readyz")
        assert ready.status_code == 503
        assert "withdrawn" in ready.text
        assert "mph" in ready.text


def test_rescore_lists_the_changed_decisions_and_alters_nothing(old_api: ApiClient) -> None:
    answered = _submit_cases(old_api)
    assert all(a["triage"]["model"] == f"field_mais3@{RETIRED}" for a in answered.values())
    before = _snapshot(old_api)

    sessions = old_api.client.app.state.ctx.sessions  # type: ignore[attr-defined]
    report = rescore(sessions, load_engine_models(field_artifact=artifact_for_version(MAIS3)))
    assert report.cases == len(DELTA_V_KMH) + 1
    assert not report.refused
    for row in report.rows:
        old = answered[row.case_id]["triage"]
        assert row.old_probability == old["probability"]
        assert row.old_decision == old["iss15_plus"]
        assert row.old_model == f"field_mais3@{RETIRED}"
        assert row.new_model == f"field_mais3@{MAIS3}"
    # the retired model read km/h as mph: it over-predicted every one of these cases
    assert all(r.new_probability < r.old_probability for r in report.rows)
    assert report.changed, "the 1.6x over-read must change some dispatch advice"
    assert report.down == len(report.changed), "only over-triage is withdrawn"
    assert _snapshot(old_api) == before, "the stored records are not altered"


def test_rescore_with_the_deciding_version_changes_nothing(old_api: ApiClient) -> None:
    """Determinism: the same notification and model version give the same answer."""
    answered = _submit_cases(old_api)
    sessions = old_api.client.app.state.ctx.sessions  # type: ignore[attr-defined]
    models = load_engine_models(field_artifact=artifact_for_version(RETIRED))
    report = rescore(sessions, models)
    assert len(report.rows) == len(answered)
    assert not report.changed
    for row in report.rows:
        assert row.new_probability == row.old_probability


def test_the_command_prints_and_writes_the_changed_cases(
    old_api: ApiClient,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    answered = _submit_cases(old_api)
    before = _snapshot(old_api)
    monkeypatch.setenv("AACN_DATABASE_URL", old_api.settings.database_url)
    get_settings.cache_clear()
    out = tmp_path / "recall.csv"
    try:
        assert cli.main(["cases", "rescore", "--model", MAIS3, "--out", str(out)]) == 0
        printed = capsys.readouterr()
        assert cli.main(["cases", "rescore", "--model", "9.9.9", "--out", str(out)]) == 2
        assert "no field model artifact of version '9.9.9'" in capsys.readouterr().err
    finally:
        get_settings.cache_clear()
    with out.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert tuple(rows[0]) == CSV_COLUMNS
    assert rows, "some decisions change"
    for row in rows:
        old = answered[row["case_id"]]["triage"]
        assert row["old_decision"] == str(old["iss15_plus"]).lower()
        assert row["new_decision"] != row["old_decision"]
        assert float(row["old_probability"]) == pytest.approx(old["probability"], abs=5e-7)
        assert row["case_id"] in printed.out
    assert f"{len(answered)} stored cases" in printed.err
    assert f"{len(rows)} decisions change" in printed.err
    assert _snapshot(old_api) == before


def test_cases_decided_by_2_0_0_are_rescored_with_the_iss15_model(
    mais3_api: ApiClient,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:
    """`cases rescore --model <shipped version>` on cases decided by 2.0.0 (P(MAIS 3+)): every
    case is run again with the shipped ISS 15+ model, the CSV lists old and new model,
    probability and decision, and the stored records are untouched."""
    answered = _submit_cases(mais3_api)
    assert all(a["triage"]["model"] == f"field_mais3@{MAIS3}" for a in answered.values())
    assert all(a["triage"]["outcome"] == "MAIS3+" for a in answered.values())
    before = _snapshot(mais3_api)
    new = load_default()
    monkeypatch.setenv("AACN_DATABASE_URL", mais3_api.settings.database_url)
    get_settings.cache_clear()
    out = tmp_path / "recall.csv"
    try:
        code = cli.main(["cases", "rescore", "--model", new.version, "--all", "--out", str(out)])
        assert code == 0
        printed = capsys.readouterr()
    finally:
        get_settings.cache_clear()
    with out.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(answered)
    engine = load_engine_models(field_artifact=artifact_for_version(new.version))
    sessions = mais3_api.client.app.state.ctx.sessions  # type: ignore[attr-defined]
    report = rescore(sessions, engine)
    by_id = {r.case_id: r for r in report.rows}
    for row in rows:
        old = answered[row["case_id"]]["triage"]
        assert row["old_model"] == f"field_mais3@{MAIS3}"
        assert row["new_model"] == f"field_iss15@{new.version}"
        assert float(row["old_probability"]) == pytest.approx(old["probability"], abs=5e-7)
        again = by_id[row["case_id"]]
        assert float(row["new_probability"]) == pytest.approx(again.new_probability, abs=5e-7)
        assert row["new_decision"] == str(again.new_decision).lower()
    assert f"{len(answered)} stored cases" in printed.err
    assert _snapshot(mais3_api) == before, "the stored records are not altered"


#: Earlier ISS 15+ models: 3.0.0 (regressions only), retired as the decision by 3.1.0
#: (bags of boosted trees), retired by 3.2.0 (feature set 2); both of feature set 1.
ISS15_EARLIER = ("3.0.0", "3.1.0")


@pytest.fixture(params=ISS15_EARLIER)
def iss15_old_api(
    request: pytest.FixtureRequest, sqlite_url: str, tmp_path: Path
) -> Iterator[ApiClient]:
    """The service as it ran with an earlier ISS 15+ field model."""
    yield from _api(sqlite_url, tmp_path, field_artifact=artifact_for_version(request.param))


def test_cases_decided_by_earlier_iss15_models_are_rescored_with_the_shipped_model(
    iss15_old_api: ApiClient,
) -> None:
    """Cases decided by 3.0.0 or 3.1.0 rescored with the shipped version: all answer ISS 15+;
    the report carries both versions and each case's new probability is the shipped model's
    answer to the same notification; nothing stored changes."""
    new = load_default()
    answered = _submit_cases(iss15_old_api)
    old = next(iter(answered.values()))["triage"]["model"].removeprefix("field_iss15@")
    assert old in ISS15_EARLIER
    assert new.version != old
    assert all(a["triage"]["model"] == f"field_iss15@{old}" for a in answered.values())
    assert all(a["triage"]["outcome"] == "ISS15+" for a in answered.values())
    before = _snapshot(iss15_old_api)
    sessions = iss15_old_api.client.app.state.ctx.sessions  # type: ignore[attr-defined]
    report = rescore(sessions, load_engine_models(field_artifact=artifact_for_version(new.version)))
    assert report.cases == len(answered)
    assert not report.refused
    by_id = {r.case_id: r for r in report.rows}
    assert set(by_id) == set(answered)
    for case_id, r in by_id.items():
        assert r.old_model == f"field_iss15@{old}"
        assert r.new_model == f"field_iss15@{new.version}"
        assert r.old_probability == answered[case_id]["triage"]["probability"]
        assert r.new_probability != r.old_probability  # another model, another number
    # risk still rises with delta-V under the new model (the belted summary cases)
    belted = [
        by_id[cid].new_probability
        for cid, a in answered.items()
        if a["event_id"].startswith("recall-") and int(a["event_id"].split("-")[1]) % 3 != 0
    ]
    assert belted == sorted(belted)
    assert _snapshot(iss15_old_api) == before, "the stored records are not altered"
