"""Shared fixtures: real SQLite files, a real PostgreSQL server, the app, API keys.

PostgreSQL: `AACN_TEST_POSTGRES_URL` (a server you run) is used when set;
otherwise the fixture starts a throwaway cluster with the installed server
binaries (initdb + pg_ctl, as the `postgres` user when run as root) on a free
loopback port, and stops it at the end. PostgreSQL tests are skipped, with the
reason, only when neither works.
"""

from __future__ import annotations

import glob
import os
import shutil
import socket
import subprocess
import tempfile
import uuid
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from hypothesis import settings as hypothesis_settings
from sqlalchemy import create_engine, text

from service.app import create_app
from service.auth import Role, create_api_key
from service.settings import Settings
from tests.support import ApiClient

# Property tests draw the same examples on every run (no flaky CI); run with
# HYPOTHESIS_PROFILE=explore to search new ones.
hypothesis_settings.register_profile("ci", derandomize=True)
hypothesis_settings.register_profile("explore", derandomize=False)
hypothesis_settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

# ----------------------------------------------------------------- PostgreSQL


def _find_pg_bin() -> Path | None:
    found = shutil.which("initdb")
    if found:
        return Path(found).resolve().parent
    candidates = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"), reverse=True)
    return Path(candidates[0]).parent if candidates else None


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class _Cluster:
    admin_url: str
    stop: Callable[[], None]
    #: ``pg_ctl(*args)`` on this cluster, e.g. ``("stop", "-m", "fast")``, ``("start",)``
    pg_ctl: Callable[..., None]


def _start_cluster() -> _Cluster:
    pg_bin = _find_pg_bin()
    if pg_bin is None:
        raise RuntimeError("no PostgreSQL server binaries (initdb) found; install `postgresql`")
    root = Path(tempfile.mkdtemp(prefix="aacn-pg-"))
    data = root / "data"
    prefix: list[str] = []
    user = "postgres"
    if os.geteuid() == 0:
        runuser = shutil.which("runuser")
        if runuser is None:
            raise RuntimeError("running as root without `runuser` to drop to the postgres user")
        import pwd

        try:
            pw = pwd.getpwnam("postgres")
        except KeyError as exc:
            raise RuntimeError("running as root and no `postgres` system user") from exc
        os.chown(root, pw.pw_uid, pw.pw_gid)
        prefix = [runuser, "-u", "postgres", "--"]
    else:
        import getpass

        user = getpass.getuser()
    port = _free_port()

    def run(*cmd: str) -> None:
        subprocess.run(
            [*prefix, *cmd], check=True, capture_output=True, text=True, timeout=120, cwd=root
        )

    def pg_ctl(command: str, *options: str) -> None:
        run(
            str(pg_bin / "pg_ctl"),
            "-D",
            str(data),
            "-l",
            str(root / "server.log"),
            "-w",
            "-t",
            "60",
            "-o",
            f"-c listen_addresses=127.0.0.1 -p {port} -k {root} -c fsync=off",
            command,
            *options,
        )

    try:
        run(str(pg_bin / "initdb"), "-D", str(data), "-A", "trust", "-U", user, "-E", "UTF8")
        pg_ctl("start")
    except subprocess.CalledProcessError as exc:
        shutil.rmtree(root, ignore_errors=True)
        raise RuntimeError(f"could not start PostgreSQL: {exc.stderr.strip()[-500:]}") from exc

    def stop() -> None:
        try:
            run(str(pg_bin / "pg_ctl"), "-D", str(data), "-m", "immediate", "-w", "stop")
        finally:
            shutil.rmtree(root, ignore_errors=True)

    return _Cluster(
        admin_url=f"postgresql+psycopg://{user}@127.0.0.1:{port}/postgres", stop=stop, pg_ctl=pg_ctl
    )


@pytest.fixture(scope="session")
def postgres_admin_url() -> Iterator[str]:
    """URL of a PostgreSQL maintenance database on a real server."""
    given = os.environ.get("AACN_TEST_POSTGRES_URL")
    if given:
        yield given
        return
    try:
        cluster = _start_cluster()
    except (RuntimeError, OSError, subprocess.SubprocessError) as exc:
        pytest.skip(f"PostgreSQL tests skipped: {exc}")
    try:
        yield cluster.admin_url
    finally:
        cluster.stop()


@pytest.fixture
def own_postgres() -> Iterator[_Cluster]:
    """A PostgreSQL cluster of the test's own, which the test may stop and start."""
    if os.environ.get("AACN_TEST_POSTGRES_URL"):
        pytest.skip("needs a cluster the test can stop: unset AACN_TEST_POSTGRES_URL")
    try:
        cluster = _start_cluster()
    except (RuntimeError, OSError, subprocess.SubprocessError) as exc:
        pytest.skip(f"PostgreSQL tests skipped: {exc}")
    try:
        yield cluster
    finally:
        try:
            cluster.stop()
        except subprocess.CalledProcessError:  # stopped by the test already
            pass


@pytest.fixture
def postgres_url(postgres_admin_url: str) -> Iterator[str]:
    """A fresh, empty PostgreSQL database for one test (dropped afterwards)."""
    name = "aacn_test_" + uuid.uuid4().hex[:12]
    admin = create_engine(postgres_admin_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    base, _ = postgres_admin_url.rsplit("/", 1)
    try:
        yield f"{base}/{name}"
    finally:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


# ----------------------------------------------------------------- SQLite


@pytest.fixture
def sqlite_url(tmp_path: Path) -> str:
    """A fresh SQLite file database."""
    return f"sqlite:///{tmp_path / 'aacn.db'}"


# ---------------------------------------------------------------------- app


def _api(url: str, spool_dir: Path, **overrides: object) -> Iterator[ApiClient]:
    overrides.setdefault("spool_path", spool_dir / "spool.db")
    settings = Settings(database_url=url, **overrides)  # type: ignore[arg-type]
    app = create_app(settings)
    with TestClient(app) as client:
        sessions = app.state.ctx.sessions
        keys = {}
        for role in Role:
            _, secret = create_api_key(sessions, name=f"{role.value}-client", role=role)
            keys[role.value] = secret
        _, keys["submitter2"] = create_api_key(sessions, name="other-center", role=Role.SUBMITTER)
        yield ApiClient(client=client, keys=keys, settings=settings)


@pytest.fixture
def api(sqlite_url: str, tmp_path: Path) -> Iterator[ApiClient]:
    """The app on a fresh SQLite file, with keys for every role."""
    yield from _api(sqlite_url, tmp_path)


@pytest.fixture(params=["sqlite", pytest.param("postgres", marks=pytest.mark.postgres)])
def api_any_db(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[ApiClient]:
    """The app on SQLite and on PostgreSQL."""
    if request.param == "sqlite":
        yield from _api(f"sqlite:///{tmp_path / 'aacn.db'}", tmp_path)
    else:
        url = request.getfixturevalue("postgres_url")
        yield from _api(url, tmp_path)
