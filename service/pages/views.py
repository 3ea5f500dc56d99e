"""The dispatcher's case page and case list: view models and rendering.

Everything on a page comes from the stored case (the notification as received,
the result as answered, the models recorded with it): the engine is never run
again, so a case decided before a model change shows the numbers and the model
versions it was decided with. The stored documents are read as plain JSON, not
through today's wire models, so an older stored shape still renders (for
instance `assumptions` as strings, or as objects with a `message`).

Templates: ``service/pages/templates/`` (Jinja2, autoescaped), in the pages' frame
(``service.page_frame``: ``base.html``, the stylesheet ``service/static/report.css``);
drawings: :mod:`service.pages.drawing`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any, TypeVar
from urllib.parse import urlencode

from models.impact_mode import ImpactMode
from models.injury.limits import SIDE_MODES, InjuryLimit, injury_limit
from models.notification import Body, Seat
from service.cases.result import derive_tiers
from service.db.repository import CaseRecord
from service.page_frame import template_environment
from service.pages import text as wording
from service.pages.drawing import (
    BODY_REGIONS,
    Bar,
    CarDiagram,
    Plot,
    car_diagram,
    probability_bar,
    pulse_plot,
)
from service.pages.regions import RISK_REGION_SHAPES, RiskRegionView, physics_skill, risk_regions
from service.pages.text import elapsed_text, fmt, parse_time, pct, utc_text

__all__ = [
    "AuditView",
    "CaseView",
    "ListRow",
    "build_case_view",
    "render",
]

TEMPLATES_DIR = Path(__file__).resolve().parent / "templates"

#: One environment per process: templates compile once and are cached.
_ENV = template_environment(TEMPLATES_DIR)


def render(template: str, **context: Any) -> str:
    """Render one template of ``service/pages/templates/`` (in the frame of
    ``service/templates/base.html``)."""
    return _ENV.get_template(template).render(**context)


# ------------------------------------------------------------------ labels

#: "Driver", "Front passenger", "Rear left", ..., "Third row middle", "Front middle".
SEAT_LABELS = {s.value: s.value.replace("_", " ").capitalize() for s in Seat}
BODY_LABELS = {
    "male_50th": "50th percentile male (Hybrid III 50M)",
    "female_5th": "5th percentile female (Hybrid III 5F)",
}
MODE_LABELS = {
    "frontal": "frontal",
    "rear": "rear",
    "near_side": "near side",
    "far_side": "far side",
    "rollover": "rollover",
}
AIRBAG_LABELS = {
    "deployed": "deployed",
    "not_deployed": "not deployed",
    "absent": "absent",
}
REGION_LABELS = {
    "head_neck": "Head and neck",
    "face": "Face",
    "chest": "Chest",
    "abdomen": "Abdomen",
    "extremities": "Extremities",
    "external": "External (skin)",
}
#: AIS severity words (AAAM Abbreviated Injury Scale).
AIS_WORDS = ("none", "minor", "moderate", "serious", "severe", "critical", "maximal")
OUTCOME_LABELS = {
    "MAIS3+": "P(MAIS 3+): at least one serious (AIS 3 or worse) injury. MAIS 3+ is the field "
    "model's stand-in for ISS 15+ (broader: one AIS 3 injury alone is ISS 9).",
    "ISS15+": "P(ISS >= 15) attributable to the crash loads, from the occupant models' injury "
    "measures.",
    "police_A+K": "P(police-reported incapacitating or fatal injury), the statistical baseline's "
    "outcome (a proxy for ISS 15+).",
}
OUTCOME_SHORT = {"MAIS3+": "MAIS 3+", "ISS15+": "ISS 15+", "police_A+K": "police A+K"}
#: The field risk model's ISS 15+ (3.0.0 on): a field-calibrated probability, not the
#: occupant models' physics one.
FIELD_ISS15_LABEL = (
    "P(ISS 15+) of such occupants in US towaway crashes, fitted on real NASS-CDS crashes "
    "1997-2014 and calibrated with the national weights (the trauma-center criterion)."
)


MEASURE_LABELS = {
    "hic15": ("HIC15", ""),
    "nij": ("Nij (neck)", ""),
    "chest_deflection_mm": ("Chest deflection", "mm"),
    "chest_vc_m_s": ("Chest viscous criterion", "m/s"),
    "chest_a3ms_g": ("Chest acceleration, 3 ms", "g"),
    "chest_cti": ("Combined thoracic index", ""),
    "abdomen_vc_m_s": ("Abdomen viscous criterion", "m/s"),
}


# ------------------------------------------------------------------ formatting


def _map(doc: Mapping[str, Any], key: str) -> Mapping[str, Any]:
    """A sub-document of a stored document, or an empty one."""
    value = doc.get(key)
    return value if isinstance(value, Mapping) else {}


def _num(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    v = float(value)
    return v if math.isfinite(v) else None


# ------------------------------------------------------------------ view models


@dataclass(frozen=True)
class DecisionView:
    """One decision (`triage`, `occupant_model` or `baseline`) ready to show."""

    flagged: bool
    #: ``high``, ``moderate`` or ``none``: the field decision's tier (for a second
    #: opinion, ``moderate`` when it flags: it has no tier of its own)
    tier: str
    headline: str
    recommendation: str
    probability: float
    low: float
    high: float
    threshold: float
    outcome: str
    outcome_short: str
    outcome_text: str
    model: str
    operating_point: str | None
    bar: Bar
    high_threshold: float | None = None

    @property
    def probability_text(self) -> str:
        return pct(self.probability)

    @property
    def interval_text(self) -> str:
        return f"{pct(self.low)} to {pct(self.high)}"

    @property
    def threshold_text(self) -> str:
        return pct(self.threshold)

    @property
    def symbol(self) -> str:
        return wording.TIER_SYMBOLS[self.tier]

    @property
    def high_threshold_text(self) -> str:
        return pct(self.high_threshold) if self.high_threshold is not None else ""


def decision_view(triage: Mapping[str, Any] | None) -> DecisionView | None:
    if not isinstance(triage, Mapping):
        return None
    p = _num(triage.get("probability"))
    threshold = _num(triage.get("threshold"))
    ci = triage.get("probability_ci95")
    if p is None or threshold is None:
        return None
    low, high = p, p
    if isinstance(ci, Sequence) and len(ci) == 2:
        low, high = _num(ci[0]) or 0.0, _num(ci[1]) or 0.0
    flagged = bool(triage.get("iss15_plus"))
    outcome = str(triage.get("outcome") or "")
    tier = str(triage.get("tier") or ("moderate" if flagged else "none"))  # second opinions
    return DecisionView(
        flagged=flagged,
        tier=tier,
        headline=wording.TIER_HEADLINES[tier],
        recommendation=str(triage.get("recommendation") or ""),
        probability=p,
        low=low,
        high=high,
        threshold=threshold,
        outcome=outcome,
        outcome_short=OUTCOME_SHORT.get(outcome, outcome or "probability"),
        outcome_text=(
            FIELD_ISS15_LABEL
            if outcome == "ISS15+" and str(triage.get("model") or "").startswith("field_")
            else OUTCOME_LABELS.get(outcome, outcome)
        ),
        model=str(triage.get("model") or ""),
        operating_point=triage.get("operating_point"),
        bar=probability_bar(p, low, high, threshold),
        high_threshold=_num(triage.get("high_threshold")),
    )


@dataclass(frozen=True)
class MeasureRow:
    key: str
    label: str
    unit: str
    value: float
    value_text: str
    ci_text: str
    limit: InjuryLimit | None
    limit_text: str
    ratio: float | None
    #: Width of the value's bar in a 0-120 viewBox where the limit sits at 80.
    bar_width: float
    over: bool


@dataclass(frozen=True)
class RegionView:
    key: str
    label: str
    ais: int
    severity: str

    @property
    def css(self) -> str:
        return f"ais-{min(self.ais, 6)}"


@dataclass(frozen=True)
class AssumptionView:
    text: str
    code: str | None = None


@dataclass(frozen=True)
class OccupantView:
    index: int
    seat: str
    seat_label: str
    body_label: str
    age_text: str
    sex_text: str
    restraints: tuple[tuple[str, str], ...]
    method: str
    method_text: str
    impact_mode: str
    field_mode: str
    impact_angle_text: str
    decision: DecisionView | None
    occupant_model: DecisionView | None
    baseline: DecisionView | None
    regions: tuple[RegionView, ...]
    iss_estimate: int | None
    iss_text: str
    measures: tuple[MeasureRow, ...]
    sensor_text: str
    assumptions: tuple[AssumptionView, ...]
    risk_regions: tuple[RiskRegionView, ...] = ()

    @property
    def region_ais(self) -> dict[str, int]:
        return {r.key: r.ais for r in self.regions}

    @property
    def region_risk(self) -> dict[str, RiskRegionView]:
        return {r.key: r for r in self.risk_regions}


@dataclass(frozen=True)
class CrashView:
    pulse_kind: str
    delta_v_kmh: float | None
    facts: tuple[tuple[str, str], ...]
    pdof_deg: float | None
    diagram: CarDiagram | None
    plot: Plot | None
    multiple_impacts: str
    rollover: str
    assumptions: tuple[AssumptionView, ...]


@dataclass(frozen=True)
class AuditView:
    case_id: str
    event_id: str
    client_name: str
    received_text: str
    stored_text: str
    request_sha256: str
    engine_version: str
    models: tuple[tuple[str, str, str], ...]
    timings: tuple[tuple[str, str], ...]
    #: ``json`` or ``veds``, and how the page says it
    source_format: str = "json"
    source_text: str = "JSON notification"
    #: for VEDS: the vehicle as the document names it (make, model, year), or empty
    vehicle_text: str = ""


@dataclass(frozen=True)
class CaseView:
    case_id: str
    event_id: str
    decision: DecisionView | None
    occurred_text: str
    received_text: str
    since_crash_text: str
    delay_text: str
    rendered_text: str
    occupants: tuple[OccupantView, ...]
    crash: CrashView
    audit: AuditView
    #: stored before risk tiers: the tiers shown are derived (``derive_tiers``)
    tiers_derived: bool = False


_OCCUPANT_PREFIX = re.compile(r"^occupants\[([0-9]{1,9})\]:\s*")


def _assumptions(items: Any) -> tuple[list[AssumptionView], dict[int, list[AssumptionView]]]:
    """Case-level and per-occupant assumptions; each item a string or ``{code, message}``."""
    case_level: list[AssumptionView] = []
    per_occupant: dict[int, list[AssumptionView]] = {}
    if not isinstance(items, list):
        return case_level, per_occupant
    for item in items:
        code: str | None = None
        occupant: int | None = None
        if isinstance(item, Mapping):
            text = str(item.get("message") or item.get("text") or item.get("code") or "")
            code = str(item["code"]) if item.get("code") is not None else None
            if isinstance(item.get("occupant"), int) and not isinstance(item["occupant"], bool):
                occupant = item["occupant"]
        else:
            text = str(item)
        match = _OCCUPANT_PREFIX.match(text)
        if match:
            occupant = int(match.group(1)) if occupant is None else occupant
            text = text[match.end() :]
        view = AssumptionView(text=text, code=code)
        if occupant is None:
            case_level.append(view)
        else:
            per_occupant.setdefault(occupant, []).append(view)
    return case_level, per_occupant


_Engine = TypeVar("_Engine", ImpactMode, Body)


def _enum(kind: type[_Engine], value: Any) -> _Engine | None:
    """A stored string as its engine enum, or None (not one of its values)."""
    try:
        return kind(value)
    except ValueError:
        return None


def _measure_rows(occ: Mapping[str, Any]) -> tuple[MeasureRow, ...]:
    measures = _map(occ, "measures")
    cis = _map(occ, "measures_ci95")
    mode, body = _enum(ImpactMode, occ.get("impact_mode")), _enum(Body, occ.get("body"))
    rows = []
    for key, raw in measures.items():
        value = _num(raw)
        if value is None:
            continue
        label, unit = MEASURE_LABELS.get(key, (key, ""))
        if key == "chest_deflection_mm" and mode in SIDE_MODES:
            label = "Rib deflection"
        ci = cis.get(key)
        ci_text = "-"
        if isinstance(ci, Sequence) and len(ci) == 2 and None not in (_num(ci[0]), _num(ci[1])):
            ci_text = f"{fmt(float(ci[0]))} to {fmt(float(ci[1]))}"
        limit = None if mode is None or body is None else injury_limit(key, mode, body)
        ratio = value / limit.value if limit is not None and limit.value > 0 else None
        rows.append(
            MeasureRow(
                key=key,
                label=label,
                unit=unit,
                value=value,
                value_text=fmt(value),
                ci_text=ci_text,
                limit=limit,
                limit_text=(fmt(limit.value) + (f" {unit}" if unit else "")) if limit else "none",
                ratio=ratio,
                bar_width=round(min(max(ratio, 0.0), 1.5) * 80.0, 1) if ratio is not None else 0,
                over=ratio is not None and ratio >= 1.0,
            )
        )
    return tuple(rows)


def _method_text(occ: Mapping[str, Any]) -> str:
    mode = MODE_LABELS.get(str(occ.get("impact_mode")), str(occ.get("impact_mode")))
    if occ.get("method") == "lpm":
        return (
            f"Occupant model: the {mode} occupant model ran on the crash pulse; its injury "
            "measures explain the decision."
        )
    seat = str(occ.get("seat") or "")
    if seat.startswith("rear"):
        why = "a second-row seat; the occupant models are of the front row"
    elif not occ.get("in_lpm_coverage", False):
        why = "the direction of force lies outside the occupant models' ranges"
    else:
        why = "the occupant model could not answer"
    return f"Statistical: no occupant model for this occupant ({why})."


def _restraints(given: Mapping[str, Any]) -> tuple[tuple[str, str], ...]:
    def state(key: str) -> str:
        v = given.get(key)
        return "not reported" if v is None else AIRBAG_LABELS.get(str(v), str(v))

    def flag(key: str, yes: str, no: str) -> str:
        v = given.get(key)
        return "not reported" if v is None else (yes if v else no)

    out = [
        ("Seat belt", flag("belted", "fastened", "NOT fastened")),
        ("Frontal airbag", state("frontal_airbag")),
        ("Side and curtain airbags", state("side_airbag")),
        ("Belt pretensioner", flag("pretensioner_fired", "fired", "not fired")),
    ]
    fire = _num(given.get("airbag_fire_time_ms"))
    if fire is not None:
        out.append(("Airbag fired at", f"{fire:g} ms"))
    return tuple(out)


def _occupant_view(
    index: int,
    occ: Mapping[str, Any],
    given: Mapping[str, Any],
    assumptions: list[AssumptionView],
) -> OccupantView:
    seat = str(occ.get("seat") or given.get("seat") or "")
    body = str(occ.get("body") or "")
    age = _num(given.get("age_years"))
    region_ais = occ.get("region_ais")
    regions: tuple[RegionView, ...] = ()
    if isinstance(region_ais, Mapping):
        regions = tuple(
            RegionView(
                key=str(key),
                label=REGION_LABELS.get(str(key), str(key)),
                ais=int(ais),
                severity=AIS_WORDS[min(max(int(ais), 0), 6)],
            )
            for key, ais in region_ais.items()
            if isinstance(ais, int) and not isinstance(ais, bool)
        )
    iss = _map(occ, "iss")
    iss_estimate = iss.get("estimate")
    iss_text = "not available (no occupant model)"
    if isinstance(iss_estimate, int):
        iss_text = str(iss_estimate)
        ci = iss.get("ci95")
        if isinstance(ci, Sequence) and len(ci) == 2 and None not in (_num(ci[0]), _num(ci[1])):
            iss_text += f" (95 % interval {float(ci[0]):.0f} to {float(ci[1]):.0f})"
    sensors = _map(occ, "sensor_inputs")
    sensor_text = ""
    if sensors:
        posture, seat_mm = _num(sensors.get("posture_deg")), _num(sensors.get("seat_track_mm"))
        p_sd, s_sd = _num(sensors.get("posture_sd_deg")), _num(sensors.get("seat_track_sd_mm"))
        if None not in (posture, seat_mm, p_sd, s_sd):
            sensor_text = (
                f"Computed at lumbar flexion {posture:.1f} deg (SD {p_sd:.1f}) and seat track "
                f"{seat_mm:+.0f} mm from mid track (SD {s_sd:.0f} mm)."
            )
    angle = _num(occ.get("impact_angle_deg"))
    return OccupantView(
        index=index,
        seat=seat,
        seat_label=SEAT_LABELS.get(seat, seat),
        body_label=BODY_LABELS.get(body, body or "unknown"),
        age_text=f"{age:g} years" if age is not None else "age not reported",
        sex_text=str(given.get("sex") or "sex not reported"),
        restraints=_restraints(given),
        method=str(occ.get("method") or ""),
        method_text=_method_text(occ),
        impact_mode=MODE_LABELS.get(str(occ.get("impact_mode")), str(occ.get("impact_mode"))),
        field_mode=MODE_LABELS.get(str(occ.get("field_mode")), str(occ.get("field_mode"))),
        impact_angle_text=f"{angle:+.0f} deg from the mode's axis" if angle is not None else "",
        decision=decision_view(occ.get("triage")),
        occupant_model=decision_view(occ.get("occupant_model")),
        baseline=decision_view(occ.get("baseline")),
        regions=regions,
        iss_estimate=iss_estimate if isinstance(iss_estimate, int) else None,
        iss_text=iss_text,
        measures=_measure_rows(occ),
        sensor_text=sensor_text,
        assumptions=tuple(assumptions),
        risk_regions=risk_regions(occ),
    )


def _yes_no(value: Any) -> str:
    return "not reported" if value is None else ("YES" if value else "no")


def _impacts(crash: Mapping[str, Any]) -> str:
    """Multiple impacts as the page says it, with the count where sent."""
    count = crash.get("impact_count")
    if isinstance(count, int) and count >= 2:
        return f"YES ({count} impacts)"
    if count == 1:
        return "no (1 impact)"
    return _yes_no(crash.get("multiple_impacts"))


_DELTA_V_SOURCES = {"measured": "measured by the vehicle", "reconstructed": "reconstructed"}


def _crash_view(
    notification: Mapping[str, Any],
    result: Mapping[str, Any],
    occupants: Sequence[OccupantView],
    assumptions: list[AssumptionView],
) -> CrashView:
    crash = _map(notification, "crash")
    sent = _map(crash, "pulse")
    derived = _map(result, "pulse")
    vehicle = _map(notification, "vehicle")
    kind = str(sent.get("kind") or "unknown")
    facts: list[tuple[str, str]] = []
    dv = _num(derived.get("delta_v_kmh"))
    pdof = _num(derived.get("pdof_deg"))
    if dv is not None:
        how = _DELTA_V_SOURCES.get(str(derived.get("delta_v_source", "measured")), "")
        facts.append(("Delta-V (resultant)", f"{dv:.1f} km/h, {how}"))
    lon = _num(derived.get("delta_v_longitudinal_kmh"))
    lat = _num(derived.get("delta_v_lateral_kmh"))
    if lon is not None and lat is not None:
        facts.append(("Delta-V x / y", f"{lon:+.1f} / {lat:+.1f} km/h"))
    if pdof is not None:
        facts.append(("PDOF", f"{pdof:.0f} deg clockwise from straight ahead"))
    peak, duration = _num(derived.get("peak_accel_g")), _num(derived.get("duration_ms"))
    if peak is not None:
        facts.append(("Peak acceleration", f"{peak:.1f} g"))
    if duration is not None:
        facts.append(("Pulse duration", f"{duration:.0f} ms"))
    facts.append(
        (
            "Pulse sent as",
            {
                "summary": "summary (delta-V and PDOF)",
                "delta_v": "EDR delta-V record",
                "acceleration": "acceleration samples",
            }.get(kind, kind),
        )
    )
    facts.append(
        (
            "Vehicle",
            f"{vehicle.get('model', 'compact_sedan')}, "
            f"{vehicle.get('drive_side', 'left')}-hand drive",
        )
    )
    haversine = _map(derived, "haversine")
    diagram = None
    if pdof is not None:
        diagram = car_diagram(
            pdof,
            str(vehicle.get("drive_side", "left")),
            [(o.seat, bool(o.decision and o.decision.flagged), o.seat_label) for o in occupants],
        )
    return CrashView(
        pulse_kind=kind,
        delta_v_kmh=dv,
        facts=tuple(facts),
        pdof_deg=pdof,
        diagram=diagram,
        plot=pulse_plot(dict(sent), dict(haversine) or None),
        multiple_impacts=_impacts(crash),
        rollover=_yes_no(crash.get("rollover")),
        assumptions=tuple(assumptions),
    )


def _source_view(record: CaseRecord) -> dict[str, str]:
    """How the audit trail says the case came in (JSON, or VEDS XML mapped to it)."""
    if record.source_format != "veds":
        return {"source_format": "json", "source_text": "JSON notification", "vehicle_text": ""}
    mapping = record.source_mapping if isinstance(record.source_mapping, Mapping) else {}
    version = str(mapping.get("veds_version", "")).strip()
    vehicle = _map(mapping, "vehicle")
    named = " ".join(
        str(vehicle[k]) for k in ("make", "model", "model_year") if vehicle.get(k) is not None
    )
    return {
        "source_format": "veds",
        "source_text": f"VEDS {version} XML (RFC 8148), mapped to a notification; the document "
        "is kept with the case",
        "vehicle_text": named,
    }


def build_case_view(record: CaseRecord, *, now: datetime) -> CaseView:
    """The case page's view of a stored case (nothing is recomputed; a case stored
    before risk tiers shows the tiers of its stored probabilities and thresholds)."""
    stored_triage = record.result.get("triage")
    derived = isinstance(stored_triage, Mapping) and "tier" not in stored_triage
    result, notification = derive_tiers(dict(record.result)), record.notification
    case_level, per_occupant = _assumptions(result.get("assumptions"))
    given_list = notification.get("occupants")
    given_list = given_list if isinstance(given_list, list) else []
    occupants = tuple(
        _occupant_view(
            i,
            occ,
            given_list[i] if i < len(given_list) and isinstance(given_list[i], Mapping) else {},
            per_occupant.get(i, []),
        )
        for i, occ in enumerate(result.get("occupants") or [])
        if isinstance(occ, Mapping)
    )
    occurred = parse_time(notification.get("occurred_at"))
    since = delay = "unknown"
    if occurred is not None:
        seconds = (now - occurred).total_seconds()
        since = (
            f"{elapsed_text(seconds)} since the crash"
            if seconds >= 0
            else f"the crash time is {elapsed_text(seconds)} after now: check the sender's clock"
        )
        delay = elapsed_text((record.received_at - occurred).total_seconds())
    models = tuple(
        (str(name), str(m.get("version", "")), str(m.get("sha256", "")))
        for name, m in sorted(record.models.items())
        if isinstance(m, Mapping)
    )
    timings = _map(result, "timings_ms")
    audit = AuditView(
        case_id=record.case_id,
        event_id=record.event_id,
        client_name=record.client_name,
        received_text=utc_text(record.received_at),
        stored_text=utc_text(record.stored_at),
        request_sha256=record.request_sha256,
        engine_version=record.engine_version,
        models=models,
        timings=tuple((str(k), f"{v:.1f} ms") for k, v in timings.items() if _num(v) is not None),
        **_source_view(record),
    )
    return CaseView(
        case_id=record.case_id,
        event_id=record.event_id,
        decision=decision_view(result.get("triage")),
        occurred_text=utc_text(occurred),
        received_text=utc_text(record.received_at),
        since_crash_text=since,
        delay_text=delay,
        rendered_text=utc_text(now),
        occupants=occupants,
        crash=_crash_view(notification, result, occupants, case_level),
        audit=audit,
        tiers_derived=derived,
    )


# ------------------------------------------------------------------ case list


@dataclass(frozen=True)
class ListRow:
    case_id: str
    event_id: str
    client_name: str
    received_text: str
    flagged: bool
    tier: str
    probability: float
    probability_text: str
    impact_modes: str

    @property
    def symbol(self) -> str:
        return wording.TIER_SYMBOLS[self.tier]

    @property
    def tier_text(self) -> str:
        return wording.TIER_HEADLINES[self.tier].split(":")[0]


def list_rows(items: Sequence[Any]) -> tuple[ListRow, ...]:
    """Rows of the case list from ``CaseSummary`` items."""
    return tuple(
        ListRow(
            case_id=c.case_id,
            event_id=c.event_id,
            client_name=c.client_name,
            received_text=utc_text(c.received_at),
            flagged=c.iss15_plus,
            tier=str(c.tier),
            probability=c.probability,
            probability_text=pct(c.probability),
            impact_modes=", ".join(MODE_LABELS.get(m, m) for m in c.impact_modes),
        )
        for c in items
    )


def query_string(params: Mapping[str, str | None]) -> str:
    """``?a=1&b=2`` of the non-empty parameters, or empty."""
    kept = {k: v for k, v in params.items() if v not in (None, "")}
    return "?" + urlencode(kept) if kept else ""


def case_page(record: CaseRecord, *, now: datetime, chrome: Mapping[str, Any]) -> str:
    """The HTML of the case page of a stored case."""
    view = build_case_view(record, now=now)
    return render(
        "case.html",
        view=view,
        body_regions=BODY_REGIONS,
        risk_shapes=RISK_REGION_SHAPES,
        physics=physics_skill(),
        **chrome,
    )
