"""API keys: generation, hashing, roles, and the FastAPI dependencies.

Keys are 256-bit random tokens, so a plain SHA-256 is a sound stored form (a
slow password hash buys nothing against a key with this much entropy); the
lookup is by hash, so no secret is ever compared in Python.

Every request reads its key from the store, so a revoked or rotated key is refused
at once. Only while the store cannot be read (an outage, when cases go to the
spool) is a key judged by what this process last knew of it: revoked keys are
refused, keys known active within `KEY_CACHE_MAX_AGE_S` accepted, others unknown
(503); the key table is re-read every `key_refresh_interval_s` (`service.key_cache`).
"""

from __future__ import annotations

import hashlib
import secrets
from dataclasses import dataclass
from datetime import UTC, datetime
from enum import StrEnum
from typing import Annotated, Any

from fastapi import Depends, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy.exc import DBAPIError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError
from sqlalchemy.orm import Session, sessionmaker

from service.db import repository
from service.db.tables import ApiKey
from service.key_cache import KEY_CACHE_MAX_AGE_S, KeyStates, Verdict
from service.problems import Forbidden, StoreUnavailable, Unauthorized

__all__ = [
    "KEY_PREFIX",
    "Caller",
    "Role",
    "KEY_CACHE_MAX_AGE_S",
    "caller_for_key",
    "caller_of_row",
    "caller_for_key_id",
    "create_api_key",
    "hash_key",
    "session_key_tag",
    "require_auditor",
    "require_registry",
    "metrics_access",
    "require_submitter",
    "revoke_api_key",
    "rotate_api_key",
]

#: Every key starts with this, so leaked keys are recognisable by scanners.
KEY_PREFIX = "aacn_"
#: Random bytes in a key (256 bits).
KEY_BYTES = 32


class Role(StrEnum):
    """Submitters POST cases, auditors read them, admins do both; metrics reads /metrics;
    registry writes outcomes of stored occupants and nothing else (a trauma registry's
    link is not a call center: it neither submits nor reads cases)."""

    SUBMITTER = "submitter"
    AUDITOR = "auditor"
    ADMIN = "admin"
    METRICS = "metrics"
    REGISTRY = "registry"


@dataclass(frozen=True)
class Caller:
    """The authenticated client of a request."""

    key_id: int
    name: str
    role: Role


def hash_key(key: str) -> str:
    """SHA-256 hex digest of an API key."""
    return hashlib.sha256(key.encode("utf-8")).hexdigest()


def session_key_tag(key_sha256: str) -> str:
    """The fingerprint of a key's secret that its browser sessions carry.

    Derived from the stored digest (never the digest itself): rotating the key gives it
    a new digest, so every session signed in with the old secret stops matching it.
    """
    return hashlib.sha256(f"session-key\x00{key_sha256}".encode()).hexdigest()[:32]


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


def caller_for_key_id(sessions: sessionmaker[Session], key_id: int, key_tag: str) -> Caller | None:
    """The caller of a browser session: its key by id, active and still holding the secret
    the session was signed in with (`session_key_tag`); else None (revoked or rotated)."""
    with sessions() as session:
        row = repository.get_active_key_by_id(session, key_id)
    if row is None or not secrets.compare_digest(session_key_tag(row.key_sha256), key_tag):
        return None
    return Caller(key_id=row.id, name=row.name, role=Role(row.role))


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
    """Give a key a new secret (same name, role and cases); the old one stops at once, and
    so do the browser sessions signed in with it (`session_key_tag`).

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


bearer_scheme = HTTPBearer(auto_error=False, description="API key: `Authorization: Bearer <key>`.")


def authenticate(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(bearer_scheme)],
) -> Caller:
    if credentials is None or credentials.scheme.lower() != "bearer" or not credentials.credentials:
        raise Unauthorized("Send an API key as `Authorization: Bearer <key>`.")
    ctx = request.app.state.ctx
    digest = hash_key(credentials.credentials)
    states: KeyStates = ctx.key_states
    try:
        with ctx.sessions() as session:
            row = repository.find_active_key(session, digest)
    except (DBAPIError, PoolTimeoutError) as exc:
        # the outage rule (service.key_cache)
        verdict, known = states.verdict(digest)
        if verdict is Verdict.ACTIVE and isinstance(known, Caller):
            return known
        if verdict is Verdict.REVOKED:
            raise Unauthorized("The API key is unknown or revoked.") from exc
        raise StoreUnavailable("The key store is unavailable; retry later.") from exc
    if row is None:
        states.seen_refused(digest)
        raise Unauthorized("The API key is unknown or revoked.")
    caller = caller_of_row(row)
    states.seen_active(digest, caller)
    return caller


def caller_of_row(row: Any) -> Caller:
    """The caller of a key row (anything with ``id``, ``name`` and ``role``)."""
    return Caller(key_id=row.id, name=row.name, role=Role(row.role))


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

    async def dependency(caller: Annotated[Caller, Depends(authenticate)]) -> Caller:
        # async: the role check does no I/O, so it runs on the event loop instead of
        # taking a worker thread of its own (the key's read, `authenticate`, does)
        return _check_role(caller, allowed)

    return dependency


def _metrics_access(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(bearer_scheme)],
) -> None:
    if request.app.state.ctx.settings.metrics_access == "open":
        return
    _check_role(authenticate(request, credentials), frozenset({Role.METRICS, Role.ADMIN}))


require_submitter = Annotated[Caller, Depends(_require(Role.SUBMITTER))]
require_auditor = Annotated[Caller, Depends(_require(Role.AUDITOR))]
#: Outcome writes: registry (and admin) keys.
require_registry = Annotated[Caller, Depends(_require(Role.REGISTRY))]
#: /metrics: open, or for metrics and admin keys (setting `metrics_access`).
metrics_access = Annotated[None, Depends(_metrics_access)]
