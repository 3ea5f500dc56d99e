"""The quality page (auditor, admin): the figures of ``GET /v1/quality`` for a reader.

Turns a :class:`service.outcomes.quality.QualityReport` into what the template shows:
each rate as "12.5 % (3 of 24; 95 % 4.3-31.0 %)", the targets met or not, the drift
alarm and its next step, and the reliability plot (``reliability.py``). No queries.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime
from typing import Any

from service.outcomes.quality import (
    AGE_GROUPS,
    CRASH_MODES,
    QualityFilters,
    QualityGroup,
    QualityReport,
    RateOut,
)
from service.outcomes.reliability import ReliabilityPlot, reliability_plot

__all__ = ["QualityRow", "filters_from_query", "quality_context"]


def rate_text(rate: RateOut) -> str:
    """A rate with its counts and interval, in words."""
    if rate.rate is None:
        return f"no occupants (0 of {rate.denominator})"
    text = f"{100 * rate.rate:.1f} % ({rate.numerator} of {rate.denominator}"
    if rate.ci95 is not None:
        text += f"; 95 % {100 * rate.ci95[0]:.1f}-{100 * rate.ci95[1]:.1f} %"
    return text + ")"


def _target(rate: RateOut) -> str:
    if rate.within_target is None:
        return ""
    return "meets target" if rate.within_target else "outside target"


@dataclass(frozen=True)
class QualityRow:
    """One line of the table: a month and operating point, or all of them."""

    month: str
    operating_point: str
    cases: int
    occupants: int
    linked: str
    linked_by_tier: str
    figures: tuple[tuple[str, str, str], ...]  # (name, rate text, target note)
    ratio: str


_FIGURES = (
    ("flagged", "under_triage", "Under-triage"),
    ("flagged", "over_triage_cribari", "Over-triage, 1 - PPV (Cribari)"),
    ("flagged", "over_triage_of_minor", "Over-triage, share of ISS < 15 flagged"),
    ("high_tier", "under_triage", "Under-triage of the high tier"),
    ("high_tier", "over_triage_cribari", "High tier: 1 - PPV"),
)


def _row(g: QualityGroup) -> QualityRow:
    figures = []
    for decision, name, words in _FIGURES:
        rate = getattr(getattr(g, decision), name)
        figures.append((words, rate_text(rate), _target(rate)))
    cal = g.calibration
    ratio = "no linked occupants"
    if cal.observed_over_predicted is not None and cal.observed_over_predicted_ci95:
        lo, hi = cal.observed_over_predicted_ci95
        ratio = f"{cal.observed_over_predicted:.2f} (95 % {lo:.2f}-{hi:.2f})"
    tiers = "; ".join(
        f"{tier}: {t.linked.numerator} of {t.occupants}" for tier, t in g.by_tier.items()
    )
    return QualityRow(
        month=g.month or "all months",
        operating_point=g.operating_point or "all",
        cases=g.cases,
        occupants=g.occupants,
        linked=rate_text(g.linked),
        linked_by_tier=tiers,
        figures=tuple(figures),
        ratio=ratio,
    )


def _plot(report: QualityReport) -> ReliabilityPlot | None:
    deciles = [
        (d.mean_predicted, d.observed.rate or 0.0, *(d.observed.ci95 or (0.0, 1.0)), d.occupants)
        for d in report.overall.calibration.deciles
    ]
    if not deciles:
        return None
    return reliability_plot(
        deciles, "Reliability: observed against predicted ISS 15+ by decile, with 95 % intervals"
    )


def quality_context(report: QualityReport) -> dict[str, Any]:
    """The template's context for a report."""
    return {
        "overall": _row(report.overall),
        "rows": [_row(g) for g in report.groups],
        "drift": report.drift,
        "plot": _plot(report),
        "targets": report.targets,
        "crash_modes": CRASH_MODES,
        "age_groups": AGE_GROUPS,
    }


def filters_from_query(
    query: dict[str, str], parse_time: Callable[[str, str], datetime | None]
) -> QualityFilters:
    """The page's filters from its query (ValueError in the reader's words); ``parse_time``
    reads a form's time given the field's name (``service.page_frame.form_time``)."""
    mode = query.get("crash_mode", "").strip()
    if mode and mode not in CRASH_MODES:
        raise ValueError(f"Unknown crash mode {mode!r}.")
    age = query.get("age_group", "").strip()
    if age and age not in AGE_GROUPS:
        raise ValueError(f"Unknown age group {age!r}.")
    row = query.get("seat_row", "").strip()
    if row and row not in ("1", "2", "3"):
        raise ValueError("Seat row must be 1, 2 or 3.")
    return QualityFilters(
        received_from=parse_time(query.get("received_from", ""), "Received from"),
        received_before=parse_time(query.get("received_before", ""), "Received before"),
        crash_mode=mode or None,
        age_group=age or None,
        seat_row=int(row) if row else None,
    )
