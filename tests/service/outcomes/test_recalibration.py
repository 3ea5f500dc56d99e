"""`aacn-triage outcomes recalibrate` (issue 50, item 4), end to end over HTTP and the CLI.

Cases are submitted over HTTP and triaged by the served model; their outcomes, written
over HTTP by the registry key (the first cases) and imported as a registry extract (the
rest), are drawn (seeded) from a known shift of the served
probabilities: ``logit P_true = -1 + logit P_served`` (the model over-predicts, the
odds e times too high). The command refuses with too few ISS 15+ outcomes and says
how many are needed; with enough it writes a new version whose provenance names the
occupants it learned from, which ``cases rescore --model`` compares with the served
one, and which the service then serves: its probability is the served one through the
map, its thresholds flag the same occupants, its high tier is 20 % of the new
probability. On SQLite and PostgreSQL.
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from models.field.recalibrated import cases_sha256
from models.field.recalibration import MIN_EFFECTIVE_EVENTS
from models.field.risk_model import RiskModel, load_default
from models.tiers import ThresholdOrderError
from service.cli import main as cli
from service.outcomes.recalibrate import recalibrate
from service.settings import get_settings
from tests.conftest import _api
from tests.support import ApiClient, post_case, summary

#: The shift the outcomes are drawn from: logit P_true = A + B logit P_served.
SHIFT_INTERCEPT, SHIFT_SLOPE = -1.0, 1.0
#: Seats of each notification: seven occupants a case (fewer POSTs), none in the seats of
#: the occupant models (the field model decides every seat; the test's time is its own).
SEATS = (
    "rear_left",
    "rear_middle",
    "rear_right",
    "third_row_left",
    "third_row_middle",
    "third_row_right",
    "front_middle",
)
HEADER = "case_id,client,event_id,seat,iss,mais,died,disposition,source,recorded_at,weight\n"


def _expit(x: float) -> float:
    return 1.0 / (1.0 + math.exp(-x))


def _logit(p: float) -> float:
    return math.log(p) - math.log1p(-p)


def _notification(i: int, rng: np.random.Generator) -> dict[str, Any]:
    body = summary(float(rng.uniform(35.0, 120.0)), float(rng.choice([0.0, 0.0, 90.0, 270.0])))
    body["event_id"] = f"recal-{i}"
    driver = body["occupants"][0]
    body["occupants"] = [
        {
            **driver,
            "seat": seat,
            "belted": bool(rng.random() < 0.6),
            "age_years": int(rng.integers(18, 85)),
            "frontal_airbag": "absent",
        }
        for seat in SEATS
    ]
    return body


@pytest.fixture
def env_api(
    api_any_db: ApiClient, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> Iterator[ApiClient]:
    """The app, and the command line on the same database with its own model directory."""
    monkeypatch.setenv("AACN_DATABASE_URL", api_any_db.settings.database_url)
    monkeypatch.setenv("AACN_LOCAL_MODEL_DIR", str(tmp_path / "local-models"))
    get_settings.cache_clear()
    yield api_any_db
    get_settings.cache_clear()


def _submit(api: ApiClient, cases: range) -> list[tuple[str, str, float]]:
    """(case_id, seat, decided probability) of every occupant of new cases (by number)."""
    rng = np.random.default_rng(cases.start)
    out = []
    for i in cases:
        answer = post_case(api, _notification(i, rng))
        for occ in answer["occupants"]:
            out.append((answer["case_id"], occ["seat"], occ["triage"]["probability"]))
    return out


def _draw(occupants: list[tuple[str, str, float]], seed: int) -> list[bool]:
    """ISS 15+ of each occupant, drawn from the shift."""
    rng = np.random.default_rng(seed)
    return [
        bool(rng.random() < _expit(SHIFT_INTERCEPT + SHIFT_SLOPE * _logit(p)))
        for _, _, p in occupants
    ]


def _put(api: ApiClient, occupants: list[tuple[str, str, float]]) -> int:
    """Outcomes drawn from the shift, written over HTTP by the registry key; the ISS 15+."""
    serious = _draw(occupants, 52)
    for (case_id, seat, _), s in zip(occupants, serious, strict=True):
        body = {
            "iss": 17 if s else 4,
            "mais": 3 if s else 2,
            "died": False,
            "disposition": "admitted_icu" if s else "discharged_from_ed",
            "source": "trauma_registry",
            "recorded_at": "2026-12-01T10:00:00Z",
        }
        r = api.client.put(
            f"/v1/cases/{case_id}/occupants/{seat}/outcome",
            json=body,
            headers=api.headers("registry"),
        )
        assert r.status_code == 201, r.text
    return sum(serious)


def _import(occupants: list[tuple[str, str, float]], path: Path) -> int:
    """Outcomes drawn from the shift, imported as a registry extract; the ISS 15+ count."""
    serious = _draw(occupants, 51)
    lines = []
    for (case_id, seat, _), s in zip(occupants, serious, strict=True):
        iss, mais, where = (17, 3, "admitted_icu") if s else (4, 2, "discharged_from_ed")
        lines.append(
            f"{case_id},,,{seat},{iss},{mais},false,{where},trauma_registry,2026-12-01T10:00Z,\n"
        )
    path.write_text(HEADER + "".join(lines))
    assert cli.main(["outcomes", "import", str(path)]) == 0
    return sum(serious)


def test_recalibrate_refuses_then_writes_a_version_rescore_compares_and_serves(
    env_api: ApiClient, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    served = load_default()
    first = _submit(env_api, range(12))
    events = _put(env_api, first)
    capsys.readouterr()
    # too few ISS 15+: refused, the minimum and its reason said, nothing written
    assert cli.main(["outcomes", "recalibrate", "--site", "county-x"]) == 1
    err = capsys.readouterr().err
    assert f"needs at least {MIN_EFFECTIVE_EVENTS} effective linked ISS 15+" in err
    assert "within a factor 1.25 at 95 %" in err
    local = tmp_path / "local-models"
    assert not local.exists() or not list(local.iterdir())

    rest = _submit(env_api, range(12, 60))
    events += _import(rest, tmp_path / "rest.csv")
    occupants = first + rest
    capsys.readouterr()
    assert cli.main(["outcomes", "recalibrate", "--site", "county-x", "--dry-run"]) == 0
    assert "dry run: nothing written" in capsys.readouterr().out
    assert cli.main(["outcomes", "recalibrate", "--site", "County X"]) == 2  # a bad site name
    # a map that would lift an operating threshold above the high tier is refused, unwritten
    sessions = env_api.client.app.state.ctx.sessions  # type: ignore[attr-defined]
    with pytest.raises(ThresholdOrderError, match="high-risk threshold"):
        recalibrate(sessions, served, site="county-x", out_dir=local, high_threshold=0.001)
    assert not local.exists() or not list(local.iterdir())
    capsys.readouterr()
    assert cli.main(["outcomes", "recalibrate", "--site", "county-x"]) == 0
    out = capsys.readouterr().out
    version = f"{served.version}+local.county-x.1"
    path = local / f"field_iss15-{version}.json"
    assert f"wrote {path}" in out, out
    model = RiskModel.from_artifact(path)  # checksummed: it loads
    assert model.version == version
    doc = json.loads(path.read_text())
    rc = doc["recalibration"]
    learned = rc["learned_from"]
    named = [f"{c}:{s}" for c, s, _ in occupants]
    assert learned["occupants"] == len(occupants) == len(named)
    assert learned["cases"] == 60
    assert learned["occupants_sha256"] == cases_sha256(named)
    assert learned["occupant_list"] == sorted(named)
    assert learned["events"] == events >= MIN_EFFECTIVE_EVENTS
    assert rc["fitted"]["on_version"] == served.version
    assert rc["fitted"]["on_content_sha256"] == served.document["content_sha256"]
    # the shift is found: the intercept within 3 robust SEs of the truth
    assert rc["fitted"]["method"] == "intercept_and_slope"
    a, b = rc["intercept"], rc["slope"]
    assert abs(a - SHIFT_INTERCEPT) < 3 * rc["fitted"]["intercept_se"]
    assert abs(b - SHIFT_SLOPE) < 3 * rc["fitted"]["slope_se"]
    cv = rc["cross_validation"]
    assert cv["recalibrated_log_loss"] < cv["served_log_loss"]
    assert abs(cv["recalibrated_ratio"] - 1.0) < abs(cv["served_ratio"] - 1.0)
    # thresholds mapped: the same occupants flagged
    for name, t in served.thresholds.items():
        assert model.thresholds[name] == pytest.approx(_expit(a + b * _logit(t)), rel=1e-12)
    # the same outcomes give the same bytes (a second run is version .2, the same content)
    assert cli.main(["outcomes", "recalibrate", "--site", "county-x"]) == 0
    again = json.loads((local / f"field_iss15-{served.version}+local.county-x.2.json").read_text())
    assert again["recalibration"] == rc

    # rescore compares it with the served model on every stored case
    csv_path = tmp_path / "rescore.csv"
    capsys.readouterr()
    assert cli.main(["cases", "rescore", "--model", version, "--out", str(csv_path), "--all"]) == 0
    assert "60 stored cases, 60 run again" in capsys.readouterr().err
    with csv_path.open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 60
    for row in rows:
        assert row["new_model"] == f"field_iss15@{version}"
        old_p, new_p = float(row["old_probability"]), float(row["new_probability"])
        assert new_p == pytest.approx(_expit(a + b * _logit(old_p)), abs=2e-6)
        assert row["old_decision"] == row["new_decision"]  # mapped thresholds

    # served: the answer is the served answer through the map; the high tier is 20 % of it
    body = _notification(99, np.random.default_rng(7))
    before = post_case(env_api, body)
    served_db = tmp_path / "served-local"
    served_db.mkdir()
    for new_api in _api(f"sqlite:///{served_db / 'a.db'}", served_db, field_artifact=path):
        after = post_case(new_api, {**body, "event_id": "recal-served"})
        assert after["models"]["field_model"]["version"] == version
        for o_old, o_new in zip(before["occupants"], after["occupants"], strict=True):
            p_old, p_new = o_old["triage"]["probability"], o_new["triage"]["probability"]
            assert p_new == pytest.approx(_expit(a + b * _logit(p_old)), rel=1e-9)
            assert o_new["triage"]["iss15_plus"] == o_old["triage"]["iss15_plus"]
            assert (o_new["triage"]["tier"] == "high") == (
                o_new["triage"]["iss15_plus"] and p_new >= 0.2
            )


def test_linked_outcomes_stream_each_linked_occupants_latest_revision(env_api: ApiClient) -> None:
    """The recalibration's rows: only occupants with an outcome, the current revision of a
    corrected one, the served model's decided probability, cases in the order received."""
    from service.cli.common import open_sessions
    from service.outcomes.recalibrate import linked_outcomes

    occupants = _submit(env_api, range(900, 903))  # 3 cases x 7 occupants
    linked = [occupants[0], occupants[2], occupants[8], occupants[15]]

    def put(case_id: str, seat: str, iss: int) -> None:
        body = {"iss": iss, "source": "trauma_registry", "recorded_at": "2026-12-01T10:00:00Z"}
        r = env_api.client.put(
            f"/v1/cases/{case_id}/occupants/{seat}/outcome",
            json=body,
            headers=env_api.headers("registry"),
        )
        assert r.status_code in (200, 201), r.text

    for case_id, seat, _ in linked:
        put(case_id, seat, 4)
    put(linked[1][0], linked[1][1], 17)  # a correction: ISS 4 -> 17 (revision 2)
    sha = load_default().sha256
    with open_sessions() as sessions:
        rows = linked_outcomes(sessions, sha)
        other = linked_outcomes(sessions, "0" * 64)
    assert rows.occupants == tuple(f"{c}:{s}" for c, s, _ in linked)
    assert rows.crash == tuple(c for c, _, _ in linked)
    assert rows.probability.tolist() == [p for _, _, p in linked]
    assert rows.serious.tolist() == [0.0, 1.0, 0.0, 0.0]
    assert rows.weight.tolist() == [1.0] * 4
    assert other.occupants == ()  # decided by another artifact: none
