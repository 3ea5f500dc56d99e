"""The application factory and its lifespan."""

from __future__ import annotations

import json
import logging
import re
import secrets
import uuid
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from importlib import resources
from pathlib import Path
from typing import Any

from fastapi import FastAPI, Request
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import HTMLResponse
from fastapi.routing import APIRoute
from fastapi.staticfiles import StaticFiles
from starlette.datastructures import MutableHeaders
from starlette.responses import Response
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service import __version__, health
from service.balance import ConnectionBalance, WorkerLoads
from service.cases import endpoints as cases
from service.cases import service as cases_service
from service.cases.examples import EXAMPLE_NOTIFICATIONS, EXAMPLE_VEDS
from service.cases.notification import CrashNotificationIn
from service.cases.veds import VEDS_MEDIA_TYPE
from service.context import ServiceContext, engine_models_for
from service.db import migrate
from service.db.session import make_engine, make_sessionmaker
from service.db.spool import Spool, SpoolReplayer
from service.logs import request_id
from service.metrics import Metrics, metrics_middleware
from service.pages import endpoints as pages
from service.problems import PROBLEM_MEDIA_TYPE, install_problem_handlers, problem_response
from service.settings import Settings, get_settings

__all__ = ["create_app"]

log = logging.getLogger("aacn_triage")


class BodySizeLimit:
    """Refuse request bodies over `max_bytes` with 413, before they are read whole.

    A declared ``Content-Length`` over the limit is refused at once. A body without
    one (``Transfer-Encoding: chunked``) is read here up to the limit and handed on
    whole, so that it too gets the 413 problem instead of a parse error and a reset
    connection (issue 24, a fuzzing finding).
    """

    def __init__(self, app: ASGIApp, max_bytes: int) -> None:
        self.app = app
        self.max_bytes = max_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        declared = dict(scope.get("headers") or []).get(b"content-length")
        if declared is not None:
            if declared.isdigit() and int(declared) > self.max_bytes:
                await self._refuse(scope, receive, send)
                return
            await self.app(scope, receive, send)
            return
        chunks: list[bytes] = []
        received = 0
        while True:
            message = await receive()
            if message["type"] != "http.request":  # the client went away
                await self.app(scope, _replay([message]), send)
                return
            body = message.get("body", b"")
            received += len(body)
            if received > self.max_bytes:
                await self._refuse(scope, receive, send)
                return
            chunks.append(body)
            if not message.get("more_body", False):
                break
        whole = {"type": "http.request", "body": b"".join(chunks), "more_body": False}
        await self.app(scope, _replay([whole], then=receive), send)

    async def _refuse(self, scope: Scope, receive: Receive, send: Send) -> None:
        response = problem_response(
            413,
            "Request body too large",
            f"The body exceeds {self.max_bytes} bytes.",
            slug="payload-too-large",
            instance=scope.get("path"),
            headers={"Connection": "close"},
        )
        await response(scope, receive, send)


def _replay(messages: list[Message], then: Receive | None = None) -> Receive:
    """A receive callable giving `messages` first, then `then` (a disconnect wait)."""
    pending = list(messages)

    async def receive() -> Message:
        if pending:
            return pending.pop(0)
        if then is not None:
            return await then()
        return {"type": "http.disconnect"}

    return receive


#: A request id taken from the client: printable ASCII without spaces, bounded.
_REQUEST_ID = re.compile(r"^[\x21-\x7e]{1,64}$")


class ResponseHeaders:
    """Request id and security headers on every response.

    ``X-Request-ID`` (the client's when it sends a plausible one, else a new UUID)
    is echoed and set for the logs; ``X-Content-Type-Options: nosniff`` always;
    ``Cache-Control: no-store`` on case data (``/v1/``); no ``Server`` banner.
    """

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        given = dict(scope.get("headers") or []).get(b"x-request-id", b"").decode("latin-1")
        rid = given if _REQUEST_ID.match(given) else uuid.uuid4().hex
        token = request_id.set(rid)
        case_data = str(scope.get("path", "")).startswith("/v1/")

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                headers["X-Request-ID"] = rid
                headers["X-Content-Type-Options"] = "nosniff"
                if case_data:
                    headers["Cache-Control"] = "no-store"
                if "server" in headers:
                    del headers["server"]
            await send(message)

        try:
            await self.app(scope, receive, send_with_headers)
        finally:
            request_id.reset(token)


#: The pages' stylesheet and icon (package data).
STATIC_DIR = Path(__file__).resolve().parent / "pages" / "static"


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
        schemas = doc.setdefault("components", {}).setdefault("schemas", {})
        _document_notification_body(doc, schemas)
        if "HTTPValidationError" not in json.dumps(doc.get("paths", {})):
            schemas.pop("HTTPValidationError", None)
            schemas.pop("ValidationError", None)
        app.openapi_schema = doc
        return doc

    app.openapi = openapi  # type: ignore[method-assign]


