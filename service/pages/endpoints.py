"""The dispatcher's pages (HTML) and their browser session.

- ``GET /v1/cases/{case_id}/report``: the case page (auditor or admin).
- ``GET /v1/reports``: recent cases with the filters of ``GET /v1/cases``.
- ``GET /v1/quality/report``: triage quality against linked outcomes (``GET /v1/quality``).
- ``GET /v1/session``: the sign-in form; ``POST /v1/session``: sign in with an API
  key (sets the session cookie); ``POST /v1/session/logout``: sign out.

The pages accept a session cookie (``service.browser_session``) or, like the API, an
``Authorization: Bearer`` key. They are HTML resources, kept out of the OpenAPI
document; the JSON API is unchanged. An unauthenticated visit gets 401 with the
sign-in form and no case data.
"""

from __future__ import annotations

import hmac
import re
import time
from datetime import UTC, datetime
from typing import Any
from urllib.parse import parse_qs, quote

from fastapi import APIRouter, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from sqlalchemy.exc import DBAPIError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError

from models.impact_mode import ImpactMode
from models.tiers import Tier
from service.auth import (
    Caller,
    Role,
    caller_for_key,
    caller_for_key_id,
    hash_key,
    session_key_tag,
)
from service.browser_session import (
    COOKIE_PATH,
    LOGIN_CSRF_COOKIE,
    SESSION_COOKIE,
    BrowserSession,
    check_login_csrf,
    clear_session_cookie,
    issue_session,
    logout_token,
    new_login_csrf,
    read_session,
    same_origin,
    set_login_csrf_cookie,
    set_session_cookie,
)
from service.browser_session_end import end_session, session_has_ended
from service.cases import service as cases_service
from service.context import ServiceContext
from service.db.repository import CaseFilters
from service.deps import ContextDep
from service.outcomes.quality import AGE_GROUPS, CRASH_MODES, drift_settings_of, quality_report
from service.pages import views as report
from service.pages.quality_page import filters_from_query, quality_context
from service.problems import UnprocessableNotification

__all__ = ["CONTENT_SECURITY_POLICY", "router"]

router = APIRouter(include_in_schema=False)

#: Roles that may read the pages (as ``GET /v1/cases``).
PAGE_ROLES = frozenset({Role.AUDITOR, Role.ADMIN})
#: Everything comes from the service itself; no script at all.
CONTENT_SECURITY_POLICY = (
    "default-src 'none'; style-src 'self'; img-src 'self'; form-action 'self'; "
    "frame-ancestors 'none'; base-uri 'none'"
)
_SECURITY_HEADERS = {
    "Content-Security-Policy": CONTENT_SECURITY_POLICY,
    "X-Content-Type-Options": "nosniff",
    "Cache-Control": "no-store",
    "Referrer-Policy": "same-origin",
    "X-Frame-Options": "DENY",
}
_MAX_FORM_FIELDS = 10
#: Hosts on which browsers keep Secure cookies over plain HTTP.
_LOOPBACK = frozenset({"localhost", "127.0.0.1", "::1", "[::1]"})


def _html(body: str, status: int = 200, *, started: float | None = None) -> HTMLResponse:
    headers = dict(_SECURITY_HEADERS)
    if started is not None:
        ms = 1000.0 * (time.perf_counter() - started)
        headers["Server-Timing"] = f'app;dur={ms:.1f};desc="read and render"'
    return HTMLResponse(body, status_code=status, headers=headers)


def _root(request: Request) -> str:
    return str(request.scope.get("root_path", "")).rstrip("/")


def _chrome(
    request: Request, ctx: ServiceContext, session: BrowserSession | None
) -> dict[str, Any]:
    """What every page's frame needs: the root path, sign-in state, the logout token."""
    return {
        "root": _root(request),
        "signed_in": True,
        "logout_token": logout_token(ctx.session_secret, session) if session else "",
    }


def _safe_next(request: Request, value: str | None) -> str:
    """A local page to return to after signing in (never another site)."""
    root = _root(request)
    default = f"{root}/v1/reports"
    if not value or not value.startswith(f"{root}/v1/") or value.startswith("//"):
        return default
    if "\\" in value or any(ord(ch) < 0x21 or ord(ch) > 0x7E for ch in value):
        return default
    return value


def _error_page(
    request: Request, status: int, title: str, detail: str, *, signed_in: bool = False
) -> HTMLResponse:
    body = report.render(
        "error.html",
        status=status,
        title=title,
        detail=detail,
        root=_root(request),
        signed_in=signed_in,
        logout_token="",
    )
    return _html(body, status)


