"""The frame every HTML page of the service shares, whichever feature draws it.

- the templates: :func:`template_environment` gives a feature a Jinja2 environment over
  its own ``templates/`` and the frame's (``service/templates/``: ``base.html``, the
  sign-in form ``login.html``, ``error.html``); the stylesheet and icon that
  ``base.html`` links are ``service/static/`` (mounted by the app at ``/static``);
- the answer: :func:`html_response` with the pages' headers (a strict
  Content-Security-Policy: everything from the service itself, no script at all);
- the gate: :func:`gate` lets an auditor or admin through (a Bearer key, or the
  signed session cookie of ``service.browser_session``) and answers anyone else with
  the sign-in form (401) or the error page (403);
- what each page's frame shows (:func:`chrome`: the root path, signed in, the logout
  token) and how a page's form writes a time (:func:`form_time`).

The sign-in routes that the form posts to are ``service.sign_in``.
"""

from __future__ import annotations

import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from fastapi import Request
from fastapi.responses import HTMLResponse, Response
from jinja2 import Environment, FileSystemLoader, StrictUndefined, select_autoescape

from service.auth import Caller, Role, caller_for_key, caller_for_key_id
from service.browser_session import (
    SESSION_COOKIE,
    BrowserSession,
    logout_token,
    new_login_csrf,
    read_session,
    set_login_csrf_cookie,
)
from service.browser_session_end import session_has_ended
from service.context import ServiceContext

__all__ = [
    "CONTENT_SECURITY_POLICY",
    "PAGE_ROLES",
    "SECURITY_HEADERS",
    "STATIC_DIR",
    "TEMPLATES_DIR",
    "chrome",
    "error_page",
    "form_time",
    "gate",
    "html_response",
    "login_page",
    "root_path",
    "safe_next",
    "template_environment",
]

#: The frame's templates (``base.html``, ``login.html``, ``error.html``).
TEMPLATES_DIR = Path(__file__).resolve().parent / "templates"
#: The pages' stylesheet and icon (package data), served at ``/static``.
STATIC_DIR = Path(__file__).resolve().parent / "static"

#: Roles that may read the pages (as ``GET /v1/cases``).
PAGE_ROLES = frozenset({Role.AUDITOR, Role.ADMIN})
#: Everything comes from the service itself; no script at all.
CONTENT_SECURITY_POLICY = (
    "default-src 'none'; style-src 'self'; img-src 'self'; form-action 'self'; "
    "frame-ancestors 'none'; base-uri 'none'"
)
SECURITY_HEADERS = {
    "Content-Security-Policy": CONTENT_SECURITY_POLICY,
    "X-Content-Type-Options": "nosniff",
    "Cache-Control": "no-store",
    "Referrer-Policy": "same-origin",
    "X-Frame-Options": "DENY",
}
#: Hosts on which browsers keep Secure cookies over plain HTTP.
_LOOPBACK = frozenset({"localhost", "127.0.0.1", "::1", "[::1]"})


def template_environment(*directories: Path) -> Environment:
    """A Jinja2 environment over a feature's template directories, then the frame's.

    One per feature and process: templates compile once and are cached. Autoescaped,
    strict about undefined names; a feature's template extends ``base.html``.
    """
    return Environment(
        loader=FileSystemLoader([*directories, TEMPLATES_DIR]),
        autoescape=select_autoescape(default=True, default_for_string=True),
        undefined=StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        auto_reload=False,
    )


_FRAME = template_environment()


def html_response(body: str, status: int = 200, *, started: float | None = None) -> HTMLResponse:
    """A page with the pages' headers; with ``started`` (``time.perf_counter()``), the
    time to read and render it as ``Server-Timing``."""
    headers = dict(SECURITY_HEADERS)
    if started is not None:
        ms = 1000.0 * (time.perf_counter() - started)
        headers["Server-Timing"] = f'app;dur={ms:.1f};desc="read and render"'
    return HTMLResponse(body, status_code=status, headers=headers)


def root_path(request: Request) -> str:
    """The path the service is mounted under (no trailing slash; empty at the root)."""
    return str(request.scope.get("root_path", "")).rstrip("/")


