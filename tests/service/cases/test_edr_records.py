"""EDR records that are not physical are refused over HTTP, naming the field."""

from __future__ import annotations

from typing import Any

import pytest

from tests.models.test_pulse_plausibility import FLIPPING, OSCILLATING
from tests.support import ApiClient, assert_problem, example, post_case


def _edr(longitudinal: list[float]) -> dict[str, Any]:
    body = example("delta_v")
    body["crash"]["pulse"] = {
        "kind": "delta_v",
        "interval_ms": 10,
        "longitudinal_kmh": longitudinal,
        "lateral_kmh": [0] * len(longitudinal),
    }
    return body


@pytest.mark.parametrize(
    ("record", "reason"),
    [(OSCILLATING, "turns back"), (FLIPPING, "beyond the accepted 500 g")],
    ids=["oscillating", "flipping"],
)
def test_an_oscillating_record_is_a_422_naming_the_field(
    api: ApiClient, record: list[float], reason: str
) -> None:
    body = _edr(record)
    r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    problem = assert_problem(r, 422)
    named = [f"{e['field']} {e['reason']}" for e in problem["errors"]]
    assert any(n.startswith("crash.pulse") and "longitudinal_kmh" in n for n in named), named
    assert any(reason in n for n in named), named
    # nothing stored under the event
    listed = api.client.get("/v1/cases", headers=api.headers("auditor")).json()
    assert body["event_id"] not in str(listed)


def test_a_monotone_severe_record_is_decided_on_its_maximum(api: ApiClient) -> None:
    # the same peak as the oscillating record, monotone: decided on 60 km/h
    answer = post_case(api, _edr([0, -8, -18, -30, -42, -52, -58, -60, -60, -60, -60, -60]))
    assert answer["pulse"]["delta_v_kmh"] == pytest.approx(60.0)
