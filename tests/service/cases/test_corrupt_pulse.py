"""An acceleration record that is not a vehicle's motion is decided conservatively.

The CFC 60 filter removes what lies above the crash-pulse band; a record alternating
+/-400 g at every sample left only the filter's edge ringing and was answered as a
minor crash (P 0.0021, no transport, no word). It is now answered with
``pulse_looks_corrupt`` and every occupant flagged for a trauma center; no pulse the
project ships (the documented examples, the VEDS documents, the EDR and acceleration
records of the tests) raises that alarm.
"""

from __future__ import annotations

import json
import math
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from models.notification import Pulse
from models.pulse import process_pulse
from models.triage.decision import RECOMMENDATION_RECORD_CORRUPT
from service.cases.examples import EXAMPLE_NOTIFICATIONS
from service.cases.notification import CrashNotificationIn
from service.cases.veds import read_veds
from tests.models import test_pulse, test_pulse_plausibility
from tests.support import ApiClient, example

VEDS_DIR = Path(__file__).parent / "veds"


def _alternating_body() -> dict[str, Any]:
    """The issue's record: +/-400 g at every sample, 10 kHz, 100 ms."""
    body = example("acceleration")
    n = 1000
    body["crash"]["pulse"] = {
        "kind": "acceleration",
        "sample_rate_hz": 10_000,
        "longitudinal_g": [400.0 * (-1) ** k for k in range(n)],
        "lateral_g": [0.0] * n,
    }
    return body


def test_an_alternating_acceleration_record_flags_every_occupant(api: ApiClient) -> None:
    body = _alternating_body()
    body["occupants"].append({**body["occupants"][0], "seat": "driver", "belted": True})
    r = api.client.post("/v1/cases", json=body, headers=api.headers("submitter"))
    assert r.status_code == 201, r.text
    result = r.json()
    corrupt = [a for a in result["assumptions"] if a["code"] == "pulse_looks_corrupt"]
    assert len(corrupt) == 1, result["assumptions"]
    assert "`longitudinal_g` changes sign at 100% of its samples" in corrupt[0]["message"]
    for decided in [result["triage"], *(o["triage"] for o in result["occupants"])]:
        assert decided["iss15_plus"] is True
        assert decided["recommendation"] == RECOMMENDATION_RECORD_CORRUPT
        # the probability is kept as computed: low, which is why it is not trusted
        assert decided["probability"] < decided["threshold"]
    stored = api.client.get(f"/v1/cases/{result['case_id']}", headers=api.headers("auditor"))
    assert stored.json()["result"] == result


def _shipped_pulses() -> list[tuple[str, Pulse]]:
    """Every pulse the project ships: the documented examples, the VEDS documents, and
    the EDR and acceleration records the tests treat as physical."""
    pulses: list[tuple[str, Pulse]] = []
    for kind, documented in EXAMPLE_NOTIFICATIONS.items():
        notification, _ = CrashNotificationIn.from_json(json.dumps(documented["value"]))
        pulses.append((f"example {kind}", notification.to_engine()[0].pulse))
    for doc in sorted(VEDS_DIR.glob("*.xml")):
        mapped = read_veds(doc.read_bytes(), received_at=datetime.now(UTC))
        pulses.append((f"veds {doc.name}", mapped.notification.to_engine()[0].pulse))
    records = [
        [0, -8, -20, -32, -40, -37, -34, -34, -40, -48, -55, -52, -48, -48, -48],
        [0, -10, -22, -34, -44, -49, -50, -47, -43, -41, -40, -40, -40, -40],
        [0, -8, -18, -30, -42, -52, -58, -60, -60, -60, -60, -60],
    ]
    for i, rec in enumerate(records):
        pulses.append((f"edr record {i}", test_pulse_plausibility._record(rec)))
    for dv, pdof in ((15.0, 0.0), (50.0, 90.0), (90.0, 180.0), (40.0, 270.0)):
        pulses.append((f"acceleration {dv} {pdof}", test_pulse._accel_pulse(dv, pdof)))
        pulses.append((f"edr {dv} {pdof}", test_pulse._edr_record(dv, pdof)))
    rng = np.random.default_rng(7)  # the filter test's ringing and noise
    t = np.arange(int(0.25 * test_pulse.RATE_HZ) + 1) / test_pulse.RATE_HZ
    noise = 5.0 * np.sin(2 * math.pi * 400.0 * t) + rng.normal(0.0, 2.0, t.size)
    pulses.append(("acceleration with noise", test_pulse._accel_pulse(50.0, 0.0, noise=noise)))
    pulses.append(("acceleration at 1 kHz", test_pulse._accel_pulse(40.0, 90.0, rate_hz=1_000.0)))
    return pulses


def test_no_shipped_pulse_raises_a_false_alarm() -> None:
    pulses = _shipped_pulses()
    assert {"example acceleration", "example delta_v", "example summary"} <= {n for n, _ in pulses}
    alarms = {name: process_pulse(p).nonphysical for name, p in pulses}
    assert {name: why for name, why in alarms.items() if why is not None} == {}


@pytest.mark.parametrize("kind", sorted(EXAMPLE_NOTIFICATIONS))
def test_no_documented_example_is_decided_as_corrupt(api: ApiClient, kind: str) -> None:
    r = api.client.post("/v1/cases", json=example(kind), headers=api.headers("submitter"))
    assert r.status_code == 201, r.text
    result = r.json()
    assert "pulse_looks_corrupt" not in {a["code"] for a in result["assumptions"]}
    for o in result["occupants"]:
        assert o["triage"]["iss15_plus"] == (o["triage"]["probability"] >= o["triage"]["threshold"])
