"""Replicas behind a real nginx, one killed mid-load (`tests.replicas`).

Three ``aacn-triage serve`` processes on one real PostgreSQL database behind
Debian's nginx with the repository's site configuration. Several hundred POSTs
from several threads, some replaying an earlier ``event_id`` and some conflicting
with it; one replica is killed with SIGKILL mid-load and started again. Every
acknowledged case is stored exactly once under the case id it was answered with,
replays and 409s hold whichever replica answers, nginx routes around the dead
replica and back to it once restarted, and no client is left with a 5xx (the ones
it may retry, and why: `tests.replicas`).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests.replicas import LoadPlan, deployment, find_nginx, run_load

pytestmark = pytest.mark.postgres


def test_a_replica_killed_mid_load_loses_and_doubles_nothing(
    postgres_url: str, tmp_path: Path
) -> None:
    binary = find_nginx()
    if binary is None:
        if os.environ.get("CI"):
            pytest.fail("no nginx binary in CI: .ci/run installs Debian's nginx")
        pytest.skip("no nginx binary: apt-get install nginx (.ci/run installs it)")
    with deployment(postgres_url, tmp_path, binary) as (nginx, replicas, key):
        report = run_load(nginx, replicas, key, LoadPlan(), postgres_url, victim=1)
    figures = report.figures()
    assert not report.problems(), (report.problems()[:20], figures)
    assert figures["duplicates"] == 0
    assert figures["lost"] == 0
    assert figures["stored"] == figures["events_acknowledged"]
    assert figures["conflict_409"] > 0, "the plan holds conflicts"
    assert figures["replayed_200"] > 0, "the plan holds replays"
    assert figures["served_by_killed_after_restart"] > 0, "nginx sends to the restarted replica"