def _document_notification_body(doc: dict[str, Any], schemas: dict[str, Any]) -> None:
    """Document POST /v1/cases's body, which the route reads itself.

    The route parses the body after authentication and refuses duplicate keys
    (`service.cases.endpoints`), so FastAPI does not see it as a parameter; its schema
    and examples are added here, as FastAPI would have.
    """
    post = doc.get("paths", {}).get("/v1/cases", {}).get("post")
    if post is None:
        return
    schema = CrashNotificationIn.model_json_schema(ref_template="#/components/schemas/{model}")
    for name, sub in schema.pop("$defs", {}).items():
        schemas.setdefault(name, sub)
    schemas["CrashNotificationIn"] = schema
    post["requestBody"] = {
        "required": True,
        "description": "A notification of this contract (JSON), or a VEDS document (RFC 8148 "
        "XML) mapped to one (`docs/api.md` has the element-to-field table).",
        "content": {
            "application/json": {
                "schema": {"$ref": "#/components/schemas/CrashNotificationIn"},
                "examples": EXAMPLE_NOTIFICATIONS,
            },
            VEDS_MEDIA_TYPE: {
                "schema": {
                    "type": "string",
                    "contentMediaType": VEDS_MEDIA_TYPE,
                    "description": "A VEDS 3.1 (or 1.0) `veds:AutomatedCrashNotification` "
                    "document in UTF-8, without a DOCTYPE. Read: the crash pulses (delta-V "
                    "with its unit KPH or MPH, PDOF in clock hours, rollover quarter turns), "
                    "the seats (location code 1-5, occupied, belt fastened), the airbags "
                    "(category, deployed), the rollover and multiple-impacts indicators, the "
                    "incident id (the `event_id`; else the document's SHA-256) and time.",
                },
                "examples": EXAMPLE_VEDS,
            },
        },
    }


def _install_offline_docs(app: FastAPI) -> None:
    """Serve /docs from the Swagger UI files shipped in a package: no CDN needed.

    The call center may be offline; FastAPI's default page loads Swagger UI from a
    public CDN. The files come with the ``fastapi-offline`` package (Swagger UI 5,
    which reads OpenAPI 3.1).
    """
    static = resources.files("fastapi_offline") / "static"
    app.mount("/docs/static", StaticFiles(directory=str(static)), name="docs-static")

    @app.get("/docs", include_in_schema=False)
    async def docs(request: Request) -> HTMLResponse:
        root = request.scope.get("root_path", "")
        return get_swagger_ui_html(
            openapi_url=f"{root}/openapi.json",
            title="aacn-triage - API documentation",
            swagger_js_url=f"{root}/docs/static/swagger-ui-bundle.js",
            swagger_css_url=f"{root}/docs/static/swagger-ui.css",
            swagger_favicon_url=f"{root}/docs/static/favicon.png",
        )


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the FastAPI application.

    The lifespan migrates the database (when `auto_migrate`), loads and verifies
    the models, and warms the engine. A model that fails to load leaves the
    service alive but not ready (/readyz says why).
    """
    settings = settings or get_settings()
    metrics = Metrics()
    # with several worker processes: their shared table of requests in flight
    loads = WorkerLoads(settings.worker_loads_path) if settings.worker_loads_path else None

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
        ctx = ServiceContext(
            settings=settings,
            db_engine=db_engine,
            sessions=make_sessionmaker(db_engine),
            metrics=metrics,
            models=models,
            spool=Spool(settings.resolved_spool_path()),
            models_error=error,
            session_secret=_session_secret(settings),
        )
        app.state.ctx = ctx
        replayer = SpoolReplayer(
            ctx.spool,
            lambda entry: cases_service.store_spooled(ctx, entry),
            interval_s=settings.spool_replay_interval_s,
        )
        app.state.replayer = replayer
        replayer.start()
        if loads is not None:
            loads.claim()  # counted among the workers once it serves
        try:
            yield {}
        finally:
            if loads is not None:
                loads.close()
            replayer.stop()
            db_engine.dispose()

    app = FastAPI(
        title="aacn-triage",
        version=__version__,
        summary="Advanced automatic crash notification triage per occupant, audited.",
        description=(
            "POST a crash notification; get, per occupant, a trauma-center recommendation "
            "decided on a field-calibrated probability of MAIS 3+ (an AIS 3+ injury: the "
            "stand-in for ISS 15+, fitted on real NASS-CDS crashes) with its 95% interval, "
            "the occupant models' physics that explains it (injury measures, region AIS, "
            "ISS, their own P(ISS >= 15)), and coded assumptions. Every case is stored for "
            "audit with the versions and checksums of its models. Errors are RFC 9457 "
            "problem+json. Authenticate with `Authorization: Bearer <key>`."
        ),
        lifespan=lifespan,
        docs_url=None,
        redoc_url=None,
        openapi_url="/openapi.json" if settings.docs_enabled else None,
        generate_unique_id_function=_operation_id,
    )
    install_problem_handlers(app)
    _document_validation_problems(app)
    if settings.docs_enabled:
        _install_offline_docs(app)
    app.middleware("http")(metrics_middleware(metrics))
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    app.add_middleware(ResponseHeaders)
    if loads is not None:
        app.add_middleware(ConnectionBalance, loads=loads)
    app.include_router(health.router)
    app.include_router(cases.router)
    app.include_router(pages.router)
    app.mount("/static", _StaticFiles(directory=STATIC_DIR), name="static")
    return app
