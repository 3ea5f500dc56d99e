"""Prometheus metrics: HTTP requests and latencies, triage decisions, engine time.

One registry per app (so test apps do not collide). HTTP metrics are labelled
by route template, not raw path, to keep cardinality bounded; health and
metrics endpoints are not counted.
"""

from __future__ import annotations

import time

from prometheus_client import CollectorRegistry, Counter, Histogram
from starlette.routing import Match
from starlette.types import ASGIApp, Message, Receive, Scope, Send

__all__ = ["Metrics", "MetricsMiddleware"]

#: Paths left out of the HTTP metrics (polar's METRICS_DENY_LIST).
UNCOUNTED_PATHS = frozenset({"/livez", "/readyz", "/metrics"})
#: Latency buckets, s: the request path is milliseconds; batch calls can take seconds.
LATENCY_BUCKETS_S = (0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1.0, 2.5, 5.0, 10.0)


class Metrics:
    """The service's collectors, in their own registry."""

    def __init__(self) -> None:
        self.registry = CollectorRegistry(auto_describe=True)
        self.requests = Counter(
            "aacn_http_requests_total",
            "HTTP requests by route template, method and status class.",
            ["handler", "method", "status"],
            registry=self.registry,
        )
        self.latency = Histogram(
            "aacn_http_request_duration_seconds",
            "HTTP request latency by route template and method, s.",
            ["handler", "method"],
            buckets=LATENCY_BUCKETS_S,
            registry=self.registry,
        )
        self.decisions = Counter(
            "aacn_triage_decisions_total",
            "Case-level triage decisions of newly stored cases.",
            ["decision", "method"],
            registry=self.registry,
        )
        self.engine_seconds = Histogram(
            "aacn_engine_seconds",
            "Engine time per notification, s.",
            buckets=LATENCY_BUCKETS_S,
            registry=self.registry,
        )
        self.replays = Counter(
            "aacn_idempotent_replays_total",
            "POSTs answered from the idempotency record.",
            registry=self.registry,
        )
        self.spooled = Counter(
            "aacn_spooled_total",
            "Cases recorded in the local spool because the store was unavailable.",
            registry=self.registry,
        )
        self.spool_replayed = Counter(
            "aacn_spool_replayed_total",
            "Spooled cases this process stored once the store returned.",
            registry=self.registry,
        )


def _handler_name(scope: Scope) -> str:
    matched = scope.get("route")  # set by Starlette's router once it has routed
    if matched is not None:
        return str(getattr(matched, "path", "none"))
    for route in scope["app"].router.routes:
        match, _ = route.matches(scope)
        if match is Match.FULL:
            return str(getattr(route, "path", "none"))
    return "none"


class MetricsMiddleware:
    """ASGI middleware recording each HTTP request's count and latency.

    The status is the one the answer started with; a request whose app raised before
    answering counts as 500 (the error middleware outside answers it so). Latency runs
    from the request to the end of the answer's body.
    """

    def __init__(self, app: ASGIApp, metrics: Metrics) -> None:
        self.app = app
        self.metrics = metrics

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["path"] in UNCOUNTED_PATHS:
            await self.app(scope, receive, send)
            return
        start = time.perf_counter()
        status = 500

        async def send_status(message: Message) -> None:
            nonlocal status
            if message["type"] == "http.response.start":
                status = message["status"]
            await send(message)

        try:
            await self.app(scope, receive, send_status)
        finally:
            handler, method = _handler_name(scope), scope["method"]
            self.metrics.requests.labels(handler, method, f"{status // 100}xx").inc()
            self.metrics.latency.labels(handler, method).observe(time.perf_counter() - start)
