"""Triage quality: the decided probability and tier of each stored occupant against its
linked outcome, per month, operating point and tier.

Population: the occupants of the cases received in the window that pass the filters.
An occupant with no outcome is not a negative (registries hold admitted patients):
every rate counts linked occupants only, and the linked share is reported beside it,
by tier. An outcome's ISS 15+ is ``iss >= 15``; an EMS outcome without an ISS
(``not_transported``) counts as ISS < 15.

Two decisions are judged: ``flagged``, the operating point's (tier moderate or high,
``iss15_plus``), and ``high_tier`` (tier high). For each:

- under-triage: ISS 15+ not flagged / ISS 15+ (ACS-COT target at most 5 %);
- over-triage, two definitions in use, both reported and named:
  ``over_triage_cribari`` = flagged with ISS < 15 / flagged (1 - PPV, the trauma
  registries' Cribari matrix), and ``over_triage_of_minor`` = flagged with ISS < 15 /
  ISS < 15; ACS-COT's target is 25-50 %.

Calibration: linked occupants in ten groups of equal count by decided probability
(fewer when fewer occupants), each group's mean predicted against its observed share
with its Wilson interval; the observed/predicted ratio with the observed share's
interval divided by the mean predicted (the predictions taken as fixed). Shares are
weighted by the outcomes' weights (``service.outcomes.stats``); counts are shown
beside every rate. Targets: crash-data-and-triage.md section 4.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any, Final

from pydantic import BaseModel, Field
from sqlalchemy.orm import Session, sessionmaker

from models.field.features import FieldMode
from models.notification import Seat
from models.tiers import HIGH_RISK_THRESHOLD, Tier
from service.db import repository
from service.db.tables import Case, CaseOccupant, OccupantOutcome
from service.outcomes.drift import DriftSettings, DriftStatus, drift_status
from service.outcomes.stats import Share, share
from service.settings import Settings

__all__ = [
    "AGE_GROUPS",
    "CRASH_MODES",
    "OVER_TRIAGE_TARGET",
    "UNDER_TRIAGE_TARGET_MAX",
    "LinkedOccupant",
    "QualityFilters",
    "QualityReport",
    "drift_of",
    "drift_settings_of",
    "figures_of",
    "occupant_facts",
    "quality_report",
]

#: ACS-COT under-triage target: at most 5 % (crash-data-and-triage.md section 4).
UNDER_TRIAGE_TARGET_MAX: Final[float] = 0.05
#: ACS-COT over-triage target range, 25-50 % (crash-data-and-triage.md section 4).
OVER_TRIAGE_TARGET: Final[tuple[float, float]] = (0.25, 0.50)
#: ISS of a serious injury (the trauma-center criterion; ISS 15 cannot occur).
SERIOUS_ISS: Final[int] = 15
#: Calibration groups (deciles).
CALIBRATION_GROUPS: Final[int] = 10

CRASH_MODES: Final[tuple[str, ...]] = tuple(m.value for m in FieldMode)
#: Age groups, children apart (the field model's 0-4 / 5-9 / 10-15), and ``child``
#: (every child) and ``unknown`` (age not given) as filters.
AGE_BANDS: Final[tuple[tuple[str, float, float], ...]] = (
    ("child_0_4", 0.0, 5.0),
    ("child_5_9", 5.0, 10.0),
    ("child_10_15", 10.0, 16.0),
    ("adult_16_64", 16.0, 65.0),
    ("adult_65_plus", 65.0, float("inf")),
)
AGE_GROUPS: Final[tuple[str, ...]] = (*(b[0] for b in AGE_BANDS), "child", "unknown")


@dataclass(frozen=True)
class QualityFilters:
    received_from: datetime | None = None
    received_before: datetime | None = None
    crash_mode: str | None = None
    age_group: str | None = None
    seat_row: int | None = None


@dataclass(frozen=True)
class LinkedOccupant:
    """One stored occupant with what the figures need (outcome None: not linked)."""

    case_id: str
    received_at: datetime
    month: str
    operating_point: str
    tier: Tier
    flagged: bool
    probability: float
    crash_mode: str
    age_group: str
    seat_row: int
    serious: bool | None
    weight: float


def _age_group(age: Any) -> str:
    if not isinstance(age, int | float) or isinstance(age, bool):
        return "unknown"
    for name, low, high in AGE_BANDS:
        if low <= age < high:
            return name
    return "unknown"


def _occupant_tier(o: CaseOccupant, high_threshold: float | None) -> Tier:
    if o.tier is not None:
        return Tier(o.tier)
    if not o.iss15_plus:
        return Tier.NONE
    high = HIGH_RISK_THRESHOLD if high_threshold is None else high_threshold
    return Tier.HIGH if o.probability >= high else Tier.MODERATE


def _item(document: Mapping[str, Any], key: str, position: int) -> Mapping[str, Any]:
    items = document.get(key)
    if isinstance(items, list) and position < len(items) and isinstance(items[position], dict):
        return items[position]
    return {}


def occupant_facts(
    case: Case, occupant: CaseOccupant, outcome: OccupantOutcome | None
) -> LinkedOccupant:
    """The figures' view of one stored occupant (its stored answer, its outcome)."""
    answered = _item(case.result, "occupants", occupant.position)
    sent = _item(case.notification, "occupants", occupant.position)
    triage = answered.get("triage") or {}
    serious = None
    if outcome is not None:
        serious = outcome.iss is not None and outcome.iss >= SERIOUS_ISS
    return LinkedOccupant(
        case_id=case.id,
        received_at=case.received_at,
        month=case.received_at.strftime("%Y-%m"),
        operating_point=str(triage.get("operating_point") or "threshold_override"),
        tier=_occupant_tier(occupant, case.high_threshold),
        flagged=occupant.iss15_plus,
        probability=occupant.probability,
        crash_mode=str(answered.get("field_mode") or occupant.impact_mode),
        age_group=_age_group(sent.get("age_years")),
        seat_row=Seat(occupant.seat).row,
        serious=serious,
        weight=1.0 if outcome is None else outcome.weight,
    )


