"""Security headers beyond the pages' own: the API documentation page, and HSTS.

* ``/docs`` (Swagger UI) gets the pages' framing and referrer rules and a
  Content-Security-Policy of its own: Swagger UI starts from one inline script,
  allowed by a nonce drawn per response, and nothing loads from elsewhere.
* ``Strict-Transport-Security`` goes on every response to a request that came
  over TLS as the service sees it (uvicorn serving TLS itself, or a trusted proxy's
  ``X-Forwarded-Proto: https``); never over plain HTTP, where browsers ignore it
  (RFC 6797 section 8.1). Where TLS ends in a proxy the service does not trust for
  forwarded headers, the proxy adds it (``deploy/nginx/aacn-triage.conf``).
"""

from __future__ import annotations

import secrets
from typing import Final

from starlette.responses import HTMLResponse

__all__ = [
    "HSTS_MAX_AGE_S",
    "HSTS_VALUE",
    "docs_content_security_policy",
    "secure_docs_page",
]

#: HSTS lifetime, s. [R] One year, the value the HSTS preload list asks for and
#: RFC 6797's examples use; no ``includeSubDomains`` (the service may share a domain).
HSTS_MAX_AGE_S: Final[int] = 31_536_000
HSTS_VALUE: Final[str] = f"max-age={HSTS_MAX_AGE_S}"

#: Swagger UI's one inline script (FastAPI's ``get_swagger_ui_html``), which the nonce allows.
_INLINE_SCRIPT: Final[str] = "<script>"


def docs_content_security_policy(nonce: str) -> str:
    """The /docs policy: the service's own files, the one inline script by its nonce.

    ``img-src data:``: Swagger UI's stylesheet draws its icons as data URIs;
    ``style-src 'unsafe-inline'``: its components set inline styles. No script but
    the bundle and the nonce'd start-up, no frames, forms only to the service.
    """
    return (
        f"default-src 'none'; script-src 'self' 'nonce-{nonce}'; "
        "style-src 'self' 'unsafe-inline'; img-src 'self' data:; connect-src 'self'; "
        "font-src 'self'; form-action 'self'; frame-ancestors 'none'; base-uri 'none'"
    )


def secure_docs_page(page: HTMLResponse) -> HTMLResponse:
    """The Swagger UI page with a fresh nonce on its inline script, and the headers."""
    nonce = secrets.token_urlsafe(16)
    body = bytes(page.body).decode("utf-8")
    body = body.replace(_INLINE_SCRIPT, f'<script nonce="{nonce}">')
    response = HTMLResponse(body, status_code=page.status_code)
    response.headers["Content-Security-Policy"] = docs_content_security_policy(nonce)
    response.headers["X-Frame-Options"] = "DENY"
    response.headers["Referrer-Policy"] = "same-origin"
    return response
