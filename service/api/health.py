"""Liveness, readiness and Prometheus metrics (unversioned, outside auth)."""

from __future__ import annotations

from fastapi import APIRouter
from fastapi.responses import JSONResponse, Response
from prometheus_client import CONTENT_TYPE_LATEST, generate_latest

from service.api.deps import ContextDep
from service.db import repository
from service.problems import problem_response

__all__ = ["router"]

router = APIRouter(tags=["health"])


@router.get("/livez", include_in_schema=False)
async def livez() -> dict[str, str]:
    """The process is up (checks no dependency)."""
    return {"status": "ok"}


@router.get("/readyz", include_in_schema=False)
def readyz(ctx: ContextDep) -> JSONResponse:
    """The database answers and the models are loaded; otherwise 503."""
    reasons: list[str] = []
    try:
        with ctx.sessions() as session:
            repository.ping(session)
    except Exception as exc:  # any driver error means "not ready"
        reasons.append(f"database unreachable: {type(exc).__name__}: {exc}"[:300])
    if ctx.models is None:
        reasons.append(f"models not loaded: {ctx.models_error or 'unknown reason'}")
    if reasons:
        return problem_response(503, "Not ready", "; ".join(reasons), slug="not-ready")
    return JSONResponse(
        {
            "status": "ready",
            "models": {
                name: {"version": m.version, "sha256": m.sha256}
                for name, m in (ctx.models.model_infos().items() if ctx.models else [])
            },
        }
    )


@router.get("/metrics", include_in_schema=False)
def metrics(ctx: ContextDep) -> Response:
    """Prometheus text exposition."""
    return Response(generate_latest(ctx.metrics.registry), media_type=CONTENT_TYPE_LATEST)
