"""The decided probabilities of a fixed set of notifications, pinned (issue 51).

A speed-up of the engine must give the same decisions: the field risk model's
probability, its 95 % interval, the range over the unknown inputs, the threshold
and the tier of every occupant and of the vehicle, and the case's decision. This
module names the notifications (the README's, the OpenAPI examples and a few
varied ones: side, rear, rollover, unknown ages, measured and reconstructed
delta-V, children, several occupants), extracts those fields from the service's
answer, and writes them (``python -m tests.decision_pins``) to
``tests/decision_pins.json``, with the occupant models' explanation beside them.
Floats are stored as JSON numbers written by :func:`repr` (which reads back to
the same double) and as :meth:`float.hex`. The pins are written at the commit the
file names, by a model release only (field model 3.4.0 rewrote them: its answers
are not 3.3.1's); a speed-up holds the answers to them bit for bit
(``tests/service/cases/test_decision_pins.py``).
"""

from __future__ import annotations

import json
import os
import platform
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from models.offline.field.readme import README_EXAMPLE
from tests.paths import ROOT

PINS_PATH = ROOT / "tests" / "decision_pins.json"
RECEIVED_AT = datetime(2026, 12, 7, 12, 0, tzinfo=UTC)

#: Environment variables that change the floating-point code paths (``.ci/run``).
FLOAT_PATH_ENV = (
    "NUMBA_CPU_NAME",
    "NPY_DISABLE_CPU_FEATURES",
    "OPENBLAS_CORETYPE",
    "GLIBC_TUNABLES",
)

_DRIVER = README_EXAMPLE["occupants"][0]  # the README's belted 42-year-old driver
#: The second occupant of issue 51's benchmark notification.
FRONT_PASSENGER = {
    "seat": "front_passenger",
    "stature_cm": 160,
    "mass_kg": 55,
    "age_years": 38,
    "sex": "female",
    "belted": True,
    "frontal_airbag": "deployed",
}


def _summary(dv: float, pdof: float, **extra: Any) -> dict[str, Any]:
    return {"kind": "summary", "delta_v_kmh": dv, "pdof_deg": pdof, **extra}


def _case(
    event_id: str, pulse: dict[str, Any], occupants: list[dict[str, Any]], **crash: Any
) -> Any:
    return {
        "event_id": event_id,
        "occurred_at": "2026-11-23T08:15:30Z",
        "crash": {"pulse": pulse, **crash},
        "occupants": occupants,
    }


def readme_two_occupants() -> dict[str, Any]:
    """The README's "Try it" notification with issue 51's front passenger added."""
    return _case("tsp-0001", _summary(40, 0), [_DRIVER, FRONT_PASSENGER])


def notifications() -> dict[str, dict[str, Any]]:
    """The pinned notifications by name (wire JSON documents)."""
    from service.cases.examples import EXAMPLE_NOTIFICATIONS

    out: dict[str, dict[str, Any]] = {
        f"example_{k}": v["value"] for k, v in sorted(EXAMPLE_NOTIFICATIONS.items())
    }
    unbelted_old = {
        "seat": "driver",
        "stature_cm": 175,
        "mass_kg": 78,
        "age_years": 70,
        "sex": "male",
        "belted": False,
        "frontal_airbag": "absent",
    }
    young_woman = {
        "seat": "driver",
        "stature_cm": 165,
        "mass_kg": 62,
        "age_years": 30,
        "sex": "female",
        "belted": True,
        "frontal_airbag": "not_deployed",
    }
    unknown_age = {"seat": "driver", "belted": True, "frontal_airbag": "deployed"}
    child = {
        "seat": "rear_right",
        "age_years": 6,
        "stature_cm": 115,
        "mass_kg": 21,
        "sex": "female",
        "belted": True,
        "frontal_airbag": "not_deployed",
    }
    rear_unknown = {"seat": "rear_left", "belted": True, "frontal_airbag": "not_deployed"}
    out.update(
        {
            "readme_try_it": _case("tsp-0001", _summary(40, 0), [_DRIVER]),
            "readme_two_occupants": readme_two_occupants(),
            "readme_high": _case("tsp-high", _summary(70, 0), [unbelted_old]),
            "readme_moderate": _case("tsp-moderate", _summary(60, 0), [_DRIVER]),
            "readme_none": _case("tsp-none", _summary(15, 0), [young_woman]),
            "near_side_left": _case("v-side-l", _summary(35, 270), [_DRIVER, FRONT_PASSENGER]),
            "side_right": _case("v-side-r", _summary(45, 90), [_DRIVER, FRONT_PASSENGER]),
            "oblique": _case("v-oblique", _summary(50, 330), [_DRIVER]),
            "rear": _case("v-rear", _summary(25, 180), [_DRIVER, FRONT_PASSENGER]),
            "rollover": _case(
                "v-roll", _summary(30, 0), [unbelted_old], rollover=True, multiple_impacts=True
            ),
            "unknown_ages": _case("v-unknown", _summary(55, 0), [unknown_age, rear_unknown]),
            "reconstructed": _case(
                "v-recon", _summary(55, 0, delta_v_source="reconstructed"), [_DRIVER]
            ),
            "measured_long": _case("v-meas", _summary(65, 10), [_DRIVER, FRONT_PASSENGER]),
            "children": _case(
                "v-child", _summary(45, 0), [_DRIVER, child, {**child, "seat": "rear_left"}]
            ),
            "several": _case(
                "v-several",
                _summary(62, 350),
                [
                    _DRIVER,
                    FRONT_PASSENGER,
                    child,
                    rear_unknown,
                    {**unknown_age, "seat": "rear_middle"},
                ],
            ),
            "severe": _case("v-severe", _summary(95, 0), [unbelted_old, FRONT_PASSENGER]),
        }
    )
    return out


