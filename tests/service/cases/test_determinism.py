"""Determinism on one machine: the same notification gives the same result bytes.

Across machines the engine's floats may differ in the last bits (CPU-dependent
numpy, BLAS, libm and numba code paths: tests/tolerance.py), so tests compare
stored figures within a tolerance. On one machine, with one build of the
libraries, the answer must not depend on anything else: the service's result JSON
(everything but the per-step timings) is the same bytes when the notification is
evaluated twice in one process, and in two fresh processes with different hash
seeds (set and dict iteration orders) and BLAS thread counts, and whether the
occupants of a notification are computed one after the other or on several
threads, one request at a time or several at once.
"""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
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


def _occupant_rich_notifications() -> list[str]:
    """The documented examples and the pinned notifications (several with two or more
    occupants in the occupant models' coverage, and rear seats), fixed event ids."""
    from tests.decision_pins import notifications

    pinned = [
        json.dumps({**doc, "event_id": f"threads-{name}"})
        for name, doc in sorted(notifications().items())
    ]
    return _notifications() + pinned


def test_occupants_on_several_threads_give_the_same_bytes(models: EngineModels) -> None:
    texts = _occupant_rich_notifications()
    assert any(len(json.loads(t)["occupants"]) >= 2 for t in texts)
    one = dataclasses.replace(models, occupant_threads=1)
    expected = [_result_bytes(t, one) for t in texts]
    for threads in (2, 3):
        several = dataclasses.replace(models, occupant_threads=threads)
        assert [_result_bytes(t, several) for t in texts] == expected, threads


def test_concurrent_requests_sharing_the_occupant_pool_give_the_same_bytes(
    models: EngineModels,
) -> None:
    """Requests on several threads at once (as `serve` runs them), every one handing
    occupants to the same helper pool: each answer is the one-thread answer."""
    texts = _occupant_rich_notifications()
    one = dataclasses.replace(models, occupant_threads=1)
    expected = {t: _result_bytes(t, one) for t in texts}
    several = dataclasses.replace(models, occupant_threads=2)
    with ThreadPoolExecutor(max_workers=4) as requests:
        answers = list(requests.map(lambda t: (t, _result_bytes(t, several)), texts * 3))
    assert all(answer == expected[t] for t, answer in answers)
