"""API keys: generation, hashing, roles, and the FastAPI dependencies.

Keys are 256-bit random tokens, so a plain SHA-256 is a sound stored form (a
slow password hash buys nothing against a key with this much entropy); the
lookup is by hash, so no secret is ever compared in Python.

Every request reads its key from the store, so a revoked or rotated key is refused
at once. Only while the store cannot be read (an outage, when cases go to the
spool) are keys accepted from the keys this process saw valid within
`KEY_CACHE_MAX_AGE_S`.
"""

from __future__ import annotations

import hashlib
import secrets
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from enum import StrEnum
from typing import Annotated

from fastapi import Depends, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy.exc import DBAPIError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError
from sqlalchemy.orm import Session, sessionmaker

from service.db import repository
from service.db.tables import ApiKey
from service.problems import Forbidden, StoreUnavailable, Unauthorized

__all__ = [
    "KEY_PREFIX",
    "Caller",
    "Role",
    "caller_for_key",
    "caller_for_key_id",
    "create_api_key",
    "hash_key",
    "require_auditor",
    "metrics_access",
    "require_submitter",
    "revoke_api_key",
    "rotate_api_key",
]

#: Every key starts with this, so leaked keys are recognisable by scanners.
KEY_PREFIX = "aacn_"
#: Random bytes in a key (256 bits).
KEY_BYTES = 32
#: Seconds a key seen valid is still accepted while the store cannot be read.
#: [R] Long enough to ride out a database maintenance window; a revocation made
#: during an outage cannot be read anyway, and is enforced once the store returns.
KEY_CACHE_MAX_AGE_S = 24 * 3600.0


class Role(StrEnum):
    """Submitters POST cases, auditors read them, admins do both; metrics reads /metrics."""

    SUBMITTER = "submitter"
    AUDITOR = "auditor"
    ADMIN = "admin"
    METRICS = "metrics"


@dataclass(frozen=True)
class Caller:
    """The authenticated client of a request."""

    key_id: int
    name: str
    role: Role


def hash_key(key: str) -> str:
    """SHA-256 hex digest of an API key."""
    return hashlib.sha256(key.encode("utf-8")).hexdigest()


def create_api_key(sessions: sessionmaker[Session], *, name: str, role: Role) -> tuple[ApiKey, str]:
    """Create and store a key; returns the row and the secret (shown once, never stored)."""
    secret, prefix, digest = _new_secret()
    with sessions.begin() as session:
        if repository.get_api_key_by_name(session, name) is not None:
            raise ValueError(f"an API key named {name!r} exists already")
        row = repository.add_api_key(
            session,
            ApiKey(
                name=name,
                role=role.value,
                key_prefix=prefix,
                key_sha256=digest,
                created_at=datetime.now(UTC),
                revoked_at=None,
            ),
        )
        session.expunge(row)
    return row, secret


def caller_for_key(sessions: sessionmaker[Session], key: str) -> Caller | None:
    """The caller of an active API key, or None when it is unknown or revoked."""
    with sessions() as session:
        row = repository.find_active_key(session, hash_key(key))
    return None if row is None else Caller(key_id=row.id, name=row.name, role=Role(row.role))


def caller_for_key_id(sessions: sessionmaker[Session], key_id: int) -> Caller | None:
    """The caller of an active API key by its id (browser sessions), or None."""
    with sessions() as session:
        row = repository.get_active_key_by_id(session, key_id)
    return None if row is None else Caller(key_id=row.id, name=row.name, role=Role(row.role))


def _new_secret() -> tuple[str, str, str]:
    secret = KEY_PREFIX + secrets.token_urlsafe(KEY_BYTES)
    return secret, secret[: len(KEY_PREFIX) + 6], hash_key(secret)


def revoke_api_key(sessions: sessionmaker[Session], name_or_id: str) -> ApiKey:
    """Revoke a key by name or id; refused at once by every service process.

    Raises
    ------
    LookupError
        No such key.
    """
    with sessions.begin() as session:
        key = repository.get_api_key(session, name_or_id)
        if key is None:
            raise LookupError(f"no API key named or numbered {name_or_id!r}")
        if key.revoked_at is None:
            repository.revoke_api_key(session, key, datetime.now(UTC))
        session.expunge(key)
    return key


def rotate_api_key(sessions: sessionmaker[Session], name_or_id: str) -> tuple[ApiKey, str]:
    """Give a key a new secret (same name, role and cases); the old one stops at once.

    Raises
    ------
    LookupError
        No such key, or it is revoked.
    """
    secret, prefix, digest = _new_secret()
    with sessions.begin() as session:
        key = repository.get_api_key(session, name_or_id)
        if key is None or key.revoked_at is not None:
            raise LookupError(f"no active API key named or numbered {name_or_id!r}")
        repository.rotate_api_key(session, key, key_prefix=prefix, key_sha256=digest)
        session.expunge(key)
    return key, secret


_bearer = HTTPBearer(auto_error=False, description="API key: `Authorization: Bearer <key>`.")


def _authenticate(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> Caller:
    if credentials is None or credentials.scheme.lower() != "bearer" or not credentials.credentials:
        raise Unauthorized("Send an API key as `Authorization: Bearer <key>`.")
    ctx = request.app.state.ctx
    digest = hash_key(credentials.credentials)
    cache: dict[str, tuple[Caller, float]] = ctx.key_cache
    try:
        with ctx.sessions() as session:
            row = repository.find_active_key(session, digest)
    except (DBAPIError, PoolTimeoutError) as exc:
        seen = cache.get(digest)
        if seen is not None and time.monotonic() - seen[1] <= KEY_CACHE_MAX_AGE_S:
            return seen[0]
        raise StoreUnavailable("The key store is unavailable; retry later.") from exc
    if row is None:
        cache.pop(digest, None)
        raise Unauthorized("The API key is unknown or revoked.")
    caller = Caller(key_id=row.id, name=row.name, role=Role(row.role))
    cache[digest] = (caller, time.monotonic())
    return caller


def _check_role(caller: Caller, allowed: frozenset[Role]) -> Caller:
    if caller.role not in allowed:
        raise Forbidden(
            f"The key {caller.name!r} has role {caller.role.value!r}; this needs "
            + " or ".join(sorted(r.value for r in allowed))
            + "."
        )
    return caller


def _require(*roles: Role) -> object:
    allowed = frozenset(roles) | {Role.ADMIN}

    def dependency(caller: Annotated[Caller, Depends(_authenticate)]) -> Caller:
        return _check_role(caller, allowed)

    return dependency


def _metrics_access(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    if request.app.state.ctx.settings.metrics_access == "open":
        return
    _check_role(_authenticate(request, credentials), frozenset({Role.METRICS, Role.ADMIN}))


require_submitter = Annotated[Caller, Depends(_require(Role.SUBMITTER))]
require_auditor = Annotated[Caller, Depends(_require(Role.AUDITOR))]
#: /metrics: open, or for metrics and admin keys (setting `metrics_access`).
metrics_access = Annotated[None, Depends(_metrics_access)]
