"""How the pages write numbers, times, durations and risk tiers (plain functions of values)."""

from __future__ import annotations

from datetime import UTC, datetime
from typing import Any

__all__ = [
    "TIER_HEADLINES",
    "TIER_SYMBOLS",
    "elapsed_text",
    "fmt",
    "parse_time",
    "pct",
    "utc_text",
]

#: The banner's words by risk tier (``models.tiers``); a decision without a tier (a
#: second opinion) is said as a telemetry indication or none.
TIER_HEADLINES = {
    "high": "High risk: highest-level trauma center",
    "moderate": "Moderate risk: consider a trauma center",
    "none": "No telemetry indication",
}
#: Each tier's symbol beside its words (colour is never the only signal): a triangle,
#: a diamond, a disc.
TIER_SYMBOLS = {"high": "\u25b2", "moderate": "\u25c6", "none": "\u25cf"}


def pct(p: float) -> str:
    """A probability in percent, one decimal."""
    return f"{100.0 * p:.1f} %"


def fmt(v: float) -> str:
    """A measure with about three significant figures, never in e-notation."""
    a = abs(v)
    if a >= 100:
        return f"{v:.0f}"
    if a >= 10:
        return f"{v:.1f}"
    if a >= 1:
        return f"{v:.2f}"
    return f"{v:.3f}"


def parse_time(value: Any) -> datetime | None:
    """An RFC 3339 text or a datetime, as an aware UTC datetime."""
    if isinstance(value, datetime):
        at = value
    elif isinstance(value, str):
        try:
            at = datetime.fromisoformat(value)
        except ValueError:
            return None
    else:
        return None
    return at.replace(tzinfo=UTC) if at.tzinfo is None else at.astimezone(UTC)


def utc_text(at: datetime | None) -> str:
    return "unknown" if at is None else at.strftime("%Y-%m-%d %H:%M:%S UTC")


def elapsed_text(seconds: float) -> str:
    """A duration in words: 45 s, 12 min, 2 h 05 min, 3 d 4 h."""
    s = int(abs(seconds))
    if s < 90:
        return f"{s} s"
    if s < 90 * 60:
        return f"{round(s / 60)} min"
    if s < 48 * 3600:
        return f"{s // 3600} h {(s % 3600) // 60:02d} min"
    return f"{s // 86400} d {(s % 86400) // 3600} h"
