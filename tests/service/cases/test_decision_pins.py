"""The decided probabilities of a fixed set of notifications stay what they were (issue 51).

The pins (``tests/decision_pins.json``, written by ``python -m tests.decision_pins``
at commit 90e87cc, before the engine's speed-up) hold every occupant's and the
vehicle's decided probability, its 95 % interval, the range over the unknown
inputs, the threshold and the tier. On the host and library build that wrote
them, with no floating-point override (``.ci/run``'s second run sets them), the
decision is compared bit for bit; elsewhere at :data:`tests.tolerance.RERUN_RTOL`.
The occupant models' explanation (measures, their intervals, the uncorrected
probability) is held to :data:`tests.tolerance.LPM_RTOL`, the tolerance of a
direct LPM output.
"""

from __future__ import annotations

import json
from typing import Any

import pytest

from models.triage import EngineModels, load_engine_models
from tests.decision_pins import PINS_PATH, compute_pins, host_signature, notifications
from tests.tolerance import LPM_RTOL, RERUN_RTOL, assert_tree_close


@pytest.fixture(scope="module")
def stored() -> dict[str, Any]:
    return dict(json.loads(PINS_PATH.read_text()))


@pytest.fixture(scope="module")
def fresh() -> dict[str, Any]:
    models: EngineModels = load_engine_models()
    return compute_pins(models)


def test_the_pins_cover_the_notifications_the_issue_names(stored: dict[str, Any]) -> None:
    pins = stored["pins"]
    assert sorted(pins) == sorted(notifications())
    modes = {e["method"] for p in pins.values() for e in p["explanation"]}
    assert modes == {"lpm", "field"}
    tiers = {o["tier"] for p in pins.values() for o in p["decision"]["occupants"]}
    assert tiers == {"none", "moderate", "high"}
    # the hex form is the same double as the repr form
    for name, pin in pins.items():
        for o, h in zip(
            pin["decision"]["occupants"], stored["pins_hex"][name]["occupants"], strict=True
        ):
            assert float.fromhex(h["probability"]) == o["probability"]


def test_decisions_equal_the_pins(stored: dict[str, Any], fresh: dict[str, Any]) -> None:
    same_host = stored["host"] == host_signature()
    for name, pin in stored["pins"].items():
        got = fresh[name]["decision"]
        if same_host:
            assert got == pin["decision"], f"{name}: the decision changed bits"
        else:
            assert_tree_close(got, pin["decision"], rtol=RERUN_RTOL, path=name)


def test_explanations_stay_within_the_lpm_tolerance(
    stored: dict[str, Any], fresh: dict[str, Any]
) -> None:
    for name, pin in stored["pins"].items():
        assert_tree_close(fresh[name]["explanation"], pin["explanation"], rtol=LPM_RTOL, path=name)
