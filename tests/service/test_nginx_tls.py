"""The TLS site of the nginx recipe: HTTPS to a served process, HSTS once, sign-in.

Debian's nginx with ``deploy/nginx/aacn-triage-tls.conf`` (a throwaway self-signed
certificate, loopback ports) in front of the real ``aacn-triage serve``.
"""

from __future__ import annotations

import os
import re
import shutil
import ssl
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import httpx2 as httpx
import pytest

from tests.paths import ROOT
from tests.replicas import find_nginx
from tests.service.pages_support import csrf_token
from tests.support import console_server, free_port

SITES = ROOT / "deploy" / "nginx"
TLS_SITE = SITES / "aacn-triage-tls.conf"


def _location(conf: Path) -> str:
    text = conf.read_text(encoding="utf-8")
    match = re.search(r"\n    location / \{.*?\n    \}\n", text, re.S)
    assert match, conf
    return match.group(0)


def test_the_tls_site_proxies_as_the_plain_one() -> None:
    assert _location(TLS_SITE) == _location(SITES / "aacn-triage.conf")


def _self_signed(directory: Path) -> tuple[Path, Path]:
    if shutil.which("openssl") is None:
        pytest.skip("openssl is not installed")
    cert, key = directory / "cert.pem", directory / "key.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1"]
        + ["-subj", "/CN=localhost", "-addext", "subjectAltName=DNS:localhost,IP:127.0.0.1"]
        + ["-keyout", str(key), "-out", str(cert)],
        check=True,
        capture_output=True,
        timeout=60,
    )
    return cert, key


@pytest.fixture
def behind_tls(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> Iterator[tuple[str, str, str, str]]:
    """(https base, http base, admin key, certificate): nginx's TLS site before one `serve`."""
    nginx = find_nginx()
    if nginx is None:
        pytest.skip("nginx is not installed")
    cert, key = _self_signed(tmp_path)
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    monkeypatch.setenv("AACN_SESSION_SECRET", "t" * 40)
    with console_server(tmp_path, "--workers", "1") as (_, upstream, admin, _log):
        prefix = tmp_path / "nginx"
        for sub in ("client_body", "proxy", "fastcgi", "uwsgi", "scgi"):
            (prefix / "temp" / sub).mkdir(parents=True, exist_ok=True)
        https_port, http_port = free_port(), free_port()
        site = TLS_SITE.read_text(encoding="utf-8")
        for old, new in (
            ("listen 80;", f"listen 127.0.0.1:{http_port};"),
            ("listen 443 ssl http2;", f"listen 127.0.0.1:{https_port} ssl http2;"),
            ("/etc/ssl/aacn-triage/fullchain.pem", str(cert)),
            ("/etc/ssl/aacn-triage/privkey.pem", str(key)),
        ):
            assert old in site, old
            site = site.replace(old, new)
        (prefix / "site.conf").write_text(site, encoding="utf-8")
        t = prefix / "temp"
        user = "user root;\n" if os.geteuid() == 0 else ""
        conf = prefix / "nginx.conf"
        conf.write_text(
            f"""{user}daemon off;
worker_processes 1;
pid {prefix}/nginx.pid;
error_log {prefix}/error.log warn;
events {{ worker_connections 64; }}
http {{
    access_log off;
    client_body_temp_path {t}/client_body;
    proxy_temp_path {t}/proxy;
    fastcgi_temp_path {t}/fastcgi;
    uwsgi_temp_path {t}/uwsgi;
    scgi_temp_path {t}/scgi;
    upstream aacn_triage {{
        server {upstream.removeprefix("http://")};
        keepalive 4;
    }}
    include {prefix}/site.conf;
}}
""",
            encoding="utf-8",
        )
        check = subprocess.run(
            [nginx, "-t", "-p", str(prefix), "-c", str(conf)], capture_output=True, text=True
        )
        assert check.returncode == 0, check.stderr
        proc = subprocess.Popen(
            [nginx, "-p", str(prefix), "-c", str(conf)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        base = f"https://127.0.0.1:{https_port}"
        try:
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                try:
                    httpx.get(
                        base + "/livez", verify=ssl.create_default_context(cafile=cert), timeout=2
                    )
                    break
                except httpx.TransportError:
                    time.sleep(0.1)
            yield base, f"http://127.0.0.1:{http_port}", admin, str(cert)
        finally:
            proc.terminate()
            proc.wait(timeout=30)


def test_https_through_nginx_sends_hsts_once_and_signs_in(
    behind_tls: tuple[str, str, str, str],
) -> None:
    base, plain, admin, cert = behind_tls
    trust = ssl.create_default_context(cafile=cert)
    with httpx.Client(base_url=base, verify=trust, timeout=30, follow_redirects=False) as c:
        live = c.get("/livez")
        assert live.status_code == 200
        assert live.headers.get_list("strict-transport-security") == ["max-age=31536000"]
        # the Secure session cookie is kept over HTTPS: sign in, then a page
        form = c.get("/v1/session", params={"next": "/v1/reports"})
        r = c.post(
            "/v1/session",
            data={"csrf_token": csrf_token(form.text), "api_key": admin, "next": "/v1/reports"},
        )
        assert r.status_code == 303, r.text[:300]
        assert c.get("/v1/reports").status_code == 200
    # plain HTTP only redirects, keeping the method
    redirect = httpx.post(plain + "/v1/cases", content=b"{}", timeout=10)
    assert redirect.status_code == 308
    assert redirect.headers["location"].startswith("https://127.0.0.1/v1/cases")
    assert "strict-transport-security" not in redirect.headers
