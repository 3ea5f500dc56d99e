"""The OpenAPI document's own parts: operation ids, the problem responses of
validation, the notification body's media types and examples, and the Swagger UI
served from the package (no CDN)."""

from __future__ import annotations

import json
from importlib import resources
from typing import Any

from fastapi import FastAPI, Request
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import HTMLResponse
from fastapi.routing import APIRoute
from fastapi.staticfiles import StaticFiles

from service.cases.examples import EXAMPLE_NOTIFICATIONS, EXAMPLE_VEDS
from service.cases.notification import CrashNotificationIn
from service.cases.veds import VEDS_MEDIA_TYPE
from service.problems import PROBLEM_MEDIA_TYPE
from service.security_headers import secure_docs_page

__all__ = [
    "operation_id",
    "document_validation_problems",
    "document_notification_body",
    "install_offline_docs",
]


def operation_id(route: APIRoute) -> str:
    tag = route.tags[0] if route.tags else "default"
    return f"{tag}-{route.name}"


def document_validation_problems(app: FastAPI) -> None:
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
        document_notification_body(doc, schemas)
        if "HTTPValidationError" not in json.dumps(doc.get("paths", {})):
            schemas.pop("HTTPValidationError", None)
            schemas.pop("ValidationError", None)
        app.openapi_schema = doc
        return doc

    app.openapi = openapi  # type: ignore[method-assign]


def document_notification_body(doc: dict[str, Any], schemas: dict[str, Any]) -> None:
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


def install_offline_docs(app: FastAPI) -> None:
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
        page = get_swagger_ui_html(
            openapi_url=f"{root}/openapi.json",
            title="aacn-triage - API documentation",
            swagger_js_url=f"{root}/docs/static/swagger-ui-bundle.js",
            swagger_css_url=f"{root}/docs/static/swagger-ui.css",
            swagger_favicon_url=f"{root}/docs/static/favicon.png",
        )
        return secure_docs_page(page)  # CSP (nonce), framing, referrer