def _passes(o: LinkedOccupant, f: QualityFilters) -> bool:
    if f.crash_mode is not None and o.crash_mode != f.crash_mode:
        return False
    if f.seat_row is not None and o.seat_row != f.seat_row:
        return False
    if f.age_group == "child":
        return o.age_group.startswith("child_")
    return f.age_group is None or o.age_group == f.age_group


# ------------------------------------------------------------------ the answer


class RateOut(BaseModel):
    """A rate with its counts and 95 % Wilson interval (weighted when weights are given)."""

    numerator: int = Field(description="Occupants counted in the numerator.")
    denominator: int = Field(description="Occupants in the denominator.")
    weighted_numerator: float = Field(description="Sum of the numerator's weights.")
    weighted_denominator: float = Field(description="Sum of the denominator's weights.")
    effective_n: float = Field(description="Kish effective sample size of the interval.")
    rate: float | None = Field(description="The (weighted) share; null with no occupants.")
    ci95: tuple[float, float] | None = Field(description="95 % Wilson interval.")
    target: str | None = Field(default=None, description="ACS-COT target, in words.")
    within_target: bool | None = Field(
        default=None, description="The point estimate meets the target (null: no target/rate)."
    )


def _rate(s: Share, target: str | None = None, within: bool | None = None) -> RateOut:
    return RateOut(
        numerator=s.numerator,
        denominator=s.denominator,
        weighted_numerator=s.weighted_numerator,
        weighted_denominator=s.weighted_denominator,
        effective_n=s.effective_n,
        rate=s.value,
        ci95=s.ci95,
        target=target,
        within_target=within if s.value is not None else None,
    )


class DecisionQuality(BaseModel):
    """Under- and over-triage of one decision over linked occupants."""

    under_triage: RateOut = Field(description="ISS 15+ not flagged / ISS 15+.")
    over_triage_cribari: RateOut = Field(
        description="Flagged with ISS < 15 / flagged (1 - PPV; the registries' Cribari matrix)."
    )
    over_triage_of_minor: RateOut = Field(
        description="Flagged with ISS < 15 / ISS < 15 (the share of minor patients flagged)."
    )


class TierCounts(BaseModel):
    """Occupants decided in one tier and the share of them linked to an outcome."""

    occupants: int = Field(description="Occupants decided in this tier.")
    linked: RateOut = Field(description="Share of them with an outcome linked.")
    serious: int = Field(description="Linked occupants with ISS 15+.")


