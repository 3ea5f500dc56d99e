"""Liveness, readiness and Prometheus metrics (unversioned, outside the OpenAPI document)."""

from __future__ import annotations

import logging
from datetime import UTC, datetime

from fastapi import APIRouter
from fastapi.responses import JSONResponse, Response
from prometheus_client import CONTENT_TYPE_LATEST, generate_latest

from service.auth import metrics_access
from service.context import ServiceContext
from service.db import repository
from service.db.spool import SpoolError
from service.deps import ContextDep
from service.problems import problem_response

__all__ = ["router"]

log = logging.getLogger("aacn_triage.health")

router = APIRouter(tags=["health"])


def _error_kind(exc: BaseException) -> str:
    """An error's type and SQLSTATE, never its text (which names hosts and ports)."""
    orig = getattr(exc, "orig", None) or exc
    sqlstate = getattr(orig, "sqlstate", None)
    return type(orig).__name__ + (f" (SQLSTATE {sqlstate})" if sqlstate else "")


def _store_writable(ctx: ServiceContext) -> str | None:
    """None when a committed write to the store succeeds, else what failed."""
    try:
        with ctx.sessions.begin() as session:
            repository.probe_write(session, datetime.now(UTC))
    except Exception as exc:  # any driver error means "not writable"
        log.warning("readiness: the store is not writable", exc_info=exc)
        ctx.reset_store_connections()
        return _error_kind(exc)
    return None


@router.get("/livez", include_in_schema=False)
async def livez() -> dict[str, str]:
    """The process is up (checks no dependency)."""
    return {"status": "ok"}


@router.get("/readyz", include_in_schema=False)
def readyz(ctx: ContextDep) -> JSONResponse:
    """Models loaded and cases recordable: 200 `ready`, 200 `degraded` (spooling), or 503.

    The store must take a committed write (a read-only or full database is not
    ready, though it answers ``SELECT 1``). While it cannot, the service still
    records cases in its spool: `degraded`, 200 unless `ready_while_spooling` is
    off, and unless this process has never read the key table (it started during
    the outage): it can verify no API key, so it answers 503 and a balancer routes
    around it. 503 too while the migration waits for the store. Details name error
    types only, never hosts.
    """
    reasons: list[str] = []
    store_error = _store_writable(ctx)
    spool_error: str | None = None
    pending: int | None = None
    try:
        ctx.spool.probe()
        pending = ctx.spool.pending()
    except SpoolError as exc:
        spool_error = _error_kind(exc.__cause__ or exc)
    if ctx.models is None:
        reasons.append(f"models not loaded: {ctx.models_error or 'unknown reason'}")
    if ctx.migration is not None and not ctx.migration.done.is_set():
        reasons.append("the store was unreachable at start: its migration runs once it returns")
    if store_error is not None and not ctx.key_states.loaded:
        reasons.append(
            f"store not readable ({store_error}) and the key table never read since start: "
            "no API key can be verified"
        )
    if store_error is not None:
        if spool_error is not None:
            reasons.append(f"store not writable ({store_error}) and spool failing ({spool_error})")
        elif not ctx.settings.ready_while_spooling:
            reasons.append(f"store not writable ({store_error}); cases go to the spool")
    if reasons:
        return problem_response(503, "Not ready", "; ".join(reasons), slug="not-ready")
    return JSONResponse(
        {
            "status": "ready" if store_error is None else "degraded",
            "store": "writable" if store_error is None else f"not writable: {store_error}",
            "spool": {"pending": pending} if spool_error is None else f"failing: {spool_error}",
            # configured, file, or process: replicas need the one configured secret
            "session_secret": ctx.session_secret_origin,
            "models": {
                name: {"version": m.version, "sha256": m.sha256}
                for name, m in (ctx.models.model_infos().items() if ctx.models else [])
            },
        }
    )


@router.get("/metrics", include_in_schema=False)
def metrics(ctx: ContextDep, _access: metrics_access) -> Response:
    """Prometheus text exposition; with `metrics_access=key`, for metrics and admin keys."""
    return Response(generate_latest(ctx.metrics.registry), media_type=CONTENT_TYPE_LATEST)