_DECISION_KEYS = (
    "iss15_plus",
    "probability",
    "probability_ci95",
    "unknown_inputs_range95",
    "threshold",
    "tier",
    "high_threshold",
    "knowledge",
)
_VEHICLE_KEYS = ("probability", "probability_ci95", "threshold", "tier")
_EXPLANATION_KEYS = (
    "method",
    "measures",
    "measures_ci95",
    "probability_uncorrected",
    "probability_zero_load",
)


def _pick(d: dict[str, Any] | None, keys: tuple[str, ...]) -> dict[str, Any] | None:
    return None if d is None else {k: d.get(k) for k in keys}


def pinned_fields(answer: dict[str, Any]) -> dict[str, Any]:
    """The decision (and, apart, the explanation) of a service answer (``model_dump``)."""
    occupants = answer["occupants"]
    return {
        "decision": {
            "triage": _pick(answer["triage"], _DECISION_KEYS),
            "vehicle": _pick(answer.get("vehicle"), _VEHICLE_KEYS),
            "occupants": [_pick(o["triage"], _DECISION_KEYS) for o in occupants],
        },
        "explanation": [
            {
                **(_pick(o, _EXPLANATION_KEYS) or {}),
                "occupant_model": _pick(
                    o.get("occupant_model"), ("probability", "probability_ci95", "iss15_plus")
                ),
                "iss_ci95": None if o.get("iss") is None else o["iss"]["ci95"],
            }
            for o in occupants
        ],
    }


def answer(document: dict[str, Any], models: Any) -> dict[str, Any]:
    """The service's answer to a wire document (no database), as a plain dict."""
    from service.cases.notification import CrashNotificationIn
    from service.cases.service import evaluate

    n = CrashNotificationIn.model_validate_json(json.dumps(document))
    result = evaluate(n, models, case_id=None, received_at=RECEIVED_AT)
    return result.model_dump(mode="json", exclude={"timings_ms"})


def host_signature() -> dict[str, Any]:
    """What decides the floating-point code paths here: CPU, library versions, overrides."""
    import numba
    import numpy
    import scipy

    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith(("model name", "flags")):
                cpu += line.split(":", 1)[1].strip() + ";"
            if line.startswith("flags"):
                break
    except OSError:
        pass
    return {
        "machine": platform.machine(),
        "cpu": cpu,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
        "python": platform.python_version(),
        "env": {k: os.environ.get(k) for k in FLOAT_PATH_ENV},
    }


def _hexed(value: Any) -> Any:
    if isinstance(value, float):
        return value.hex()
    if isinstance(value, dict):
        return {k: _hexed(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_hexed(v) for v in value]
    return value


def compute_pins(models: Any) -> dict[str, Any]:
    """Every pinned notification's fields (the JSON the pins file holds, without its header)."""
    return {name: pinned_fields(answer(doc, models)) for name, doc in notifications().items()}


def main() -> None:
    """Write the pins file from the engine as it is now."""
    import subprocess

    from models.triage import load_engine_models

    pins = compute_pins(load_engine_models())
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=ROOT
    ).stdout.strip()
    doc = {
        "about": "Decided probabilities pinned at the commit named (tests/decision_pins.py).",
        "commit": commit,
        "host": host_signature(),
        "pins": pins,
        "pins_hex": {k: _hexed(v["decision"]) for k, v in pins.items()},
    }
    PINS_PATH.write_text(json.dumps(doc, indent=1, sort_keys=True) + "\n")
    sys.stdout.write(f"wrote {len(pins)} notifications to {PINS_PATH}\n")


if __name__ == "__main__":
    main()
