"""GET /v1/quality against hand-counted figures; the drift alarm and its stated false-alarm
rate; the metric. Cases are stored rows with chosen probabilities and tiers (the engine's
own answers are not what is tested here); outcomes are written over HTTP."""

from __future__ import annotations

import math
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from typing import Any

import numpy as np
import pytest

from service.db.tables import Case, CaseOccupant
from service.outcomes.drift import DriftSettings, drift_status
from service.outcomes.stats import wilson
from tests.conftest import _api
from tests.support import ApiClient, assert_problem

#: (probability, tier, ISS or None: no outcome, weight) of ten November occupants.
NOVEMBER = [
    (0.010, "none", 4, 1.0),
    (0.015, "none", 17, 3.0),
    (0.030, "moderate", 9, 1.0),
    (0.050, "moderate", 22, 1.0),
    (0.080, "moderate", 1, 1.0),
    (0.120, "moderate", 0, 1.0),
    (0.250, "high", 29, 1.0),
    (0.400, "high", 5, 1.0),
    (0.300, "high", None, 1.0),
    (0.005, "none", None, 1.0),
]


def _store(api: ApiClient, case_id: str, at: datetime, p: float, tier: str, **facts: Any) -> None:
    seat = facts.get("seat", "driver")
    with api.client.app.state.ctx.sessions.begin() as session:  # type: ignore[attr-defined]
        flagged = tier != "none"
        session.add(
            Case(
                id=case_id,
                event_id=case_id,
                client_name="submitter-client",
                received_at=at,
                stored_at=at,
                spooled_at=None,
                request_sha256="0" * 64,
                notification={"occupants": [{"seat": seat, "age_years": facts.get("age", 40)}]},
                result={
                    "occupants": [
                        {
                            "seat": seat,
                            "field_mode": facts.get("mode", "frontal"),
                            "triage": {"operating_point": facts.get("point", "sens85")},
                        }
                    ]
                },
                models={},
                engine_version="test",
                iss15_plus=flagged,
                probability=p,
                tier=tier,
                high_threshold=0.2,
                occupants=[
                    CaseOccupant(
                        position=0,
                        seat=seat,
                        impact_mode="frontal",
                        method="field",
                        iss15_plus=flagged,
                        probability=p,
                        tier=tier,
                    )
                ],
            )
        )


def _outcome(api: ApiClient, case_id: str, iss: int, weight: float, seat: str = "driver") -> None:
    r = api.client.put(
        f"/v1/cases/{case_id}/occupants/{seat}/outcome",
        json={
            "iss": iss,
            "source": "trauma_registry",
            "recorded_at": "2026-12-05T00:00:00Z",
            "weight": weight,
        },
        headers=api.headers("registry"),
    )
    assert r.status_code == 201, r.text


