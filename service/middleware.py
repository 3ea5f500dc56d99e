"""The app's own ASGI middleware: the request body size limit (413 before the body is
read whole) and the response headers every answer carries (request id, security)."""

from __future__ import annotations

import re
import uuid

from starlette.datastructures import MutableHeaders
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.logs import request_id
from service.problems import problem_response
from service.security_headers import HSTS_VALUE

__all__ = ["BodySizeLimit", "ResponseHeaders"]


class BodySizeLimit:
    """Refuse request bodies over `max_bytes` with 413, before they are read whole.

    A declared ``Content-Length`` over the limit is refused at once. A body without
    one (``Transfer-Encoding: chunked``) is read here up to the limit and handed on
    whole, so that it too gets the 413 problem instead of a parse error and a reset
    connection (a fuzzing finding).
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
            if re.fullmatch(rb"[0-9]{1,19}", declared) and int(declared) > self.max_bytes:
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
    ``Cache-Control: no-store`` on case data (``/v1/``); HSTS on requests that came
    over TLS (``service.security_headers``); no ``Server`` banner.
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
        over_tls = scope.get("scheme") == "https"  # TLS ends here (service.security_headers)

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                headers["X-Request-ID"] = rid
                headers["X-Content-Type-Options"] = "nosniff"
                if case_data:
                    headers["Cache-Control"] = "no-store"
                if over_tls:
                    headers["Strict-Transport-Security"] = HSTS_VALUE
                if "server" in headers:
                    del headers["server"]
            await send(message)

        try:
            await self.app(scope, receive, send_with_headers)
        finally:
            request_id.reset(token)
