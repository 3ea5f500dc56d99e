"""The application factory and its lifespan."""

from __future__ import annotations

import json
import logging
import os
import secrets
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any

from fastapi import FastAPI
from fastapi.routing import APIRoute
from fastapi.staticfiles import StaticFiles
from starlette.responses import Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service import __version__
from service.api import cases, health, pages
from service.context import ServiceContext, engine_models_for
from service.db import migrate
from service.db.session import make_engine, make_sessionmaker
from service.metrics import Metrics, metrics_middleware
from service.problems import PROBLEM_MEDIA_TYPE, install_problem_handlers, problem_response
from service.settings import Settings, get_settings

__all__ = ["create_app"]

log = logging.getLogger("aacn_triage")


class BodySizeLimit:
    """Refuse request bodies over `max_bytes` with 413, before they are read whole."""

    def __init__(self, app: ASGIApp, max_bytes: int) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        declared = dict(scope.get("headers") or []).get(b"content-length")
        if declared is not None and declared.isdigit() and int(declared) > self.max_bytes:
            await self._refuse(scope, receive, send)
            return
        received = 0

        async def limited_receive() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > self.max_bytes:
                    raise _TooLarge
            return message

        try:
            await self.app(scope, limited_receive, send)
        except _TooLarge:
            await self._refuse(scope, receive, send)

    async def _refuse(self, scope: Scope, receive: Receive, send: Send) -> None:
        response = problem_response(
            413,
            "Request body too large",
            f"The body exceeds {self.max_bytes} bytes.",
            slug="payload-too-large",
            instance=scope.get("path"),
        )
        await response(scope, receive, send)


class _TooLarge(Exception):
    pass


#: The pages' stylesheet and icon (package data).
STATIC_DIR = Path(__file__).resolve().parent / "static"


class _StaticFiles(StaticFiles):
    """The pages' static files, not to be sniffed as another type."""

    def file_response(self, *args: Any, **kwargs: Any) -> Response:
        response = super().file_response(*args, **kwargs)
        response.headers["X-Content-Type-Options"] = "nosniff"
        return response


def _session_secret(settings: Settings) -> bytes:
    if settings.session_secret is not None:
        return settings.session_secret.get_secret_value().encode("utf-8")
    log.info(
        "AACN_SESSION_SECRET is not set: browser sessions are signed with a random secret of "
        "this process (they end at restart and are not shared between processes)"
    )
    return secrets.token_bytes(32)


def _operation_id(route: APIRoute) -> str:
    tag = route.tags[0] if route.tags else "default"
    return f"{tag}-{route.name}"


def _document_validation_problems(app: FastAPI) -> None:
    """Document every 422 as the problem+json it is (``service.problems``).

    FastAPI adds its own ``application/json`` HTTPValidationError body to each
    operation that validates input; the service answers validation errors with
    RFC 9457 problems only, so the generated document is corrected once.
    """
    generate = app.openapi

    def openapi() -> dict[str, Any]:
        if app.openapi_schema is not None:
            return app.openapi_schema
        doc = generate()
        for ops in doc.get("paths", {}).values():
            for op in ops.values():
                response = op.get("responses", {}).get("422")
                if response is not None:
                    response["description"] = "Problem: a field refused, named with the reason"
                    response["content"] = {
                        PROBLEM_MEDIA_TYPE: {"schema": {"$ref": "#/components/schemas/Problem"}}
                    }
        schemas = doc.get("components", {}).get("schemas", {})
        if "HTTPValidationError" not in json.dumps(doc.get("paths", {})):
            schemas.pop("HTTPValidationError", None)
            schemas.pop("ValidationError", None)
        app.openapi_schema = doc
        return doc

    app.openapi = openapi  # type: ignore[method-assign]


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the FastAPI application.

    The lifespan migrates the database (when `auto_migrate`), loads and verifies
    the models, and warms the engine. A model that fails to load leaves the
    service alive but not ready (/readyz says why).
    """
    settings = settings or get_settings()
    if settings.numba_cache_dir is not None:
        os.environ.setdefault("NUMBA_CACHE_DIR", str(settings.numba_cache_dir))
    metrics = Metrics()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[dict[str, Any]]:
        db_engine = make_engine(settings.database_url)
        if settings.auto_migrate:
            migrate.upgrade(settings.database_url)
        models = None
        error = None
        try:
            models = engine_models_for(settings)
        except Exception as exc:  # reported by /readyz, the service stays alive
            error = f"{type(exc).__name__}: {exc}"
            log.error("models failed to load: %s", error)
        app.state.ctx = ServiceContext(
            settings=settings,
            db_engine=db_engine,
            sessions=make_sessionmaker(db_engine),
            metrics=metrics,
            models=models,
            models_error=error,
            session_secret=_session_secret(settings),
        )
        try:
            yield {}
        finally:
            db_engine.dispose()

    app = FastAPI(
        title="aacn-triage",
        version=__version__,
        summary="Advanced automatic crash notification triage: ISS15+ per occupant, audited.",
        description=(
            "POST a crash notification; get, per occupant, the probability of an Injury "
            "Severity Score of 15 or more with its 95% interval and a transport "
            "recommendation. Every case is stored for audit. Errors are RFC 9457 "
            "problem+json. Authenticate with `Authorization: Bearer <key>`."
        ),
        lifespan=lifespan,
        docs_url="/docs" if settings.docs_enabled else None,
        redoc_url=None,
        openapi_url="/openapi.json" if settings.docs_enabled else None,
        generate_unique_id_function=_operation_id,
    )
    install_problem_handlers(app)
    _document_validation_problems(app)
    app.middleware("http")(metrics_middleware(metrics))
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    app.include_router(health.router)
    app.include_router(cases.router)
    app.include_router(pages.router)
    app.mount("/static", _StaticFiles(directory=STATIC_DIR), name="static")
    return app
