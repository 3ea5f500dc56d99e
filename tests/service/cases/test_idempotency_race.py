"""Concurrent submissions of one event: one case is stored, the others replay it."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor
from datetime import UTC, datetime

from service.auth import Caller, Role
from service.cases import service as cases_service
from service.cases.notification import CrashNotificationIn
from tests.support import ApiClient, summary


def test_concurrent_duplicates_store_one_case(api_any_db: ApiClient) -> None:
    ctx = api_any_db.client.app.state.ctx  # type: ignore[attr-defined]
    body = summary(event_id="evt-race")
    notification = CrashNotificationIn.model_validate(body)
    caller = Caller(key_id=1, name="submitter-client", role=Role.SUBMITTER)
    start = threading.Barrier(4)

    def submit(_: int) -> cases_service.SubmitOutcome:
        start.wait()
        return cases_service.submit(ctx, notification, body, caller, datetime.now(UTC))

    with ThreadPoolExecutor(max_workers=4) as pool:
        outcomes = list(pool.map(submit, range(4)))
    case_ids = {o.result.case_id for o in outcomes}
    assert len(case_ids) == 1, "every duplicate answers with the one stored case"
    assert sum(not o.replayed for o in outcomes) == 1
    listing = api_any_db.client.get("/v1/cases", headers=api_any_db.headers("auditor")).json()
    assert [c["case_id"] for c in listing["items"]] == list(case_ids)
