"""Browser sessions of the case pages: a signed cookie, CSRF tokens, origin checks.

Design (README, "The case page"): a dispatcher opens ``GET /v1/session``, pastes
an auditor or admin API key into the form, and ``POST /v1/session`` answers with a
session cookie::

    aacn_session = base64url({"k": key_id, "t": key_tag, "e": expires_unix, "n": nonce}) "." HMAC

HMAC-SHA256 under ``ServiceContext.session_secret`` (``AACN_SESSION_SECRET``, or
random per process). The cookie is HttpOnly, Secure, SameSite=Strict, Path=/v1,
with a short lifetime (``AACN_SESSION_TTL_S``, 15 minutes by default) that use does
not renew. It holds no key: every page request looks the key up again by id, so
a revoked key ends its sessions at once; ``key_tag``, a fingerprint of the key's
secret (``service.auth.session_key_tag``), must still match it, so a rotated key ends
them too. The Bearer API is untouched.

CSRF: the only writing routes are the login and the logout. The login form
carries a token that is also set as a cookie (signed double submit); the logout
form carries an HMAC of the session's nonce. Both refuse a request whose
``Origin`` names another host or whose ``Sec-Fetch-Site`` is cross-site.
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import hmac
import json
import re
import secrets
from dataclasses import dataclass
from urllib.parse import urlsplit

from starlette.requests import Request
from starlette.responses import Response

__all__ = [
    "COOKIE_PATH",
    "LOGIN_CSRF_COOKIE",
    "SESSION_COOKIE",
    "BrowserSession",
    "check_login_csrf",
    "clear_session_cookie",
    "issue_session",
    "logout_token",
    "new_login_csrf",
    "read_session",
    "same_origin",
    "set_login_csrf_cookie",
    "set_session_cookie",
]

#: Name of the session cookie.
SESSION_COOKIE = "aacn_session"
#: Name of the login form's CSRF cookie (signed double submit).
LOGIN_CSRF_COOKIE = "aacn_login_csrf"
#: The pages and the session routes all live under /v1; the cookies go nowhere else.
COOKIE_PATH = "/v1"
#: Lifetime of a login form's CSRF token, s.
LOGIN_CSRF_TTL_S = 3600


def _b64(data: bytes) -> str:
    return base64.urlsafe_b64encode(data).decode("ascii").rstrip("=")


def _unb64(text: str) -> bytes:
    return base64.urlsafe_b64decode(text + "=" * (-len(text) % 4))


def _mac(secret: bytes, purpose: str, message: str) -> str:
    digest = hmac.new(secret, f"{purpose}\x00{message}".encode(), hashlib.sha256).digest()
    return _b64(digest)


@dataclass(frozen=True)
class BrowserSession:
    """A verified, unexpired session cookie.

    `key_tag` fingerprints the secret of the key it was signed in with
    (``service.auth.session_key_tag``).
    """

    key_id: int
    expires_at: int
    nonce: str
    key_tag: str


def issue_session(
    secret: bytes, key_id: int, key_tag: str, *, now: float, ttl_s: int
) -> tuple[str, int]:
    """A new session cookie value for an API key id and the tag of its secret, and its
    expiry (Unix time)."""
    expires_at = int(now) + ttl_s
    body = _b64(
        json.dumps(
            {"k": key_id, "t": key_tag, "e": expires_at, "n": secrets.token_urlsafe(16)},
            separators=(",", ":"),
        ).encode()
    )
    return f"{body}.{_mac(secret, 'session', body)}", expires_at


def read_session(secret: bytes, value: str | None, *, now: float) -> BrowserSession | None:
    """The session of a cookie value, or None when absent, forged, malformed or expired."""
    if not value or value.count(".") != 1 or len(value) > 512:
        return None
    body, mac = value.split(".")
    if not hmac.compare_digest(mac, _mac(secret, "session", body)):
        return None
    try:
        data = json.loads(_unb64(body))
        session = BrowserSession(
            key_id=int(data["k"]), expires_at=int(data["e"]), nonce=data["n"], key_tag=data["t"]
        )
    except (ValueError, KeyError, TypeError, binascii.Error):
        return None  # a cookie without a key tag (signed before it was added) too
    if not isinstance(session.nonce, str) or not isinstance(session.key_tag, str):
        return None
    if session.expires_at <= now:
        return None
    return session


def logout_token(secret: bytes, session: BrowserSession) -> str:
    """The CSRF token of the logout form of one session."""
    return _mac(secret, "logout", session.nonce)


def new_login_csrf(secret: bytes, *, now: float) -> str:
    """A fresh login CSRF token (also set as the login CSRF cookie)."""
    message = f"{int(now)}:{secrets.token_urlsafe(16)}"
    return f"{message}.{_mac(secret, 'login', message)}"


def check_login_csrf(
    secret: bytes, form_token: str | None, cookie_token: str | None, *, now: float
) -> bool:
    """The form's token is the cookie's, signed by this service and not too old."""
    if not form_token or not cookie_token or not hmac.compare_digest(form_token, cookie_token):
        return False
    message, _, mac = form_token.rpartition(".")
    if not message or not hmac.compare_digest(mac, _mac(secret, "login", message)):
        return False
    issued, _, _ = message.partition(":")
    return bool(re.fullmatch(r"[0-9]{1,12}", issued)) and now - int(issued) <= LOGIN_CSRF_TTL_S


def same_origin(request: Request) -> bool:
    """No sign that a form was posted from another site.

    ``Sec-Fetch-Site`` (sent by current browsers) must be ``same-origin`` or
    ``none``; an ``Origin`` header must name the host the request was sent to.
    """
    site = request.headers.get("sec-fetch-site")
    if site is not None and site not in ("same-origin", "none"):
        return False
    origin = request.headers.get("origin")
    if origin is None:
        return True
    if origin == "null":
        return False
    return urlsplit(origin).netloc.lower() == request.headers.get("host", "").lower()


def _cookie(response: Response, name: str, value: str, *, max_age: int, path: str) -> None:
    response.set_cookie(
        name,
        value,
        max_age=max_age,
        path=path,
        secure=True,
        httponly=True,
        samesite="strict",
    )


def set_session_cookie(response: Response, value: str, *, max_age: int) -> None:
    _cookie(response, SESSION_COOKIE, value, max_age=max_age, path=COOKIE_PATH)


def clear_session_cookie(response: Response) -> None:
    _cookie(response, SESSION_COOKIE, "", max_age=0, path=COOKIE_PATH)


def set_login_csrf_cookie(response: Response, token: str) -> None:
    _cookie(response, LOGIN_CSRF_COOKIE, token, max_age=LOGIN_CSRF_TTL_S, path=COOKIE_PATH)
