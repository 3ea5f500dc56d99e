"""One set of input limits (the engine's), and engine failures told apart from bad input."""

from __future__ import annotations

import pytest

from models import limits
from service.cases.notification import (
    AccelerationPulseIn,
    CrashNotificationIn,
    DeltaVPulseIn,
    OccupantIn,
    SummaryPulseIn,
)
from tests.support import ApiClient, assert_problem, example, summary


def _bounds(model: type, field: str) -> dict[str, float]:
    out: dict[str, float] = {}
    for m in model.model_fields[field].metadata:
        for name in ("gt", "ge", "lt", "le", "min_length", "max_length"):
            if getattr(m, name, None) is not None:
                out[name] = getattr(m, name)
    return out


def test_the_wire_limits_are_the_engines() -> None:
    assert _bounds(SummaryPulseIn, "delta_v_kmh")["le"] == limits.MAX_DELTA_V_KMH
    rate = _bounds(AccelerationPulseIn, "sample_rate_hz")
    assert rate == {
        "gt": limits.MIN_ACCELERATION_SAMPLE_RATE_HZ,
        "le": limits.MAX_ACCELERATION_SAMPLE_RATE_HZ,
    }
    series = _bounds(AccelerationPulseIn, "longitudinal_g")
    assert (series["min_length"], series["max_length"]) == (limits.MIN_SAMPLES, limits.MAX_SAMPLES)
    interval = _bounds(DeltaVPulseIn, "interval_ms")
    assert (interval["ge"], interval["le"]) == (
        limits.MIN_EDR_INTERVAL_MS,
        limits.MAX_EDR_INTERVAL_MS,
    )
    assert _bounds(OccupantIn, "age_years")["le"] == limits.MAX_AGE_YEARS
    assert _bounds(OccupantIn, "stature_cm") == {
        "ge": limits.MIN_STATURE_CM,
        "le": limits.MAX_STATURE_CM,
    }
    assert _bounds(OccupantIn, "mass_kg") == {"ge": limits.MIN_MASS_KG, "le": limits.MAX_MASS_KG}
    assert CrashNotificationIn is not None


@pytest.mark.parametrize(
    ("pulse", "field"),
    [
        # the engine needs the CFC 60 design frequency below Nyquist (249.3 Hz): the wire
        # used to take 100 Hz and the engine then failed with a 422 about crash.pulse
        (
            {"kind": "acceleration", "sample_rate_hz": 200.0, "longitudinal_g": [0.0] * 30},
            "crash.pulse.sample_rate_hz",
        ),
        # an EDR record interval over one 563 window (20 ms)
        (
            {"kind": "delta_v", "interval_ms": 30, "longitudinal_kmh": [0, -10, -20, -25, -25]},
            "crash.pulse.interval_ms",
        ),
        # 600 g: a unit mistake (m/s^2 sent as g), refused by the wire, not deep in the engine
        (
            {
                "kind": "acceleration",
                "sample_rate_hz": 1000.0,
                "longitudinal_g": [0.0, -600.0] + [0.0] * 40,
                "lateral_g": [0.0] * 42,
            },
            "crash.pulse.longitudinal_g",
        ),
    ],
)
def test_inputs_past_an_engine_limit_are_refused_naming_their_field(
    api: ApiClient, pulse: dict[str, object], field: str
) -> None:
    body = example("summary")
    body["crash"]["pulse"] = pulse
    problem = assert_problem(
        api.client.post("/v1/cases", json=body, headers=api.headers("submitter")), 422
    )
    # the field, or its pulse with the field named in the reason (a check across fields)
    named = [f"{e['field']} {e['reason']}" for e in problem["errors"]]
    leaf = field.rsplit(".", 1)[1]
    assert any(n.startswith(field) or leaf in n for n in named), named


def test_an_engine_failure_is_a_500_with_a_case_reference_and_nothing_stored(
    api: ApiClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Fault injection: the engine raises where no input is to blame. The answer is a
    500-class problem naming a reference (not a 422 about the pulse), and no case is
    stored; the next notification is answered as usual."""
    import service.cases.service as cases_service

    def broken(*_: object, **__: object) -> object:
        raise RuntimeError("injected engine fault")

    monkeypatch.setattr(cases_service, "triage", broken)
    problem = assert_problem(
        api.client.post("/v1/cases", json=summary(40.0), headers=api.headers("submitter")), 500
    )
    assert problem["type"].endswith("engine-failure")
    assert "reference" in problem["detail"]
    assert "errors" not in problem or not problem["errors"]
    listed = api.client.get("/v1/cases", headers=api.headers("auditor")).json()
    assert listed["items"] == []
    monkeypatch.undo()
    ok = api.client.post("/v1/cases", json=summary(40.0), headers=api.headers("submitter"))
    assert ok.status_code == 201
