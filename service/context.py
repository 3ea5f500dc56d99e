"""What the lifespan builds once and every request uses."""

from __future__ import annotations

from dataclasses import dataclass

from sqlalchemy import Engine
from sqlalchemy.orm import Session, sessionmaker

from models.triage import EngineModels, load_engine_models
from service.metrics import Metrics
from service.settings import Settings

__all__ = ["ServiceContext", "engine_models_for"]


def engine_models_for(settings: Settings) -> EngineModels:
    """Load the engine models as the settings configure them (raises ValueError)."""
    return load_engine_models(
        threshold_override=settings.triage_threshold,
        operating_point=settings.operating_point,
        field_artifact=settings.field_artifact,
        posture_sd_deg=settings.posture_sd_deg,
        seat_track_sd_mm=settings.seat_track_sd_mm,
        surrogate_dir=settings.surrogate_dir,
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
    models_error: str | None = None
    #: Signs the browser session cookies and CSRF tokens (``service.web_auth``).
    session_secret: bytes = b""
