"""What the lifespan builds once and every request uses."""

from __future__ import annotations

from dataclasses import dataclass

from sqlalchemy import Engine
from sqlalchemy.orm import Session, sessionmaker

from models.triage import EngineModels
from service.metrics import Metrics
from service.settings import Settings

__all__ = ["ServiceContext"]


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