def chrome(request: Request, ctx: ServiceContext, session: BrowserSession | None) -> dict[str, Any]:
    """What every page's frame needs: the root path, sign-in state, the logout token."""
    return {
        "root": root_path(request),
        "signed_in": True,
        "logout_token": logout_token(ctx.session_secret, session) if session else "",
    }


def safe_next(request: Request, value: str | None) -> str:
    """A local page to return to after signing in (never another site)."""
    root = root_path(request)
    default = f"{root}/v1/reports"
    if not value or not value.startswith(f"{root}/v1/") or value.startswith("//"):
        return default
    if "\\" in value or any(ord(ch) < 0x21 or ord(ch) > 0x7E for ch in value):
        return default
    return value


def error_page(
    request: Request, status: int, title: str, detail: str, *, signed_in: bool = False
) -> HTMLResponse:
    """The error page: a status, a title and what happened, in the frame."""
    body = _FRAME.get_template("error.html").render(
        status=status,
        title=title,
        detail=detail,
        root=root_path(request),
        signed_in=signed_in,
        logout_token="",
    )
    return html_response(body, status)


def login_page(
    request: Request,
    ctx: ServiceContext,
    *,
    status: int,
    message: str = "",
    next_url: str | None = None,
) -> HTMLResponse:
    """The sign-in form (with a fresh login CSRF token and its cookie); a 401 names the
    Bearer scheme too."""
    token = new_login_csrf(ctx.session_secret, now=time.time())
    plain_http = request.url.scheme != "https" and request.url.hostname not in _LOOPBACK
    body = _FRAME.get_template("login.html").render(
        plain_http=plain_http,
        root=root_path(request),
        signed_in=False,
        logout_token="",
        message=message,
        csrf_token=token,
        next_url=safe_next(request, next_url),
        ttl_minutes=max(1, ctx.settings.session_ttl_s // 60),
    )
    response = html_response(body, status)
    if status == 401:
        response.headers["WWW-Authenticate"] = 'Bearer realm="aacn-triage"'
    set_login_csrf_cookie(response, token)
    return response


def _identify(request: Request, ctx: ServiceContext) -> tuple[Caller | None, BrowserSession | None]:
    """The caller of a page request: a Bearer key, else a valid session cookie."""
    header = request.headers.get("authorization")
    if header:
        scheme, _, key = header.partition(" ")
        if scheme.lower() == "bearer" and key.strip():
            return caller_for_key(ctx.sessions, key.strip()), None
        return None, None
    session = read_session(ctx.session_secret, request.cookies.get(SESSION_COOKIE), now=time.time())
    if session is None or session_has_ended(ctx.sessions, session):
        return None, None
    caller = caller_for_key_id(ctx.sessions, session.key_id, session.key_tag)
    return caller, session if caller is not None else None


def gate(request: Request, ctx: ServiceContext) -> Response | BrowserSession | None:
    """A refusal page, or the session (None for a Bearer caller) of an allowed caller."""
    caller, session = _identify(request, ctx)
    if caller is None:
        here = request.url.path + (f"?{request.url.query}" if request.url.query else "")
        return login_page(
            request,
            ctx,
            status=401,
            message="Sign in to see this page."
            if SESSION_COOKIE not in request.cookies
            else "Your session has ended or its key was revoked: sign in again.",
            next_url=here,
        )
    if caller.role not in PAGE_ROLES:
        return error_page(
            request,
            403,
            "Role not allowed",
            f"The key {caller.name!r} has role {caller.role.value!r}; the case pages need "
            "auditor or admin.",
        )
    return session


def form_time(value: str, name: str) -> datetime | None:
    """A page filter's time: RFC 3339, or a datetime-local form value (taken as UTC).

    Raises
    ------
    ValueError
        In the reader's words, naming the field (``name``).
    """
    if not value.strip():
        return None
    try:
        at = datetime.fromisoformat(value.strip())
    except ValueError as exc:
        raise ValueError(f"{name} is not a date and time (e.g. 2026-11-23T08:15).") from exc
    return at.replace(tzinfo=UTC) if at.tzinfo is None else at.astimezone(UTC)