class DecileOut(BaseModel):
    """One calibration group: its predicted range and mean against its observed share."""

    occupants: int = Field(description="Linked occupants in the group.")
    predicted_min: float = Field(description="Lowest decided probability in the group.")
    predicted_max: float = Field(description="Highest decided probability in the group.")
    mean_predicted: float = Field(description="(Weighted) mean decided probability.")
    observed: RateOut = Field(description="(Weighted) share with ISS 15+, Wilson interval.")


class CalibrationOut(BaseModel):
    """Predicted against observed ISS 15+ by decile, and the observed/predicted ratio."""

    deciles: list[DecileOut] = Field(description="Groups of equal count, lowest first.")
    mean_predicted: float | None = Field(description="(Weighted) mean decided probability.")
    observed: RateOut = Field(description="(Weighted) share with ISS 15+.")
    observed_over_predicted: float | None = Field(description="Observed / predicted.")
    observed_over_predicted_ci95: tuple[float, float] | None = Field(
        description="The observed share's interval over the mean predicted."
    )


class QualityGroup(BaseModel):
    """The figures of one month and operating point (or of all of them)."""

    month: str | None = Field(description="YYYY-MM (UTC) of the cases; null: all months.")
    operating_point: str | None = Field(description="The decisions' operating point; null: all.")
    cases: int = Field(description="Cases with an occupant in the group.")
    occupants: int = Field(description="Occupants in the group.")
    linked: RateOut = Field(description="Share of occupants with an outcome linked.")
    by_tier: dict[str, TierCounts] = Field(description="Occupants and linked share per tier.")
    flagged: DecisionQuality = Field(
        description="The operating point's decision (tier moderate or high)."
    )
    high_tier: DecisionQuality = Field(description="The high tier alone.")
    calibration: CalibrationOut


class QualityReport(BaseModel):
    """Triage quality against linked outcomes (module ``service.outcomes.quality``)."""

    filters: dict[str, Any] = Field(description="The filters applied.")
    targets: dict[str, str] = Field(description="The ACS-COT targets and their source.")
    overall: QualityGroup = Field(description="All months and operating points together.")
    groups: list[QualityGroup] = Field(description="Per month and operating point.")
    drift: DriftStatus = Field(description="The drift alarm over the last linked occupants.")


def _decision(linked: Sequence[LinkedOccupant], flagged: Sequence[bool]) -> DecisionQuality:
    ser = [(f, o.weight) for o, f in zip(linked, flagged, strict=True) if o.serious]
    minor = [(f, o.weight) for o, f in zip(linked, flagged, strict=True) if not o.serious]
    flg = [(bool(o.serious), o.weight) for o, f in zip(linked, flagged, strict=True) if f]
    under = share([not f for f, _ in ser], [w for _, w in ser])
    cribari = share([not s for s, _ in flg], [w for _, w in flg])
    of_minor = share([f for f, _ in minor], [w for _, w in minor])
    low, high = OVER_TRIAGE_TARGET

    def over(s: Share) -> RateOut:
        ok = None if s.value is None else low <= s.value <= high
        return _rate(s, f"{low:.0%}-{high:.0%}", ok)

    ut_ok = None if under.value is None else under.value <= UNDER_TRIAGE_TARGET_MAX
    return DecisionQuality(
        under_triage=_rate(under, f"at most {UNDER_TRIAGE_TARGET_MAX:.0%}", ut_ok),
        over_triage_cribari=over(cribari),
        over_triage_of_minor=over(of_minor),
    )


