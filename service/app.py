"""The application factory and its lifespan."""

from __future__ import annotations

import logging
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

from fastapi import FastAPI
from fastapi.staticfiles import StaticFiles
from starlette.responses import Response

from models.triage import ThresholdOrderError
from service import __version__, health, session_secret, sign_in
from service.auth import caller_of_row
from service.balance import ConnectionBalance, WorkerLoads
from service.cases import endpoints as cases
from service.cases import service as cases_service
from service.context import ServiceContext, engine_models_for
from service.db import migrate
from service.db.session import make_engine, make_sessionmaker
from service.db.spool import Spool, SpoolReplayer
from service.key_cache import KeyRefresher
from service.metrics import Metrics, MetricsMiddleware
from service.middleware import BodySizeLimit, ResponseHeaders
from service.nemsis import endpoints as nemsis
from service.openapi import document_validation_problems, install_offline_docs, operation_id
from service.outcomes import endpoints as outcomes
from service.outcomes import page_endpoints as quality_page
from service.outcomes.drift import DriftCollector
from service.outcomes.quality import current_drift, drift_settings_of
from service.page_frame import STATIC_DIR
from service.pages import endpoints as pages
from service.problems import install_problem_handlers
from service.settings import Settings, get_settings

__all__ = ["create_app"]


log = logging.getLogger("aacn_triage")


class _StaticFiles(StaticFiles):
    """The pages' static files, not to be sniffed as another type."""

    def file_response(self, *args: Any, **kwargs: Any) -> Response:
        response = super().file_response(*args, **kwargs)
        response.headers["X-Content-Type-Options"] = "nosniff"
        return response


def _session_secret(settings: Settings) -> session_secret.SessionSecret:
    return session_secret.load(settings)


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the FastAPI application.

    The lifespan migrates the database (when `auto_migrate`), loads and verifies
    the models, and warms the engine. A model that fails to load leaves the
    service alive but not ready (/readyz says why); so does a store that cannot be
    reached at start, whose migration then runs once it returns (``migrate.MigrationRetry``);
    a high-risk threshold below an operating threshold in use stops the start
    (ThresholdOrderError).
    """
    settings = settings or get_settings()
    metrics = Metrics()
    # with several worker processes: their shared table of requests in flight
    loads = WorkerLoads(settings.worker_loads_path) if settings.worker_loads_path else None

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[dict[str, Any]]:
        db_engine = make_engine(settings.database_url)
        migrated = not settings.auto_migrate or migrate.upgrade_or_wait(settings.database_url)
        models = None
        error = None
        try:
            models = engine_models_for(settings)
        except ThresholdOrderError:
            # a high-risk tier below the flagged cannot be answered in: refuse to start
            db_engine.dispose()
            raise
        except Exception as exc:  # reported by /readyz, the service stays alive
            error = f"{type(exc).__name__}: {exc}"
            log.error("models failed to load: %s", error)
        secret = _session_secret(settings)
        ctx = ServiceContext(
            settings=settings,
            db_engine=db_engine,
            sessions=make_sessionmaker(db_engine),
            metrics=metrics,
            models=models,
            spool=Spool(settings.resolved_spool_path()),
            models_error=error,
            session_secret=secret.value,
            session_secret_origin=secret.origin,
        )
        app.state.ctx = ctx
        drift = DriftCollector(lambda: current_drift(ctx.sessions, drift_settings_of(settings)))
        metrics.registry.register(drift)
        replayer = SpoolReplayer(
            ctx.spool,
            lambda entry: cases_service.store_spooled(ctx, entry),
            interval_s=settings.spool_replay_interval_s,
        )
        app.state.replayer = replayer
        replayer.start()
        # revocations reach this process while the store is up (service.key_cache)
        keys = KeyRefresher(
            ctx.key_states, ctx.sessions, caller_of_row, settings.key_refresh_interval_s
        )
        keys.start()
        if not migrated:  # the store was unreachable: migrate once it returns
            ctx.migration = migrate.MigrationRetry(settings.database_url, on_done=keys.refresh)
            ctx.migration.start()
        if loads is not None:
            loads.claim()  # counted among the workers once it serves
        try:
            yield {}
        finally:
            if loads is not None:
                loads.close()
            replayer.stop()
            keys.stop()
            if ctx.migration is not None:
                ctx.migration.stop()
            metrics.registry.unregister(drift)
            ctx.close_store()

    app = FastAPI(
        title="aacn-triage",
        version=__version__,
        summary="Advanced automatic crash notification triage per occupant, audited.",
        description=(
            "POST a crash notification; get, per occupant, a trauma-center recommendation "
            "decided on a field-calibrated probability of ISS 15+ (the trauma-center "
            "criterion, fitted on real NASS-CDS crashes 1997-2014 and calibrated to US towaway "
            "crashes) with its 95% interval, the risk of a serious injury per body region, the "
            "vehicle's P(anyone ISS 15+), "
            "the occupant models' physics that explains it (injury measures, region AIS, "
            "ISS, their own P(ISS >= 15)), and coded assumptions. Every case is stored for "
            "audit with the versions and checksums of its models. Errors are RFC 9457 "
            "problem+json. Authenticate with `Authorization: Bearer <key>`."
        ),
        lifespan=lifespan,
        docs_url=None,
        redoc_url=None,
        openapi_url="/openapi.json" if settings.docs_enabled else None,
        generate_unique_id_function=operation_id,
    )
    install_problem_handlers(app)
    document_validation_problems(app)
    if settings.docs_enabled:
        install_offline_docs(app)
    app.add_middleware(MetricsMiddleware, metrics=metrics)
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    app.add_middleware(ResponseHeaders)
    if loads is not None:
        app.add_middleware(ConnectionBalance, loads=loads)
    app.include_router(health.router)
    app.include_router(cases.router)
    app.include_router(nemsis.router)
    app.include_router(outcomes.router)
    app.include_router(pages.router)
    app.include_router(quality_page.router)
    app.include_router(sign_in.router)
    app.mount("/static", _StaticFiles(directory=STATIC_DIR), name="static")
    return app