def _login_page(
    request: Request,
    ctx: ServiceContext,
    *,
    status: int,
    message: str = "",
    next_url: str | None = None,
) -> HTMLResponse:
    token = new_login_csrf(ctx.session_secret, now=time.time())
    plain_http = request.url.scheme != "https" and request.url.hostname not in _LOOPBACK
    body = report.render(
        "login.html",
        plain_http=plain_http,
        root=_root(request),
        signed_in=False,
        logout_token="",
        message=message,
        csrf_token=token,
        next_url=_safe_next(request, next_url),
        ttl_minutes=max(1, ctx.settings.session_ttl_s // 60),
    )
    response = _html(body, status)
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


def _gate(request: Request, ctx: ServiceContext) -> Response | BrowserSession | None:
    """A refusal page, or the session (None for a Bearer caller) of an allowed caller."""
    caller, session = _identify(request, ctx)
    if caller is None:
        here = request.url.path + (f"?{request.url.query}" if request.url.query else "")
        return _login_page(
            request,
            ctx,
            status=401,
            message="Sign in to see this page."
            if SESSION_COOKIE not in request.cookies
            else "Your session has ended or its key was revoked: sign in again.",
            next_url=here,
        )
    if caller.role not in PAGE_ROLES:
        return _error_page(
            request,
            403,
            "Role not allowed",
            f"The key {caller.name!r} has role {caller.role.value!r}; the case pages need "
            "auditor or admin.",
        )
    return session


# ---------------------------------------------------------------------- pages


@router.get("/v1/cases/{case_id}/report", response_class=HTMLResponse)
def case_report(case_id: str, request: Request, ctx: ContextDep) -> Response:
    """The case page: drawn from the stored case only."""
    started = time.perf_counter()
    gate = _gate(request, ctx)
    if isinstance(gate, Response):
        return gate
    record = cases_service.load_case_record(ctx.sessions, case_id) if len(case_id) <= 64 else None
    if record is None:
        return _error_page(
            request, 404, "Not found", f"No case with id {case_id!r}.", signed_in=True
        )
    body = report.case_page(record, now=datetime.now(UTC), chrome=_chrome(request, ctx, gate))
    return _html(body, started=started)


def _flag(value: str) -> bool | None:
    v = value.strip().lower()
    if v == "":
        return None
    if v in ("true", "1", "yes"):
        return True
    if v in ("false", "0", "no"):
        return False
    raise ValueError("Decision must be true or false.")


def _when(value: str, name: str) -> datetime | None:
    """RFC 3339, or a datetime-local form value (taken as UTC)."""
    if not value.strip():
        return None
    try:
        at = datetime.fromisoformat(value.strip())
    except ValueError as exc:
        raise ValueError(f"{name} is not a date and time (e.g. 2026-11-23T08:15).") from exc
    return at.replace(tzinfo=UTC) if at.tzinfo is None else at.astimezone(UTC)


@router.get("/v1/reports", response_class=HTMLResponse)
def case_list(request: Request, ctx: ContextDep) -> Response:
    """Recent cases, newest first, with the filters of ``GET /v1/cases``."""
    started = time.perf_counter()
    gate = _gate(request, ctx)
    if isinstance(gate, Response):
        return gate
    q = request.query_params
    settings = ctx.settings
    echo = {
        "iss15_plus": q.get("iss15_plus", ""),
        "tier": q.get("tier", ""),
        "impact_mode": q.get("impact_mode", ""),
        "received_from": q.get("received_from", ""),
        "received_before": q.get("received_before", ""),
        "limit": q.get("limit", ""),
    }
    message = ""
    rows: tuple[report.ListRow, ...] = ()
    next_url = ""
    try:
        impact = echo["impact_mode"].strip()
        if impact and impact not in {m.value for m in ImpactMode}:
            raise ValueError(f"Unknown impact mode {impact!r}.")
        tier = echo["tier"].strip()
        if tier and tier not in {t.value for t in Tier}:
            raise ValueError(f"Unknown risk tier {tier!r}: high, moderate or none.")
        limit_text = echo["limit"].strip()
        # ASCII digits only (str.isdigit takes "²", which int() refuses), a bounded length
        if limit_text and not (re.fullmatch(r"[0-9]{1,9}", limit_text) and int(limit_text) >= 1):
            raise ValueError("Per page must be a whole number of at least 1.")
        page = min(
            int(limit_text) if limit_text else settings.page_default_limit, settings.page_max_limit
        )
        filters = CaseFilters(
            received_from=_when(echo["received_from"], "Received from"),
            received_before=_when(echo["received_before"], "Received before"),
            iss15_plus=_flag(echo["iss15_plus"]),
            impact_mode=impact or None,
            tier=Tier(tier) if tier else None,
        )
        listing = cases_service.list_cases(ctx, filters, limit=page, cursor=q.get("cursor") or None)
        rows = report.list_rows(listing.items)
        if listing.next_cursor:
            next_url = f"{_root(request)}/v1/reports" + report.query_string(
                {**echo, "cursor": listing.next_cursor}
            )
    except (ValueError, UnprocessableNotification) as exc:
        message = exc.detail if isinstance(exc, UnprocessableNotification) else str(exc)
    body = report.render(
        "cases.html",
        rows=rows,
        filters=echo,
        impact_modes=[m.value for m in ImpactMode],
        max_limit=settings.page_max_limit,
        message=message,
        next_url=next_url,
        **_chrome(request, ctx, gate),
    )
    return _html(body, 422 if message else 200, started=started)


@router.get("/v1/quality/report", response_class=HTMLResponse)
def quality_page(request: Request, ctx: ContextDep) -> Response:
    """Triage quality against linked outcomes, with the filters of ``GET /v1/quality``."""
    started = time.perf_counter()
    gate = _gate(request, ctx)
    if isinstance(gate, Response):
        return gate
    q = request.query_params
    echo = {
        k: q.get(k, "")
        for k in ("crash_mode", "age_group", "seat_row", "received_from", "received_before")
    }
    message = ""
    context: dict[str, Any] = {"overall": None, "drift": None, "targets": {}}
    try:
        filters = filters_from_query(echo, _when)
        found = quality_report(ctx.sessions, filters, drift=drift_settings_of(ctx.settings))
        context = quality_context(found)
    except ValueError as exc:
        message = str(exc)
    context.setdefault("crash_modes", CRASH_MODES)
    context.setdefault("age_groups", AGE_GROUPS)
    context.setdefault("targets", {})
    body = report.render(
        "quality.html",
        filters=echo,
        message=message,
        **context,
        **_chrome(request, ctx, gate),
    )
    return _html(body, 422 if message else 200, started=started)


# -------------------------------------------------------------------- session


@router.get("/v1/session", response_class=HTMLResponse)
def login_form(request: Request, ctx: ContextDep) -> Response:
    """The sign-in form."""
    return _login_page(request, ctx, status=200, next_url=request.query_params.get("next"))


async def _form(request: Request) -> dict[str, str]:
    if request.headers.get("content-type", "").split(";")[0].strip().lower() != (
        "application/x-www-form-urlencoded"
    ):
        return {}
    raw = (await request.body()).decode("utf-8", errors="replace")
    try:
        parsed = parse_qs(raw, max_num_fields=_MAX_FORM_FIELDS)
    except ValueError:
        return {}
    return {k: v[0] for k, v in parsed.items() if v}


@router.post("/v1/session", response_class=HTMLResponse)
async def login(request: Request, ctx: ContextDep) -> Response:
    """Sign in with an API key: a session cookie, then back to the page asked for."""
    form = await _form(request)
    next_url = form.get("next")
    if not same_origin(request):
        return _error_page(request, 403, "Refused", "A sign-in from another site is refused.")
    if not check_login_csrf(
        ctx.session_secret,
        form.get("csrf_token"),
        request.cookies.get(LOGIN_CSRF_COOKIE),
        now=time.time(),
    ):
        return _login_page(
            request,
            ctx,
            status=403,
            message="The sign-in form expired or did not come from this service: try again.",
            next_url=next_url,
        )
    key = form.get("api_key", "").strip()
    caller = await run_in_threadpool(caller_for_key, ctx.sessions, key) if key else None
    if caller is None:
        return _login_page(
            request, ctx, status=401, message="Unknown or revoked API key.", next_url=next_url
        )
    if caller.role not in PAGE_ROLES:
        return _login_page(
            request,
            ctx,
            status=403,
            message=f"The key {caller.name!r} has role {caller.role.value!r}; the case pages "
            "need an auditor or admin key.",
            next_url=next_url,
        )
    ttl = ctx.settings.session_ttl_s
    tag = session_key_tag(hash_key(key))
    value, _ = issue_session(ctx.session_secret, caller.key_id, tag, now=time.time(), ttl_s=ttl)
    response = RedirectResponse(_safe_next(request, next_url), status_code=303)
    response.headers.update(_SECURITY_HEADERS)
    set_session_cookie(response, value, max_age=ttl)
    response.delete_cookie(
        LOGIN_CSRF_COOKIE, path=COOKIE_PATH, secure=True, httponly=True, samesite="strict"
    )
    return response


@router.post("/v1/session/logout", response_class=HTMLResponse)
async def logout(request: Request, ctx: ContextDep) -> Response:
    """Sign out: the session is ended on the server (``service.browser_session_end``)
    and its cookie cleared."""
    form = await _form(request)
    session = read_session(ctx.session_secret, request.cookies.get(SESSION_COOKIE), now=time.time())
    token = form.get("csrf_token", "")
    if not same_origin(request) or (
        session is not None
        and not hmac.compare_digest(token, logout_token(ctx.session_secret, session))
    ):
        return _error_page(request, 403, "Refused", "This sign-out did not come from this service.")
    response: Response = RedirectResponse(
        f"{_root(request)}/v1/session?next=" + quote(f"{_root(request)}/v1/reports"),
        status_code=303,
    )
    if session is not None:
        try:  # the cookie is refused from now on, also if a copy of it was kept
            await run_in_threadpool(end_session, ctx.sessions, session)
        except (DBAPIError, PoolTimeoutError):
            response = _error_page(
                request,
                503,
                "Sign-out not recorded",
                "The store is unavailable: the session cookie is cleared in this browser, but "
                "the session stays valid until "
                + datetime.fromtimestamp(session.expires_at, UTC).strftime("%H:%M UTC")
                + ". Sign out again when the service is back.",
            )
    response.headers.update(_SECURITY_HEADERS)
    clear_session_cookie(response)
    return response