def _calibration(linked: Sequence[LinkedOccupant]) -> CalibrationOut:
    ordered = sorted(linked, key=lambda o: o.probability)
    n = len(ordered)
    k = min(CALIBRATION_GROUPS, n)
    deciles = []
    for g in range(k):
        part = ordered[g * n // k : (g + 1) * n // k]
        weights = [o.weight for o in part]
        deciles.append(
            DecileOut(
                occupants=len(part),
                predicted_min=part[0].probability,
                predicted_max=part[-1].probability,
                mean_predicted=sum(o.probability * o.weight for o in part) / sum(weights),
                observed=_rate(share([bool(o.serious) for o in part], weights)),
            )
        )
    weights = [o.weight for o in ordered]
    observed = share([bool(o.serious) for o in ordered], weights)
    mean_p = sum(o.probability * o.weight for o in ordered) / sum(weights) if n else None
    ratio = ci = None
    if mean_p and observed.value is not None and observed.ci95 is not None:
        ratio = observed.value / mean_p
        ci = (observed.ci95[0] / mean_p, observed.ci95[1] / mean_p)
    return CalibrationOut(
        deciles=deciles,
        mean_predicted=mean_p,
        observed=_rate(observed),
        observed_over_predicted=ratio,
        observed_over_predicted_ci95=ci,
    )


def _group(month: str | None, point: str | None, occ: Sequence[LinkedOccupant]) -> QualityGroup:
    linked = [o for o in occ if o.serious is not None]
    by_tier = {}
    for tier in Tier:
        in_tier = [o for o in occ if o.tier is tier]
        by_tier[tier.value] = TierCounts(
            occupants=len(in_tier),
            linked=_rate(share([o.serious is not None for o in in_tier], [1.0] * len(in_tier))),
            serious=sum(1 for o in in_tier if o.serious),
        )
    return QualityGroup(
        month=month,
        operating_point=point,
        cases=len({o.case_id for o in occ}),
        occupants=len(occ),
        linked=_rate(share([o.serious is not None for o in occ], [1.0] * len(occ))),
        by_tier=by_tier,
        flagged=_decision(linked, [o.flagged for o in linked]),
        high_tier=_decision(linked, [o.tier is Tier.HIGH for o in linked]),
        calibration=_calibration(linked),
    )


def figures_of(occupants: Sequence[LinkedOccupant]) -> QualityGroup:
    """The quality figures of occupants given, not read from the store (all together)."""
    return _group(None, None, occupants)


def load_occupants(session: Session, filters: QualityFilters) -> list[LinkedOccupant]:
    """Every stored occupant in the window that passes the filters, oldest case first."""
    cases = repository.quality_rows(
        session, received_from=filters.received_from, received_before=filters.received_before
    )
    outcomes = repository.current_outcomes(session, [c.id for c in cases])
    out = []
    for case in cases:
        for occupant in case.occupants:
            facts = occupant_facts(case, occupant, outcomes.get((case.id, occupant.position)))
            if _passes(facts, filters):
                out.append(facts)
    return out


def drift_settings_of(settings: Settings) -> DriftSettings:
    """The drift alarm's window and false-alarm rate as configured."""
    return DriftSettings(
        window=settings.drift_window_occupants,
        false_alarm_rate=settings.drift_false_alarm_rate,
    )


def drift_of(occupants: Sequence[LinkedOccupant], settings: DriftSettings) -> DriftStatus:
    """The drift alarm over the linked occupants (oldest first)."""
    linked = [o for o in occupants if o.serious is not None]
    return drift_status(
        [bool(o.serious) for o in linked],
        [o.probability for o in linked],
        [o.weight for o in linked],
        settings,
    )


def quality_report(
    sessions: sessionmaker[Session], filters: QualityFilters, *, drift: DriftSettings
) -> QualityReport:
    """The quality figures of the stored occupants that pass the filters."""
    with sessions() as session:
        occupants = load_occupants(session, filters)
    keys = sorted({(o.month, o.operating_point) for o in occupants})
    groups = [
        _group(m, p, [o for o in occupants if (o.month, o.operating_point) == (m, p)])
        for m, p in keys
    ]
    return QualityReport(
        filters={
            "received_from": filters.received_from,
            "received_before": filters.received_before,
            "crash_mode": filters.crash_mode,
            "age_group": filters.age_group,
            "seat_row": filters.seat_row,
        },
        targets={
            "under_triage": f"at most {UNDER_TRIAGE_TARGET_MAX:.0%}",
            "over_triage": f"{OVER_TRIAGE_TARGET[0]:.0%}-{OVER_TRIAGE_TARGET[1]:.0%}",
            "source": "ACS-COT (crash-data-and-triage.md section 4)",
        },
        overall=_group(None, None, occupants),
        groups=groups,
        drift=drift_of(occupants, drift),
    )


def current_drift(sessions: sessionmaker[Session], settings: DriftSettings) -> DriftStatus:
    """The drift alarm over every stored occupant (the Prometheus collector's reading)."""
    with sessions() as session:
        occupants = load_occupants(session, QualityFilters())
    return drift_of(occupants, settings)
