"""The start-up log is quiet: no Alembic chatter, one line per migration.

A real ``serve`` (this interpreter's, on a fresh SQLite file, so it migrates) is
started and stopped; its log has no line of Alembic's loggers (a line per plugin and
per migration context at INFO before), and the one ``database migrated`` line.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tests.support import free_port, wait_ready


def test_serve_start_up_log_has_no_alembic_lines(tmp_path: Path) -> None:
    port = free_port()
    log = tmp_path / "serve.log"
    env = {
        **os.environ,
        "AACN_DATABASE_URL": f"sqlite:///{tmp_path / 'a.db'}",
        "AACN_SPOOL_PATH": str(tmp_path / "spool.db"),
        "AACN_LOG_LEVEL": "INFO",
    }
    cmd = [sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--workers", "1"]
    with log.open("w") as sink:
        server = subprocess.Popen(cmd, env=env, stdout=sink, stderr=subprocess.STDOUT)
    try:
        wait_ready(f"http://127.0.0.1:{port}", server, log, timeout_s=300)
    finally:
        server.terminate()
        server.wait(timeout=60)
    records = [json.loads(line) for line in log.read_text().splitlines() if line.startswith("{")]
    assert records, log.read_text()[-2000:]
    assert not [r for r in records if r["logger"].startswith("alembic")]
    migrated = [r for r in records if r["message"] == "database migrated"]
    assert len(migrated) == 1, migrated
    assert migrated[0]["from_revision"] == "base"
