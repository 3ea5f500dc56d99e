"""The one settings object (pydantic-settings, environment prefix ``AACN_``)."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Literal

from pydantic import Field, SecretStr, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from models.constants import DEFAULT_POSTURE_SD_DEG, DEFAULT_SEAT_TRACK_SD_MM
from models.tiers import HIGH_RISK_THRESHOLD

__all__ = ["Settings", "get_settings"]


class Settings(BaseSettings):
    """Service configuration, read from ``AACN_*`` environment variables (and ``.env``)."""

    model_config = SettingsConfigDict(
        env_prefix="AACN_", env_file=".env", env_ignore_empty=True, extra="ignore"
    )

    database_url: str = Field(
        default="sqlite:///./aacn-triage.db",
        description="SQLAlchemy URL. SQLite file by default; PostgreSQL as "
        "postgresql+psycopg://user:pass@host/db.",
    )
    host: str = Field(default="127.0.0.1", description="Address `serve` binds to.")
    port: int = Field(default=8000, ge=1, le=65535, description="Port `serve` listens on.")
    auto_migrate: bool = Field(
        default=True,
        description="Run Alembic `upgrade head` when the service starts.",
    )
    max_body_bytes: int = Field(
        default=1_048_576, ge=1024, description="Largest accepted request body, bytes (413 above)."
    )
    page_default_limit: int = Field(default=50, ge=1, description="Default page size of lists.")
    page_max_limit: int = Field(default=200, ge=1, description="Largest page size of lists.")
    triage_threshold: float | None = Field(
        default=None,
        gt=0.0,
        lt=1.0,
        description="Override of the decision threshold on the field model's P(MAIS 3+), for "
        "every crash mode; None uses the operating point's thresholds.",
    )
    high_risk_threshold: float = Field(
        default=HIGH_RISK_THRESHOLD,
        gt=0.0,
        lt=1.0,
        description="The high-risk tier's threshold on the field model's P(ISS 15+): at or "
        "above it (and the operating threshold) the recommendation is the highest-level "
        "trauma center in reach. Default 0.20, the CDC 2008 expert panel's 'high risk of "
        "severe injury'. Below an operating threshold in use, the service refuses to start.",
    )
    operating_point: str | None = Field(
        default=None,
        description="Named operating point of the field model: `sens85` (the default: finds "
        ">= 85 % of ISS 15+ occupants held out), `acs_cot` (under-triage <= 5 %); with field "
        "model 2.0.0 (recalls): `sens80_per_mode`, `sens80`, `bahouth`. An unknown name leaves "
        "the service not ready.",
    )
    field_artifact: Path | None = Field(
        default=None,
        description="Field model artifact (JSON); None: the shipped one. An altered or stale "
        "artifact leaves the service not ready.",
    )
    local_model_dir: Path = Field(
        default=Path("local-models"),
        description="Directory of this site's recalibrated field models "
        "(`aacn-triage outcomes recalibrate` writes them there; `cases rescore --model` finds "
        "them there beside the shipped ones). Serve one with AACN_FIELD_ARTIFACT.",
    )
    allow_withdrawn_field_model: bool = Field(
        default=False,
        description="Serve a field model version withdrawn for a defect "
        "(`models.field.model.WITHDRAWN_VERSIONS`; e.g. 1.0.0, which read km/h as mph). Off: "
        "such an artifact leaves the service not ready. On only to replay past decisions.",
    )
    posture_sd_deg: float = Field(
        default=DEFAULT_POSTURE_SD_DEG,
        gt=0.0,
        description="Default posture sensor SD, deg: within 5 deg 95% of the time.",
    )
    seat_track_sd_mm: float = Field(
        default=DEFAULT_SEAT_TRACK_SD_MM,
        gt=0.0,
        description="Default seat position sensor SD, mm: within 5 cm 95% of the time.",
    )
    surrogate_dir: Path | None = Field(
        default=None,
        description="Directory of the PCE surrogate artifacts; None: the shipped ones. "
        "Artifacts that fail verification leave the service not ready.",
    )
    numba_cache_dir: Path | None = Field(
        default=None,
        description="Directory of numba's compiled-kernel cache, shared by every process; "
        "None: the user's cache directory (`service.numba_cache`), never the installed "
        "package. Read from the environment before numba is imported.",
    )
    session_secret: SecretStr | None = Field(
        default=None,
        min_length=32,
        description="Secret (at least 32 characters) that signs the browser session cookies of "
        "the case pages. None: `session_secret_file`, else one generated at start and shared by "
        "the workers of that start (sessions end when it stops). Set it when running several "
        "replicas behind one load balancer: they must all sign with the same secret.",
    )
    session_secret_file: Path | None = Field(
        default=None,
        description="A file holding the session secret (at least 32 characters; e.g. a "
        "container secret), read when `session_secret` is not set. `serve` with several "
        "workers and neither sets it for its workers to a secret it generates at start "
        "(`service.session_secret`).",
    )
    session_ttl_s: int = Field(
        default=900,
        ge=60,
        le=43_200,
        description="Lifetime of a browser session of the case pages, s (not renewed by use).",
    )
    drift_window_occupants: int = Field(
        default=400,
        ge=10,
        le=1_000_000,
        description="The drift alarm's window: the last N linked occupants whose observed ISS "
        "15+ are tested against the predicted (`service.outcomes.drift`).",
    )
    drift_false_alarm_rate: float = Field(
        default=0.01,
        gt=0.0,
        lt=0.5,
        description="The drift alarm's stated false-alarm rate per window (two-sided alpha).",
    )
    log_level: str = Field(default="INFO", description="Python logging level.")
    docs_enabled: bool = Field(
        default=True, description="Serve /docs (bundled Swagger UI, no CDN) and /openapi.json."
    )
    blas_threads: int = Field(
        default=1,
        ge=1,
        description="BLAS threads per process for the engine's matrix products (one: they are "
        "small, and several worker processes share the cores; `service.context`).",
    )
    occupant_threads: int | None = Field(
        default=None,
        ge=1,
        description="Occupants of one notification whose occupant models run at once (the "
        "request's thread and a shared pool of helpers; the answer is the same bits); 1: one "
        "after the other; None: min(2, the CPU count). A batch on several processes uses 1.",
    )
    workers: int | None = Field(
        default=None, ge=1, description="Worker processes of `serve`; None: the CPU count."
    )
    worker_loads_path: Path | None = Field(
        default=None,
        description="Set by `serve --workers N` (N > 1) for its workers, not by hand: the "
        "shared table of requests in flight per worker, by which a crowded worker asks "
        "clients to reconnect (`service.balance`).",
    )
    shutdown_timeout_s: float = Field(
        default=30.0,
        gt=0.0,
        description="On SIGTERM, seconds in-flight requests get to finish before the process "
        "exits (new connections are refused at once).",
    )
    spool_path: Path | None = Field(
        default=None,
        description="The local spool (SQLite, fsync'd) that records cases while the store "
        "cannot (202 `spooled`); replayed into the store in order once it returns. None: "
        "`aacn-spool.db` beside a SQLite store, else in the working directory. Put it on "
        "another volume than a SQLite store to outlive that disk filling up.",
    )
    spool_replay_interval_s: float = Field(
        default=1.0, gt=0.0, description="Seconds between looks at the spool for cases to store."
    )
    ready_while_spooling: bool = Field(
        default=True,
        description="/readyz answers 200 (status `degraded`) while the store is unwritable but "
        "the spool records cases, so a load balancer keeps sending notifications; false: 503.",
    )
    key_refresh_interval_s: float = Field(
        default=5.0,
        gt=0.0,
        description="Seconds between two reads of the API key table by each process, so that "
        "a revocation reaches it while the store is up and is enforced during a later "
        "outage too (`service.key_cache`).",
    )
    metrics_access: Literal["open", "key"] = Field(
        default="open",
        description="`/metrics` open to anyone who reaches it, or only with an API key of "
        "role metrics or admin.",
    )
    # the EMS agency NEMSIS records are handed to (service/nemsis; a request may name another)
    nemsis_agency_state_id: str | None = Field(
        default=None,
        min_length=1,
        max_length=50,
        pattern=r"^[\x20-\x7e]+$",
        description="NEMSIS dAgency.01, the receiving EMS agency's unique state ID.",
    )
    nemsis_agency_number: str | None = Field(
        default=None,
        min_length=1,
        max_length=15,
        pattern=r"^[\x20-\x7e]+$",
        description="NEMSIS dAgency.02 and eResponse.01, the receiving EMS agency's number.",
    )
    nemsis_agency_state: str | None = Field(
        default=None,
        pattern=r"^[0-9]{2}$",
        description="NEMSIS dAgency.04, the two-digit ANSI code of the agency's state.",
    )

    @model_validator(mode="after")
    def _high_tier_within_the_flagged(self) -> Settings:
        """The high-risk threshold may not lie below the overriding operating threshold
        (the operating point's own are checked when the field model loads)."""
        if self.triage_threshold is not None and self.high_risk_threshold < self.triage_threshold:
            raise ValueError(
                f"high_risk_threshold {self.high_risk_threshold} (AACN_HIGH_RISK_THRESHOLD) "
                f"lies below triage_threshold {self.triage_threshold} (AACN_TRIAGE_THRESHOLD): "
                "the high tier must lie within the flagged"
            )
        return self

    def resolved_spool_path(self) -> Path:
        """`spool_path`, or its default (see the field)."""
        if self.spool_path is not None:
            return self.spool_path
        from sqlalchemy.engine import make_url

        url = make_url(self.database_url)
        if url.get_backend_name() == "sqlite" and url.database not in (None, "", ":memory:"):
            return Path(str(url.database)).with_name("aacn-spool.db")
        return Path("aacn-spool.db")


@lru_cache(maxsize=1)
def get_settings() -> Settings:
    """The process-wide settings, read once."""
    return Settings()