@pytest.fixture(
    scope="module", params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)]
)
def app(
    request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[ApiClient]:
    """Ten November occupants and one December child in a rear seat, at another point."""
    tmp = tmp_path_factory.mktemp("quality")
    if request.param == "sqlite":
        url = f"sqlite:///{tmp / 'aacn.db'}"
    else:
        url = request.getfixturevalue("postgres_url_module")
    for api in _api(url, tmp):
        start = datetime(2026, 11, 5, tzinfo=UTC)
        for i, (p, tier, iss, weight) in enumerate(NOVEMBER):
            _store(api, f"nov-{i}", start + timedelta(hours=i), p, tier)
            if iss is not None:
                _outcome(api, f"nov-{i}", iss, weight)
        _store(
            api,
            "dec-child",
            datetime(2026, 12, 3, tzinfo=UTC),
            0.2,
            "high",
            age=3,
            seat="rear_left",
            point="acs_cot",
        )
        _outcome(api, "dec-child", 16, 1.0, seat="rear_left")
        yield api


from tests.service.outcomes.test_outcomes import postgres_url_module  # noqa: E402, F401


def _quality(api: ApiClient, **query: Any) -> dict[str, Any]:
    r = api.client.get("/v1/quality", params=query, headers=api.headers("auditor"))
    assert r.status_code == 200, r.text
    out: dict[str, Any] = r.json()
    return out


def _counts(rate: dict[str, Any]) -> tuple[int, int]:
    return rate["numerator"], rate["denominator"]


def test_the_november_figures_by_hand(app: ApiClient) -> None:
    report = _quality(app)
    assert [(g["month"], g["operating_point"]) for g in report["groups"]] == [
        ("2026-11", "sens85"),
        ("2026-12", "acs_cot"),
    ]
    nov = report["groups"][0]
    assert (nov["cases"], nov["occupants"]) == (10, 10)
    assert _counts(nov["linked"]) == (8, 10)
    assert {
        t: (v["occupants"], _counts(v["linked"]), v["serious"]) for t, v in nov["by_tier"].items()
    } == {
        "none": (3, (2, 3), 1),
        "moderate": (4, (4, 4), 1),
        "high": (3, (2, 3), 1),
    }
    # the operating point's decision: ISS 15+ are nov-1 (not flagged), nov-3, nov-6
    flagged = nov["flagged"]
    assert _counts(flagged["under_triage"]) == (1, 3)
    # flagged: nov-2..7; ISS < 15 among them: nov-2, 4, 5, 7
    assert _counts(flagged["over_triage_cribari"]) == (4, 6)
    # ISS < 15: nov-0, 2, 4, 5, 7; flagged among them: four
    assert _counts(flagged["over_triage_of_minor"]) == (4, 5)
    assert flagged["over_triage_cribari"]["rate"] == pytest.approx(4 / 6)
    assert flagged["over_triage_of_minor"]["rate"] == pytest.approx(4 / 5)
    assert flagged["over_triage_of_minor"]["within_target"] is False
    # unweighted: Wilson's interval of 4 of 6, as published tables give it (0.300, 0.903)
    assert flagged["over_triage_cribari"]["ci95"] == pytest.approx([0.3000, 0.9032], abs=5e-4)
    # the high tier: ISS 15+ not high: nov-1, nov-3; high with ISS < 15: nov-7
    high = nov["high_tier"]
    assert _counts(high["under_triage"]) == (2, 3)
    assert _counts(high["over_triage_cribari"]) == (1, 2)
    assert _counts(high["over_triage_of_minor"]) == (1, 5)


def test_weights_move_the_rates_not_the_counts(app: ApiClient) -> None:
    ut = _quality(app)["groups"][0]["flagged"]["under_triage"]
    # nov-1 weighs 3, nov-3 and nov-6 weigh 1: 3 of 5
    assert ut["rate"] == pytest.approx(3 / 5)
    assert ut["effective_n"] == pytest.approx(25 / 11)
    assert ut["ci95"] == pytest.approx(list(wilson(0.6, 25 / 11)))
    assert ut["within_target"] is False


def test_calibration_by_decile(app: ApiClient) -> None:
    cal = _quality(app)["groups"][0]["calibration"]
    linked = sorted((p, iss, w) for p, _, iss, w in NOVEMBER if iss is not None)
    assert [d["occupants"] for d in cal["deciles"]] == [1] * 8  # eight linked: eight groups
    assert [d["mean_predicted"] for d in cal["deciles"]] == pytest.approx([p for p, _, _ in linked])
    assert [d["observed"]["numerator"] for d in cal["deciles"]] == [
        int(iss >= 15) for _, iss, _ in linked
    ]
    w_all = sum(w for _, _, w in linked)
    mean_p = sum(p * w for p, _, w in linked) / w_all
    observed = sum(w for _, iss, w in linked if iss >= 15) / w_all
    assert cal["mean_predicted"] == pytest.approx(mean_p)
    assert cal["observed"]["rate"] == pytest.approx(observed)
    assert cal["observed_over_predicted"] == pytest.approx(observed / mean_p)
    low, high = cal["observed_over_predicted_ci95"]
    assert low < observed / mean_p < high


def test_filters_children_seat_row_and_crash_mode(app: ApiClient) -> None:
    overall = _quality(app)["overall"]
    assert (overall["occupants"], overall["linked"]["numerator"]) == (11, 9)
    for query in ({"age_group": "child"}, {"age_group": "child_0_4"}, {"seat_row": 2}):
        child = _quality(app, **query)["overall"]
        assert child["occupants"] == 1, query
        assert _counts(child["flagged"]["under_triage"]) == (0, 1)
    assert _quality(app, age_group="adult_16_64")["overall"]["occupants"] == 10
    assert _quality(app, crash_mode="rollover")["overall"]["occupants"] == 0
    assert _quality(app, received_from="2026-12-01T00:00:00Z")["overall"]["occupants"] == 1
    assert_problem(
        app.client.get("/v1/quality", params={"age_group": "teen"}, headers=app.headers("auditor")),
        422,
    )


def test_roles_of_the_quality_report(app: ApiClient) -> None:
    for role in ("submitter", "registry", "metrics"):
        assert_problem(app.client.get("/v1/quality", headers=app.headers(role)), 403)
    assert app.client.get("/v1/quality", headers=app.headers("admin")).status_code == 200


def test_too_few_outcomes_leave_the_alarm_silent_and_say_so(app: ApiClient) -> None:
    drift = _quality(app)["drift"]
    assert drift["state"] == "insufficient"
    assert drift["occupants"] == 9
    metrics = app.client.get("/metrics", headers=app.headers("admin")).text
    assert "aacn_drift_alarm 0.0" in metrics
    assert "aacn_drift_window_occupants 9.0" in metrics


def test_the_alarm_fires_on_a_shift_and_names_the_next_step() -> None:
    p = [0.1] * 400
    calm = drift_status([i % 10 == 0 for i in range(400)], p, [1.0] * 400, DriftSettings())
    assert calm.state == "ok"
    assert calm.z == pytest.approx(0.0)
    shifted = drift_status([i % 10 < 2 for i in range(400)], p, [1.0] * 400, DriftSettings())
    assert shifted.state == "alarm"
    assert shifted.z == pytest.approx(40 / math.sqrt(36))
    assert "Recalibrate" in shifted.message
    assert "too low" in shifted.message
    halved = drift_status([i % 20 == 0 for i in range(400)], p, [1.0] * 400, DriftSettings())
    assert halved.state == "alarm"
    assert "too high" in halved.message


def test_the_stated_false_alarm_rate_holds_on_a_calibrated_model() -> None:
    """2,000 windows of 400 occupants drawn from their own probabilities (seeded): the
    alarm at 1 % fires in about 1 % of them (binomial 99.9 % bounds: 0.3 %-2.0 %)."""
    rng = np.random.default_rng(20261208)
    settings = DriftSettings(window=400, false_alarm_rate=0.01)
    fired = 0
    for _ in range(2000):
        p = rng.beta(0.5, 6.0, size=400)
        y = rng.random(400) < p
        status = drift_status(list(y), list(p), [1.0] * 400, settings)
        fired += status.state == "alarm"
    assert 6 <= fired <= 40, fired


def test_the_quality_page_for_the_auditor(app: ApiClient) -> None:
    r = app.client.get("/v1/quality/report", headers=app.headers("auditor"))
    assert r.status_code == 200, r.text
    assert r.headers["content-security-policy"].startswith("default-src 'none'")
    page = r.text
    assert 'class="plot reliability"' in page
    assert page.count('<circle class="point"') == 9  # nine linked occupants, nine groups
    assert "Drift alarm: insufficient" in page
    # all months: ISS 15+ are nov-1 (weight 3, not flagged), nov-3, nov-6, the child: 3 of 6
    assert "Under-triage</td><td>50.0 % (1 of 4; 95 %" in page
    assert "Over-triage, 1 - PPV (Cribari)</td><td>57.1 % (4 of 7; 95 %" in page
    assert "style=" not in page  # the strict Content-Security-Policy allows no inline style
    child = app.client.get(
        "/v1/quality/report", params={"age_group": "child"}, headers=app.headers("admin")
    )
    assert child.status_code == 200
    assert "1 cases, 1 occupants" in child.text
    bad = app.client.get(
        "/v1/quality/report", params={"seat_row": "9"}, headers=app.headers("auditor")
    )
    assert bad.status_code == 422
    assert "Seat row must be 1, 2 or 3." in bad.text
    for role in ("registry", "submitter"):
        refused = app.client.get("/v1/quality/report", headers=app.headers(role))
        assert refused.status_code == 403
    assert app.client.get("/v1/quality/report").status_code == 401
