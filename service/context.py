"""What the lifespan builds once and every request uses."""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass, field

from sqlalchemy import Engine
from sqlalchemy.orm import Session, sessionmaker
from sqlalchemy.pool import Pool

from models.field.model import WITHDRAWN_VERSIONS
from models.tiers import check_threshold_order
from models.triage import EngineModels, load_engine_models, operating_thresholds
from service.db.migrate import MigrationRetry
from service.db.spool import Spool
from service.key_cache import KeyStates
from service.metrics import Metrics
from service.settings import Settings

log = logging.getLogger("aacn_triage.store")

#: Least seconds between two resets of the connection pool after store errors.
#: [R] A reset opens fresh connections (one that was opened read-only, or to a
#: server that restarted, is never reused); once a second is plenty under load.
POOL_RESET_MIN_INTERVAL_S = 1.0

__all__ = [
    "ServiceContext",
    "check_high_risk_threshold",
    "engine_models_for",
    "limit_blas_threads",
]


def limit_blas_threads(threads: int) -> None:
    """Cap the BLAS threads of this process (numpy's OpenBLAS), already loaded or not.

    The engine's matrix products are small (the surrogate propagation's largest is
    about 1000 x 450 by 450 x 1000); with OpenBLAS's default of one thread per core
    they were slower, and on a busy machine much slower: one triage of a
    single-occupant notification took a median 48 ms with 2 threads against 12 ms
    with 1 on this 2-core box at load average 7 (measured 2026-12-04). Serving
    several worker processes also wants one thread each, not cores x cores.
    """
    from threadpoolctl import threadpool_limits  # type: ignore[import-untyped]

    threadpool_limits(limits=threads, user_api="blas")


def engine_models_for(settings: Settings, *, occupant_models: bool = True) -> EngineModels:
    """Load the engine models as the settings configure them (raises ValueError).

    A field model version withdrawn for a defect is refused unless
    `settings.allow_withdrawn_field_model`. Also caps this process's BLAS threads
    at `settings.blas_threads`. Without `occupant_models` the surrogates are not
    loaded (a decision-only batch never runs them; they are most of the loading
    time).
    """
    limit_blas_threads(settings.blas_threads)
    models = load_engine_models(
        threshold_override=settings.triage_threshold,
        operating_point=settings.operating_point,
        high_threshold=settings.high_risk_threshold,
        field_artifact=settings.field_artifact,
        posture_sd_deg=settings.posture_sd_deg,
        seat_track_sd_mm=settings.seat_track_sd_mm,
        surrogate_dir=settings.surrogate_dir,
        use_surrogates=occupant_models,
        blas_threads=settings.blas_threads,
        occupant_threads=settings.occupant_threads,
    )
    field = models.field
    if (
        field is not None
        and field.version in WITHDRAWN_VERSIONS
        and not settings.allow_withdrawn_field_model
    ):
        raise ValueError(
            f"field model {field.name} {field.version} is withdrawn: "
            f"{WITHDRAWN_VERSIONS[field.version]}; serve the shipped model (unset "
            "AACN_FIELD_ARTIFACT), or set AACN_ALLOW_WITHDRAWN_FIELD_MODEL=true only to "
            "replay past decisions"
        )
    return models


def check_high_risk_threshold(settings: Settings) -> None:
    """Refuse a high-risk threshold below an operating threshold in use, before a start.

    Loads the configured field artifact alone (about a second). Raises
    ``models.triage.ThresholdOrderError``; any other fault of the artifact or the
    operating point is left to the start, which reports it (/readyz).
    """
    from models.field.risk_model import load_default as load_field_model
    from models.field.versions import load_field_artifact

    try:
        field = (
            load_field_model()
            if settings.field_artifact is None
            else load_field_artifact(settings.field_artifact)
        )
    except Exception:  # reported by the start itself
        return
    if settings.operating_point is not None and settings.operating_point not in (
        field.operating_points
    ):
        return
    check_threshold_order(
        settings.high_risk_threshold,
        operating_thresholds(field, settings.operating_point, settings.triage_threshold),
    )


@dataclass
class ServiceContext:
    """Settings, database, loaded engine models and metrics of one app instance.

    `models` is None while the models failed to load; `models_error` then says why
    (reported by /readyz).
    """

    settings: Settings
    db_engine: Engine
    sessions: sessionmaker[Session]
    metrics: Metrics
    models: EngineModels | None
    spool: Spool
    models_error: str | None = None
    #: Signs the browser session cookies and CSRF tokens (``service.browser_session``).
    session_secret: bytes = b""
    #: Where it came from (``service.session_secret.ORIGIN_*``), shown by /readyz.
    session_secret_origin: str = ""

    #: What this process knows of the API keys (``service.key_cache``). Used only
    #: while the store cannot be read, so that spooling works through an outage.
    key_states: KeyStates = field(default_factory=KeyStates)
    #: The migration waiting for the store, when it could not be reached at start.
    migration: MigrationRetry | None = None
    _last_reset: float = 0.0
    _reset_lock: threading.Lock = field(default_factory=threading.Lock)
    #: Pools replaced by a reset: the connections checked out at the reset return to
    #: them, and are closed at the next reset or at shutdown (:meth:`close_store`).
    _retired_pools: list[Pool] = field(default_factory=list)

    def reset_store_connections(self) -> None:
        """Drop pooled connections after a store error (at most once a second).

        A connection opened while the database was read-only stays read-only, and
        one to a server that restarted is dead; new ones are opened on next use.
        """
        with self._reset_lock:
            now = time.monotonic()
            if now - self._last_reset < POOL_RESET_MIN_INTERVAL_S:
                return
            self._last_reset = now
            log.warning("store error: resetting the connection pool")
            # dispose() closes the pool's idle connections and starts a new pool; those
            # checked out now come back to the old one, which only the garbage collector
            # would close: keep it, and close what has come back at the next reset
            retired = self.db_engine.pool
            self.db_engine.dispose()
            for pool in self._retired_pools:
                pool.dispose()
            self._retired_pools = [retired]

    def close_store(self) -> None:
        """Close every pooled connection, those of pools replaced by a reset included."""
        with self._reset_lock:
            for pool in self._retired_pools:
                pool.dispose()
            self._retired_pools = []
        self.db_engine.dispose()
