"""RFC 9457 problem details: the error tree and its one JSON shape.

Error tree::

    DomainError                      (status from the subclass)
     + Unauthorized                  401 no or unknown API key
     + Forbidden                     403 the key's role may not do this
     + NotFound                      404
     + MalformedBody                 400 not one JSON document with unique keys
     + MalformedXml                  400 not one safe, well-formed XML document (VEDS)
     + IdempotencyConflict           409 same event_id, a body of another meaning
     + PayloadTooLarge               413
     + UnsupportedMediaType          415 neither application/json nor VEDS XML
     + UnprocessableNotification     422 valid JSON or XML, impossible content
     + StoreUnavailable              503 neither the store nor the spool can record

Every handler answers ``application/problem+json`` with ``type``, ``title``,
``status``, ``detail`` and, for 422, ``errors``: one entry per offending field
with its dotted path and the reason. Owned here rather than taken from a plugin
because the plugins' field names drift (service-style.md section 4).
"""

from __future__ import annotations

import logging
from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field, ValidationError
from sqlalchemy.exc import DBAPIError
from sqlalchemy.exc import TimeoutError as PoolTimeoutError
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import Match

__all__ = [
    "PROBLEM_MEDIA_TYPE",
    "DomainError",
    "FieldError",
    "Forbidden",
    "IdempotencyConflict",
    "MalformedBody",
    "MalformedXml",
    "NotFound",
    "PayloadTooLarge",
    "Problem",
    "StoreUnavailable",
    "Unauthorized",
    "UnsupportedMediaType",
    "UnprocessableNotification",
    "empty_line_problem",
    "install_problem_handlers",
    "malformed_json_problem",
    "problem_from_domain_error",
    "problem_from_validation",
    "problem_response",
]

log = logging.getLogger("aacn_triage.problems")

PROBLEM_MEDIA_TYPE = "application/problem+json"
_TYPE_BASE = "https://aacn-triage.example/problems/"
#: Tags of the pulse union; pydantic puts the tag into error paths, callers do not see it.
_UNION_TAGS = frozenset({"acceleration", "delta_v", "summary"})


class FieldError(BaseModel):
    """One offending field of a request."""

    field: str = Field(description="Dotted path of the field, e.g. `crash.pulse.sample_rate_hz`.")
    reason: str = Field(description="Why the value was refused.")
    type: str = Field(description="Machine-readable error code.")


class Problem(BaseModel):
    """An RFC 9457 problem details object."""

    type: str = Field(description="URI identifying the problem type.")
    title: str = Field(description="Short summary of the problem type.")
    status: int = Field(description="HTTP status code.")
    detail: str = Field(description="Explanation of this occurrence.")
    instance: str | None = Field(default=None, description="The request path.")
    errors: list[FieldError] | None = Field(
        default=None, description="Offending fields (validation problems only)."
    )

    model_config = {
        "json_schema_extra": {
            "examples": [
                {
                    "type": _TYPE_BASE + "validation",
                    "title": "Invalid notification",
                    "status": 422,
                    "detail": "1 field was refused.",
                    "instance": "/v1/cases",
                    "errors": [
                        {
                            "field": "crash.pulse.sample_rate_hz",
                            "reason": "Input should be greater than 0",
                            "type": "greater_than",
                        }
                    ],
                }
            ]
        }
    }


class DomainError(Exception):
    """Base of the service's expected errors; each maps to one problem type."""

    status = 400
    slug = "bad-request"
    title = "Bad request"

    def __init__(self, detail: str, *, errors: list[FieldError] | None = None) -> None:
        super().__init__(detail)
        self.detail = detail
        self.errors = errors


class Unauthorized(DomainError):
    status, slug, title = 401, "unauthorized", "Missing or unknown API key"


class Forbidden(DomainError):
    status, slug, title = 403, "forbidden", "Role not allowed"


class NotFound(DomainError):
    status, slug, title = 404, "not-found", "Not found"


class IdempotencyConflict(DomainError):
    status, slug, title = 409, "idempotency-conflict", "event_id reused with a different body"


class PayloadTooLarge(DomainError):
    status, slug, title = 413, "payload-too-large", "Request body too large"


class UnprocessableNotification(DomainError):
    status, slug, title = 422, "validation", "Invalid notification"


class EngineFailure(DomainError):
    """The engine failed on a valid notification (a defect of ours, not of the input)."""

    status, slug, title = 500, "engine-failure", "The engine failed"

    def __init__(self, detail: str, *, reference: str) -> None:
        super().__init__(detail)
        self.reference = reference


class MalformedBody(DomainError):
    status, slug, title = 400, "malformed-json", "Malformed JSON"


class MalformedXml(DomainError):
    """A VEDS body that is not one well-formed XML document the service may safely read.

    Also a document type declaration (no entities, internal or external), nesting
    or an element count over the limits, or an encoding other than UTF-8.
    """

    status, slug, title = 400, "malformed-xml", "Malformed or refused XML"


class UnsupportedMediaType(DomainError):
    status, slug, title = 415, "unsupported-media-type", "Unsupported media type"


class StoreUnavailable(DomainError):
    status, slug, title = 503, "store-unavailable", "Store unavailable"


#: Seconds a client is asked to wait before retrying when the store is unavailable.
#: [R] The spool replayer looks every second; a few seconds spares a failing database.
RETRY_AFTER_S = 5


