"""API keys: generation, hashing, roles, and the FastAPI dependencies.

Keys are 256-bit random tokens, so a plain SHA-256 is a sound stored form (a
slow password hash buys nothing against a key with this much entropy); the
lookup is by hash, so no secret is ever compared in Python.
"""

from __future__ import annotations

import hashlib
import secrets
from dataclasses import dataclass
from datetime import UTC, datetime
from enum import StrEnum
from typing import Annotated

from fastapi import Depends, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy.orm import Session, sessionmaker

from service.db import repository
from service.db.tables import ApiKey
from service.problems import Forbidden, Unauthorized

__all__ = [
    "KEY_PREFIX",
    "Caller",
    "Role",
    "caller_for_key",
    "caller_for_key_id",
    "create_api_key",
    "hash_key",
    "require_auditor",
    "require_submitter",
]

#: Every key starts with this, so leaked keys are recognisable by scanners.
KEY_PREFIX = "aacn_"
#: Random bytes in a key (256 bits).
KEY_BYTES = 32


class Role(StrEnum):
    """Submitters POST cases, auditors read them, admins do both."""

    SUBMITTER = "submitter"
    AUDITOR = "auditor"
    ADMIN = "admin"


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
    secret = KEY_PREFIX + secrets.token_urlsafe(KEY_BYTES)
    with sessions.begin() as session:
        if repository.get_api_key_by_name(session, name) is not None:
            raise ValueError(f"an API key named {name!r} exists already")
        row = repository.add_api_key(
            session,
            ApiKey(
                name=name,
                role=role.value,
                key_prefix=secret[: len(KEY_PREFIX) + 6],
                key_sha256=hash_key(secret),
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


_bearer = HTTPBearer(auto_error=False, description="API key: `Authorization: Bearer <key>`.")


def _authenticate(
    request: Request,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> Caller:
    if credentials is None or credentials.scheme.lower() != "bearer" or not credentials.credentials:
        raise Unauthorized("Send an API key as `Authorization: Bearer <key>`.")
    caller = caller_for_key(request.app.state.ctx.sessions, credentials.credentials)
    if caller is None:
        raise Unauthorized("The API key is unknown or revoked.")
    return caller


def _require(*roles: Role) -> object:
    allowed = frozenset(roles) | {Role.ADMIN}

    def dependency(caller: Annotated[Caller, Depends(_authenticate)]) -> Caller:
        if caller.role not in allowed:
            raise Forbidden(
                f"The key {caller.name!r} has role {caller.role.value!r}; this needs "
                + " or ".join(sorted(r.value for r in allowed))
                + "."
            )
        return caller

    return dependency


require_submitter = Annotated[Caller, Depends(_require(Role.SUBMITTER))]
require_auditor = Annotated[Caller, Depends(_require(Role.AUDITOR))]
