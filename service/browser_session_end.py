"""Server-side end of a browser session: a signed-out cookie is refused.

The session cookie is signed and carries its expiry; without a record on the
server, a copy of it kept after the sign-out would open the pages until then.
The sign-out records the session (the SHA-256 of its nonce) in the store's
``ended_sessions`` table; every page request with a cookie looks it up there, so
a replayed cookie is refused (401) by every process and replica. Rows are dropped
once their session would have expired anyway.
"""

from __future__ import annotations

import hashlib
from datetime import UTC, datetime

from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session, sessionmaker

from service.browser_session import BrowserSession
from service.db import repository

__all__ = ["end_session", "session_has_ended"]


def _digest(session: BrowserSession) -> str:
    return hashlib.sha256(session.nonce.encode("utf-8")).hexdigest()


def end_session(sessions: sessionmaker[Session], session: BrowserSession) -> None:
    """Record the sign-out of `session`; raises the store's errors (the caller reports them)."""
    expires_at = datetime.fromtimestamp(session.expires_at, UTC)
    try:
        with sessions.begin() as db:
            repository.end_browser_session(db, _digest(session), expires_at, datetime.now(UTC))
    except IntegrityError:  # signed out twice at once: ended either way
        pass


def session_has_ended(sessions: sessionmaker[Session], session: BrowserSession) -> bool:
    """Whether `session` was signed out."""
    with sessions() as db:
        return repository.is_browser_session_ended(db, _digest(session))