def problem_response(
    status: int,
    title: str,
    detail: str,
    *,
    slug: str,
    instance: str | None = None,
    errors: list[FieldError] | None = None,
    headers: dict[str, str] | None = None,
) -> JSONResponse:
    """Build a problem+json response."""
    body = Problem(
        type=_TYPE_BASE + slug,
        title=title,
        status=status,
        detail=detail,
        instance=instance,
        errors=errors,
    )
    return JSONResponse(
        body.model_dump(exclude_none=True),
        status_code=status,
        media_type=PROBLEM_MEDIA_TYPE,
        headers=headers,
    )


def _field_path(loc: tuple[Any, ...] | list[Any]) -> str:
    parts = list(loc)
    if parts and parts[0] in ("body", "query", "path", "header"):
        parts = parts[1:]
    cleaned: list[str] = []
    for i, part in enumerate(parts):
        if part in _UNION_TAGS and i > 0 and parts[i - 1] == "pulse":
            continue
        cleaned.append(f"[{part}]" if isinstance(part, int) else str(part))
    text = ".".join(cleaned).replace(".[", "[")
    return text or "body"


def validation_errors(exc: RequestValidationError) -> list[FieldError]:
    """Turn pydantic's errors into field errors with dotted paths."""
    out: list[FieldError] = []
    for err in exc.errors():
        reason = str(err.get("msg", "invalid value"))
        if reason.startswith("Value error, "):
            reason = reason[len("Value error, ") :]
        out.append(
            FieldError(field=_field_path(err.get("loc", ())), reason=reason, type=str(err["type"]))
        )
    return out


def problem_from_validation(exc: ValidationError) -> dict[str, Any]:
    """A notification refused by the wire models, as the problem a batch line or a
    command prints (422 with one entry per offending field, like the API's)."""
    errors = validation_errors(RequestValidationError(exc.errors()))
    return {
        "title": "Invalid notification",
        "status": 422,
        "errors": [e.model_dump() for e in errors],
    }


def problem_from_domain_error(exc: DomainError) -> dict[str, Any]:
    """A domain error as the problem of a batch line (the API answers it with a handler)."""
    return {
        "title": exc.title,
        "status": exc.status,
        "detail": exc.detail,
        "errors": [e.model_dump() for e in exc.errors or []],
    }


def malformed_json_problem(reason: str) -> dict[str, Any]:
    """A batch line that is not one JSON document with unique keys (400)."""
    return {"title": "Malformed JSON", "status": 400, "detail": reason}


def empty_line_problem() -> dict[str, Any]:
    """A batch line with nothing on it."""
    return {"title": "Empty line"}


def install_problem_handlers(app: FastAPI) -> None:
    """Register the handlers that turn every error into problem+json."""

    @app.exception_handler(DomainError)
    async def _domain(request: Request, exc: DomainError) -> JSONResponse:
        headers = {"WWW-Authenticate": "Bearer"} if exc.status == 401 else None
        if exc.status == 503:
            headers = {"Retry-After": str(RETRY_AFTER_S)}
        return problem_response(
            exc.status,
            exc.title,
            exc.detail,
            slug=exc.slug,
            instance=request.url.path,
            errors=exc.errors,
            headers=headers,
        )

    @app.exception_handler(RequestValidationError)
    async def _validation(request: Request, exc: RequestValidationError) -> JSONResponse:
        errors = validation_errors(exc)
        if any(e.type == "json_invalid" for e in errors):
            return problem_response(
                400,
                "Malformed JSON",
                "The request body is not valid JSON: " + errors[0].reason,
                slug="malformed-json",
                instance=request.url.path,
                errors=errors,
            )
        n = len(errors)
        return problem_response(
            422,
            "Invalid request",
            f"{n} field{'s' if n != 1 else ''} {'were' if n != 1 else 'was'} refused.",
            slug="validation",
            instance=request.url.path,
            errors=errors,
        )

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        headers = dict(exc.headers) if exc.headers else {}
        if exc.status_code == 405:
            # Starlette names only the first matching route's methods; a path
            # served by several routes (GET and POST /v1/cases) allows them all
            headers["Allow"] = ", ".join(_allowed_methods(request))
        return problem_response(
            exc.status_code,
            _reason(exc.status_code),
            str(exc.detail),
            slug=f"http-{exc.status_code}",
            instance=request.url.path,
            headers=headers or None,
        )

    async def _store(request: Request, exc: Exception) -> JSONResponse:
        log.warning(
            "store unavailable on %s", request.url.path, extra={"error_type": type(exc).__name__}
        )
        return problem_response(
            503,
            StoreUnavailable.title,
            "The audit store is unavailable; retry later.",
            slug=StoreUnavailable.slug,
            instance=request.url.path,
            headers={"Retry-After": str(RETRY_AFTER_S)},
        )

    app.add_exception_handler(DBAPIError, _store)
    app.add_exception_handler(PoolTimeoutError, _store)

    @app.exception_handler(Exception)
    async def _unexpected(request: Request, exc: Exception) -> JSONResponse:
        log.error("unexpected error on %s", request.url.path, exc_info=exc)
        return problem_response(
            500,
            "Internal server error",
            "The server failed to process the request. A case is stored only in the transaction "
            "that answers 201; re-send the same event_id to get it or to retry.",
            slug="internal",
            instance=request.url.path,
        )


#: Methods probed for the ``Allow`` header of a 405.
_METHODS = ("GET", "HEAD", "POST", "PUT", "PATCH", "DELETE")


def _allowed_methods(request: Request) -> list[str]:
    """Every method some route of the app fully matches at the request's path."""
    routes = request.app.routes
    return [
        method
        for method in _METHODS
        if any(r.matches({**request.scope, "method": method})[0] is Match.FULL for r in routes)
    ]


def _reason(status: int) -> str:
    from http import HTTPStatus

    try:
        return HTTPStatus(status).phrase
    except ValueError:
        return "Error"
