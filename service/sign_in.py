"""Signing in to the pages and out of them (HTML, a router).

- ``GET /v1/session``: the sign-in form;
- ``POST /v1/session``: sign in with an auditor or admin API key (sets the session
  cookie of ``service.browser_session``), then back to the page asked for;
- ``POST /v1/session/logout``: sign out (the session is ended on the server,
  ``service.browser_session_end``, and its cookie cleared).

Every page shares this sign-in, whichever feature draws it (``service.page_frame``).
HTML resources, kept out of the OpenAPI document.
"""

from __future__ import annotations

import hmac
import time
from datetime import UTC, datetime
from urllib.parse import parse_qs, quote

from fastapi import APIRouter, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import HTMLResponse, RedirectResponse, Response
from sqlalchemy.exc import DBAPIError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError

from service.auth import caller_for_key, hash_key, session_key_tag
from service.browser_session import (
    COOKIE_PATH,
    LOGIN_CSRF_COOKIE,
    SESSION_COOKIE,
    check_login_csrf,
    clear_session_cookie,
    issue_session,
    logout_token,
    read_session,
    same_origin,
    set_session_cookie,
)
from service.browser_session_end import end_session
from service.deps import ContextDep
from service.page_frame import (
    PAGE_ROLES,
    SECURITY_HEADERS,
    error_page,
    login_page,
    root_path,
    safe_next,
)

__all__ = ["router"]

router = APIRouter(include_in_schema=False)

_MAX_FORM_FIELDS = 10


@router.get("/v1/session", response_class=HTMLResponse)
def login_form(request: Request, ctx: ContextDep) -> Response:
    """The sign-in form."""
    return login_page(request, ctx, status=200, next_url=request.query_params.get("next"))


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
        return error_page(request, 403, "Refused", "A sign-in from another site is refused.")
    if not check_login_csrf(
        ctx.session_secret,
        form.get("csrf_token"),
        request.cookies.get(LOGIN_CSRF_COOKIE),
        now=time.time(),
    ):
        return login_page(
            request,
            ctx,
            status=403,
            message="The sign-in form expired or did not come from this service: try again.",
            next_url=next_url,
        )
    key = form.get("api_key", "").strip()
    caller = await run_in_threadpool(caller_for_key, ctx.sessions, key) if key else None
    if caller is None:
        return login_page(
            request, ctx, status=401, message="Unknown or revoked API key.", next_url=next_url
        )
    if caller.role not in PAGE_ROLES:
        return login_page(
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
    response = RedirectResponse(safe_next(request, next_url), status_code=303)
    response.headers.update(SECURITY_HEADERS)
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
        return error_page(request, 403, "Refused", "This sign-out did not come from this service.")
    response: Response = RedirectResponse(
        f"{root_path(request)}/v1/session?next=" + quote(f"{root_path(request)}/v1/reports"),
        status_code=303,
    )
    if session is not None:
        try:  # the cookie is refused from now on, also if a copy of it was kept
            await run_in_threadpool(end_session, ctx.sessions, session)
        except (DBAPIError, PoolTimeoutError):
            response = error_page(
                request,
                503,
                "Sign-out not recorded",
                "The store is unavailable: the session cookie is cleared in this browser, but "
                "the session stays valid until "
                + datetime.fromtimestamp(session.expires_at, UTC).strftime("%H:%M UTC")
                + ". Sign out again when the service is back.",
            )
    response.headers.update(SECURITY_HEADERS)
    clear_session_cookie(response)
    return response
