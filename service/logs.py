"""Structured JSON logs with a request id, and no notification contents.

One JSON object per line: ``time``, ``level``, ``logger``, ``message``,
``request_id`` (of the HTTP request being served, when there is one), the
``extra`` fields a call gives, and for an exception its type and stack.

Notifications hold personal data (age, sex, the VIN), so none is ever logged:
statement parameters are kept out of SQLAlchemy's messages (``hide_parameters``
in `service.db.session`), and the message of a database error, whose driver text
can quote a failing row (PostgreSQL's "Failing row contains ..."), is replaced by
its type and SQLSTATE, for every exception of a chain.
"""

from __future__ import annotations

import contextvars
import json
import logging
import logging.config
import traceback
from datetime import UTC, datetime
from typing import Any

__all__ = ["JsonFormatter", "configure_logging", "log_config", "request_id"]

#: The id of the request being served (set by the request-id middleware).
request_id: contextvars.ContextVar[str | None] = contextvars.ContextVar(
    "aacn_request_id", default=None
)

#: Attributes every LogRecord has; anything else on a record came as ``extra``.
_RECORD_ATTRS = frozenset(
    vars(logging.LogRecord("", 0, "", 0, "", None, None)).keys() | {"message", "asctime"}
)
#: Longest exception message logged, characters.
MAX_ERROR_MESSAGE = 300


def _is_database_error(exc: BaseException) -> bool:
    module = type(exc).__module__
    return module.startswith(("sqlalchemy", "psycopg", "sqlite3")) or (
        type(exc).__name__ in {"OperationalError", "IntegrityError", "DatabaseError"}
    )


def _describe(exc: BaseException) -> dict[str, Any]:
    """Type, safe message and stack of each exception of a chain (outermost first)."""
    chain: list[dict[str, Any]] = []
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        seen.add(id(current))
        entry: dict[str, Any] = {"type": f"{type(current).__module__}.{type(current).__name__}"}
        if _is_database_error(current):
            orig = getattr(current, "orig", None) or current
            sqlstate = getattr(orig, "sqlstate", None) or getattr(
                getattr(orig, "diag", None), "sqlstate", None
            )
            entry["message"] = "database error" + (f" (SQLSTATE {sqlstate})" if sqlstate else "")
        else:
            entry["message"] = str(current)[:MAX_ERROR_MESSAGE]
        entry["stack"] = [
            f"{frame.filename}:{frame.lineno} {frame.name}"
            for frame in traceback.extract_tb(current.__traceback__)
        ]
        chain.append(entry)
        current = current.__cause__ or current.__context__
    return {"type": chain[0]["type"], "message": chain[0]["message"], "chain": chain}


class JsonFormatter(logging.Formatter):
    """One JSON object per record (see the module docstring)."""

    def format(self, record: logging.LogRecord) -> str:
        out: dict[str, Any] = {
            "time": datetime.fromtimestamp(record.created, UTC).isoformat(timespec="milliseconds"),
            "level": record.levelname,
            "logger": record.name,
            "message": record.getMessage(),
        }
        rid = request_id.get()
        if rid is not None:
            out["request_id"] = rid
        for key, value in vars(record).items():
            if key not in _RECORD_ATTRS and not key.startswith("_") and key not in out:
                out[key] = value if isinstance(value, int | float | bool | None) else str(value)
        if record.exc_info and record.exc_info[1] is not None:
            out["error"] = _describe(record.exc_info[1])
        return json.dumps(out, ensure_ascii=False)


def log_config(level: str = "INFO") -> dict[str, Any]:
    """A `logging.config.dictConfig` for the service and uvicorn, JSON on stderr."""
    handler = {"class": "logging.StreamHandler", "formatter": "json", "stream": "ext://sys.stderr"}
    return {
        "version": 1,
        "disable_existing_loggers": False,
        "formatters": {"json": {"()": JsonFormatter}},
        "handlers": {"default": handler},
        "root": {"handlers": ["default"], "level": level.upper()},
        "loggers": {
            **{
                name: {"handlers": [], "level": level.upper(), "propagate": True}
                for name in ("uvicorn", "uvicorn.error", "uvicorn.access", "aacn_triage")
            },
            # Alembic logs a line per plugin and per migration context at INFO on every
            # start; `service.db.migrate.upgrade` logs one line when it changes the schema.
            "alembic": {"handlers": [], "level": _quieter(level, "WARNING"), "propagate": True},
        },
    }


def _quieter(level: str, floor: str) -> str:
    """The higher (quieter) of two logging level names."""
    named = logging.getLevelNamesMapping()
    return max(level.upper(), floor, key=lambda name: named.get(name, logging.INFO))


def configure_logging(level: str = "INFO") -> None:
    """Install `log_config` (the CLI's `serve` does; tests and embedders need not)."""
    logging.config.dictConfig(log_config(level))
