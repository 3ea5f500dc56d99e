"""Determinism on one machine: the same notification gives the same result bytes.

Across machines the engine's floats may differ in the last bits (CPU-dependent
numpy, BLAS, libm and numba code paths: tests/tolerance.py), so tests compare
stored figures within a tolerance. On one machine, with one build of the
libraries, the answer must not depend on anything else: the service's result JSON
(everything but the per-step timings) is the same bytes when the notification is
evaluated twice in one process, and in two fresh processes with different hash
seeds (set and dict iteration orders) and BLAS thread counts.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from datetime import UTC, datetime

import pytest

from models.triage import EngineModels, load_engine_models
from service.cases.examples import EXAMPLE_NOTIFICATIONS
from service.cases.notification import CrashNotificationIn
from service.cases.service import evaluate
from tests.paths import ROOT

RECEIVED_AT = datetime(2026, 12, 3, 12, 0, tzinfo=UTC)

#: Evaluates each notification of stdin (one JSON a line) as the service does and
#: writes its result JSON (timings excluded) to stdout, one a line.
_SCRIPT = """
import sys
from datetime import datetime
from models.triage import load_engine_models
from service.cases.service import evaluate
from service.cases.notification import CrashNotificationIn
from tests.paths import ROOT

models = load_engine_models()
received_at = datetime.fromisoformat(sys.argv[1])
for line in sys.stdin:
    n = CrashNotificationIn.model_validate_json(line)
    r = evaluate(n, models, case_id=None, received_at=received_at)
    sys.stdout.write(r.model_dump_json(exclude={"timings_ms"}) + "\\n")
"""


def _notifications() -> list[str]:
    """The documented examples (summary, delta-V and acceleration pulses; frontal and
    side occupants, surrogate intervals) with fixed event ids."""
    return [
        json.dumps({**EXAMPLE_NOTIFICATIONS[kind]["value"], "event_id": f"determinism-{kind}"})
        for kind in sorted(EXAMPLE_NOTIFICATIONS)
    ]


def _result_bytes(text: str, models: EngineModels) -> bytes:
    result = evaluate(
        CrashNotificationIn.model_validate_json(text),
        models,
        case_id=None,
        received_at=RECEIVED_AT,
    )
    return result.model_dump_json(exclude={"timings_ms"}).encode()


@pytest.fixture(scope="module")
def models() -> EngineModels:
    return load_engine_models()


def test_same_notification_twice_in_one_process_gives_the_same_bytes(
    models: EngineModels,
) -> None:
    for text in _notifications():
        first = _result_bytes(text, models)
        assert b'"method":"lpm"' in first, "the occupant models answer (not only the baseline)"
        assert _result_bytes(text, models) == first


def test_same_notification_in_two_processes_gives_the_same_bytes(models: EngineModels) -> None:
    texts = _notifications()
    stdin = "".join(t + "\n" for t in texts)
    procs = []
    # other hash seeds, and other BLAS thread counts while the models load (the
    # surrogates' calibration runs matrix products at load: they must not depend on it)
    for seed in ("1", "2"):
        env = {**os.environ, "PYTHONHASHSEED": seed, "OPENBLAS_NUM_THREADS": seed}
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
        procs.append(
            subprocess.Popen(
                [sys.executable, "-c", _SCRIPT, RECEIVED_AT.isoformat()],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                env=env,
                cwd=ROOT,
            )
        )
    outputs = []
    for p in procs:
        out, err = p.communicate(stdin.encode(), timeout=600)
        assert p.returncode == 0, err.decode()[-2000:]
        outputs.append(out)
    assert outputs[0] == outputs[1]
    lines = outputs[0].splitlines()
    assert len(lines) == len(texts)
    # and the same bytes as this process (the service's own serialisation)
    assert lines == [_result_bytes(t, models) for t in texts]
