"""VEDS crash notifications (RFC 8148): read safely, map to the JSON notification.

An NG911 call center receives a vehicle's crash data as the Vehicle Emergency
Data Set, ``application/EmergencyCallData.VEDS+xml`` (VEDS 3.1, namespace
``http://www.veds.org/acn/3.1``; the 1.0 namespace is read the same way). This
module reads such a document and maps it to the service's own wire model
(:class:`~service.cases.notification.CrashNotificationIn`), so that triage, idempotency and
storage are those of a JSON notification. What the mapping took from where, what
it assumed (assumption codes) and what it left unused is recorded with the case
(:class:`~service.cases.notification.ReceivedSource`).

Reading is hardened (``defusedxml`` over the standard library's expat): a
document type declaration is refused outright, so there are no entities,
internal (entity expansion, "billion laughs") or external (XXE), and nothing is
fetched; nesting deeper than :data:`MAX_DEPTH` or more than :data:`MAX_ELEMENTS`
elements are refused while parsing; the body size limit is the service's
(``AACN_MAX_BODY_BYTES``, 413). Every refusal is a 4xx problem naming the element
(``veds:Crash/veds:CrashVehicle/veds:VehicleCrashPulse[1]/...``).

What is mapped (``docs/api.md`` has the table):

- ``veds:VehicleCrashPulse`` (one per impact): delta-V with its unit (KPH, or MPH
  converted with :data:`KM_PER_MILE`), PDOF in clock hours (1-12, 12 frontal),
  rollover quarter turns. The pulse with the largest delta-V becomes the summary
  pulse; several pulses are multiple impacts.
- ``veds:VehicleSeat``: location code (1 driver, 2 front passenger, 3-5 second row
  left, middle, right, 6-8 third row left, middle, right, 9 front middle), occupied,
  belt fastened (and monitored).
- ``veds:Airbag``: category (FRONT; SIDE and CURTAIN) and deployed, given to the
  seats they can protect (VEDS airbags name no seat).
- ``veds:VehicleRolloverIndicator``, ``veds:MultipleImpactsIndicator``, the incident
  id (``event_id``) and time (``occurred_at``); the model year (``nc:ItemModelYearDate``)
  becomes ``vehicle.model_year``; make and model are recorded.

An unknown unit, a missing delta-V or a seat code that does not exist are
refused, never guessed. Personal data of the document (names, contacts, persons) are not
mapped and never logged; the document itself is kept with the case for audit.
"""

from __future__ import annotations

import hashlib
import json
import re
from dataclasses import dataclass, field
from datetime import datetime
from decimal import Decimal
from typing import Any, Final
from xml.etree.ElementTree import Element

from pydantic import ValidationError

from models import limits, units
from models.assumptions import Assumption, AssumptionCode
from models.notification import AirbagState, Seat
from service.cases import veds_xml
from service.cases.notification import CrashNotificationIn, ReceivedSource
from service.cases.veds_xml import J_NAMESPACE, NC_NAMESPACE, VEDS_NAMESPACES, _qualified, parse_xml
from service.problems import FieldError, UnprocessableNotification

__all__ = [
    "KM_PER_MILE",
    "VEDS_MEDIA_TYPE",
    "VedsNotification",
    "clock_to_pdof_deg",
    "delta_v_to_kmh",
    "is_veds_media_type",
    "read_veds",
]


#: The media type of RFC 8148 section 6 (compared case-insensitively).
VEDS_MEDIA_TYPE: Final = "application/EmergencyCallData.VEDS+xml"


#: Kilometres in one international mile, exactly (:data:`models.units.KM_PER_MILE`,
#: the one home of the constant), as a decimal. Applied in decimal arithmetic: an
#: MPH value and its exact KPH twin give the same float.
KM_PER_MILE: Final = Decimal(repr(units.KM_PER_MILE))


#: VEDS seat location codes (VehicleSeatLocationCategoryCode) and the seats of
#: the service: every code has one (the field risk model answers every seat).
SEAT_CODES: Final[dict[str, Seat]] = {
    "1": Seat.DRIVER,
    "2": Seat.FRONT_PASSENGER,
    "3": Seat.REAR_LEFT,
    "4": Seat.REAR_MIDDLE,
    "5": Seat.REAR_RIGHT,
    "6": Seat.THIRD_ROW_LEFT,
    "7": Seat.THIRD_ROW_MIDDLE,
    "8": Seat.THIRD_ROW_RIGHT,
    "9": Seat.FRONT_MIDDLE,
}


#: VEDS AirbagCategoryCode values; ROOF and SEAT (belt) airbags have no field here.
AIRBAG_CATEGORIES: Final = frozenset({"FRONT", "SIDE", "CURTAIN", "ROOF", "SEAT"})


#: Delta-V units (nc:MeasureUnitText) and their factor to km/h.
DELTA_V_UNITS: Final[dict[str, Decimal]] = {"KPH": Decimal(1), "MPH": KM_PER_MILE}


#: Notification fields VEDS cannot carry, and the code of what the engine then assumes
#: (recorded in every VEDS case's mapping: "occupant age unknown" and the like).
NOT_IN_VEDS: Final[tuple[tuple[str, AssumptionCode], ...]] = (
    ("occupants[].age_years", AssumptionCode.AGE_IMPUTED),
    ("occupants[].stature_cm, mass_kg", AssumptionCode.BMI_IMPUTED),
    ("occupants[].body", AssumptionCode.BODY_UNKNOWN),
    ("occupants[].posture_lumbar_flexion_deg", AssumptionCode.POSTURE_NOT_SENSED),
    ("occupants[].seat_track_mm", AssumptionCode.SEAT_POSITION_NOT_SENSED),
)


#: A model year (``nc:ItemModelYearDate``, an xs:gYear): four ASCII digits.
_YEAR = re.compile(r"[0-9]{4}")
#: The model years the notification takes (``vehicle.model_year``).
MIN_MODEL_YEAR: Final = 1950
MAX_MODEL_YEAR: Final = 2100


_EVENT_ID = re.compile(r"^[\x21-\x7e]{1,128}$")


_BOOLEANS: Final = {"true": True, "1": True, "false": False, "0": False}


def _said(flag: bool | None) -> str:
    return "absent" if flag is None else str(flag).lower()


def is_veds_media_type(content_type: str) -> bool:
    """Whether a Content-Type header names the VEDS media type (parameters ignored)."""
    return content_type.split(";", 1)[0].strip().lower() == VEDS_MEDIA_TYPE.lower()


def delta_v_to_kmh(value: Decimal, unit: str) -> float:
    """A delta-V magnitude in km/h from a VEDS value and its unit.

    Parameters
    ----------
    value : Decimal
        ``nc:MeasurePointValue`` as written (its sign is the direction of the velocity
        change, which the PDOF gives; the magnitude is used).
    unit : {"KPH", "MPH"}
        ``nc:MeasureUnitText``.

    Returns
    -------
    float
        ``|value|`` km/h; MPH times :data:`KM_PER_MILE` in exact decimal arithmetic,
        rounded to a float once, so that ``20`` MPH and ``32.18688`` KPH are the same.
    """
    return float(abs(value) * DELTA_V_UNITS[unit])


def clock_to_pdof_deg(hour: int) -> float:
    """PDOF in degrees clockwise from straight ahead, from a clock direction 1-12.

    12 o'clock is frontal (0 deg), 3 the right side (90), 6 the rear (180), 9 the
    left side (270): 30 deg an hour.
    """
    return float((hour % 12) * 30)


@dataclass(frozen=True)
class VedsNotification:
    """A VEDS document mapped to the service's notification.

    Attributes
    ----------
    notification : CrashNotificationIn
        The validated notification the document maps to.
    document : dict
        Its JSON form (what a JSON client would have sent), stored as the case's
        notification.
    source : ReceivedSource
        The XML as received, the mapping record and its assumptions.
    """

    notification: CrashNotificationIn
    document: dict[str, Any]
    source: ReceivedSource


def _unprocessable(errors: list[FieldError]) -> UnprocessableNotification:
    n = len(errors)
    return UnprocessableNotification(
        f"The VEDS document cannot be triaged: {n} element{'s' if n != 1 else ''} refused.",
        errors=errors,
    )


def _refuse(path: str, reason: str, kind: str) -> UnprocessableNotification:
    return _unprocessable([FieldError(field=path, reason=reason, type=kind)])


@dataclass
class _Mapper:
    """Reads one VEDS document's elements, recording what it maps and assumes."""

    veds_ns: str
    mapped: list[dict[str, Any]] = field(default_factory=list)
    assumed: list[Assumption] = field(default_factory=list)
    #: the notification field each assumption concerns (same order as `assumed`)
    assumed_fields: list[str] = field(default_factory=list)
    ignored: list[dict[str, str]] = field(default_factory=list)
    #: JSON field path -> the element it came from (to name elements in errors)
    paths: dict[str, str] = field(default_factory=dict)

    def tag(self, name: str) -> str:
        prefix, _, local = name.partition(":")
        ns = {"veds": self.veds_ns, "nc": NC_NAMESPACE, "j": J_NAMESPACE}[prefix]
        return f"{{{ns}}}{local}"

    def all(self, parent: Element, name: str) -> list[Element]:
        tag = self.tag(name)
        return [child for child in parent if child.tag == tag]

    def one(self, parent: Element, name: str, path: str, *, required: bool) -> Element | None:
        found = self.all(parent, name)
        here = f"{path}/{name}" if path else name
        if len(found) > 1:
            raise _refuse(here, f"appears {len(found)} times; one is expected", "veds_repeated")
        if not found:
            if required:
                raise _refuse(here, "missing", "veds_missing")
            return None
        return found[0]

    def text(self, parent: Element, name: str, path: str, *, required: bool) -> str | None:
        element = self.one(parent, name, path, required=required)
        if element is None:
            return None
        value = (element.text or "").strip()
        if not value and required:
            raise _refuse(f"{path}/{name}", "empty", "veds_missing")
        return value or None

    def need(self, parent: Element, name: str, path: str) -> Element:
        """The one child `name` of `parent`, which must be there."""
        found = self.one(parent, name, path, required=True)
        assert found is not None  # one() raised otherwise
        return found

    def need_text(self, parent: Element, name: str, path: str) -> str:
        """The text of the one child `name`, which must be there and not empty."""
        value = self.text(parent, name, path, required=True)
        assert value is not None  # text() raised otherwise
        return value

    def boolean(self, parent: Element, name: str, path: str, *, required: bool) -> bool | None:
        value = self.text(parent, name, path, required=required)
        if value is None:
            return None
        if value not in _BOOLEANS:
            raise _refuse(
                f"{path}/{name}",
                f"{value!r} is not an xsd:boolean (true, false, 1, 0)",
                "veds_boolean",
            )
        return _BOOLEANS[value]

    def map(self, element: str, field_path: str, value: Any, note: str | None = None) -> None:
        entry: dict[str, Any] = {"element": element, "field": field_path, "value": value}
        if note:
            entry["note"] = note
        self.mapped.append(entry)
        self.paths.setdefault(field_path, element)

    def assume(
        self, code: AssumptionCode, message: str, occupant: int | None = None, *, field: str
    ) -> None:
        self.assumed.append(Assumption(code, message, occupant))
        self.assumed_fields.append(field)

    def ignore(self, element: str, reason: str) -> None:
        self.ignored.append({"element": element, "reason": reason})


@dataclass(frozen=True)
class _Pulse:
    path: str
    delta_v_kmh: float
    pdof_deg: float
    quarter_turns: int
    written: str


def _pulse(m: _Mapper, pulse: Element, path: str) -> _Pulse:
    measure_path = f"{path}/veds:CrashPulseChangeInVelocityMeasure"
    measure = m.need(pulse, "veds:CrashPulseChangeInVelocityMeasure", path)
    value_text = m.need_text(measure, "nc:MeasurePointValue", measure_path)
    unit = m.need_text(measure, "nc:MeasureUnitText", measure_path)
    if not veds_xml.is_xsd_decimal(value_text):
        raise _refuse(
            f"{measure_path}/nc:MeasurePointValue",
            f"{value_text!r} is not a decimal number",
            "veds_number",
        )
    if unit.upper() not in DELTA_V_UNITS:
        raise _refuse(
            f"{measure_path}/nc:MeasureUnitText",
            f"unknown delta-V unit {unit!r}: VEDS gives KPH or MPH",
            "veds_unit",
        )
    unit = unit.upper()
    delta_v_kmh = delta_v_to_kmh(Decimal(value_text), unit)
    if delta_v_kmh == 0.0:
        raise _refuse(
            f"{measure_path}/nc:MeasurePointValue", "a delta-V of 0 is no crash pulse", "veds_range"
        )
    if delta_v_kmh > limits.MAX_DELTA_V_KMH:
        raise _refuse(
            f"{measure_path}/nc:MeasurePointValue",
            f"{value_text} {unit} = {delta_v_kmh:.1f} km/h exceeds the plausible "
            f"{limits.MAX_DELTA_V_KMH:g} km/h",
            "veds_range",
        )
    pdof_path = f"{path}/veds:CrashPulsePrincipalDirectionOfForceValue"
    clock = m.need_text(pulse, "veds:CrashPulsePrincipalDirectionOfForceValue", path)
    hour = veds_xml.xsd_integer(clock)
    if hour is None or not 1 <= hour <= 12:
        raise _refuse(
            pdof_path, f"{clock!r} is not a clock direction 1-12 (12 frontal)", "veds_clock"
        )
    turns_text = m.text(pulse, "veds:CrashPulseRolloverQuarterTurnsValue", path, required=False)
    turns = 0 if turns_text is None else veds_xml.xsd_integer(turns_text)
    if turns is None or turns < 0:
        raise _refuse(
            f"{path}/veds:CrashPulseRolloverQuarterTurnsValue",
            f"{turns_text!r} is not a non-negative integer",
            "veds_number",
        )
    return _Pulse(
        path=path,
        delta_v_kmh=delta_v_kmh,
        pdof_deg=clock_to_pdof_deg(hour),
        quarter_turns=turns,
        written=f"{value_text} {unit}, {hour} o'clock",
    )


def _crash(
    m: _Mapper, crash: Element, vehicle: Element, crash_path: str, vehicle_path: str
) -> dict[str, Any]:
    pulses = m.all(vehicle, "veds:VehicleCrashPulse")
    if not pulses:
        raise _refuse(
            f"{vehicle_path}/veds:VehicleCrashPulse",
            "missing: a crash pulse (delta-V and its direction) is needed to triage",
            "veds_missing",
        )
    read = [
        _pulse(m, p, f"{vehicle_path}/veds:VehicleCrashPulse[{i + 1}]")
        for i, p in enumerate(pulses)
    ]
    worst = max(read, key=lambda p: p.delta_v_kmh)  # the first of equals
    value_path = f"{worst.path}/veds:CrashPulseChangeInVelocityMeasure/nc:MeasurePointValue"
    m.map(value_path, "crash.pulse.delta_v_kmh", worst.delta_v_kmh, worst.written)
    m.map(
        f"{worst.path}/veds:CrashPulsePrincipalDirectionOfForceValue",
        "crash.pulse.pdof_deg",
        worst.pdof_deg,
        "clock hours x 30 deg (12 o'clock = 0)",
    )
    m.paths["crash.pulse"] = worst.path
    if len(read) > 1:
        m.assume(
            AssumptionCode.VEDS_MOST_SEVERE_PULSE,
            f"{len(read)} crash pulses: the largest delta-V ({worst.written}) was triaged",
            field="crash.pulse",
        )

    indicator = m.boolean(crash, "veds:MultipleImpactsIndicator", crash_path, required=False)
    multiple = bool(indicator) or len(read) > 1
    m.map(
        f"{crash_path}/veds:MultipleImpactsIndicator"
        if indicator is not None
        else f"{vehicle_path}/veds:VehicleCrashPulse",
        "crash.multiple_impacts",
        multiple,
        f"{len(read)} pulse(s); indicator {_said(indicator)}",
    )
    # each pulse is one event the vehicle recorded: two or more count the impacts
    count = len(read) if len(read) > 1 else None
    if count is not None:
        m.map(
            f"{vehicle_path}/veds:VehicleCrashPulse",
            "crash.impact_count",
            count,
            f"{len(read)} pulses",
        )
    rolled = m.boolean(vehicle, "veds:VehicleRolloverIndicator", vehicle_path, required=False)
    most_turns = max(read, key=lambda p: p.quarter_turns)  # the first of equals
    turns = most_turns.quarter_turns
    turns_path = f"{most_turns.path}/veds:CrashPulseRolloverQuarterTurnsValue"
    if turns > 0:  # an error on the field names this element
        m.map(turns_path, "crash.rollover_quarter_turns", turns, "the most of any pulse")
    if rolled is False and turns > 0:  # the JSON rule: explicit false with turns is refused
        raise _refuse(
            turns_path,
            f"{turns} quarter turns contradict veds:VehicleRolloverIndicator false (a quarter "
            "turn is a rollover)",
            "veds_rollover_contradiction",
        )
    rollover = bool(rolled) or turns > 0
    m.map(
        f"{vehicle_path}/veds:VehicleRolloverIndicator"
        if rolled is not None
        else f"{vehicle_path}/veds:VehicleCrashPulse",
        "crash.rollover",
        rollover,
        f"indicator {_said(rolled)}; most quarter turns {turns}",
    )
    out: dict[str, Any] = {
        "pulse": {
            "kind": "summary",
            "delta_v_kmh": worst.delta_v_kmh,
            "pdof_deg": worst.pdof_deg,
        },
        "multiple_impacts": multiple,
        "rollover": rollover,
        "rollover_quarter_turns": turns if turns > 0 else None,
    }
    if count is not None:
        out["impact_count"] = count
    return out


def _airbag_states(m: _Mapper, vehicle: Element, vehicle_path: str) -> dict[str, list[bool]]:
    """Reported deployed flags per airbag group (``frontal``: FRONT, ``side``: SIDE, CURTAIN)."""
    groups: dict[str, list[bool]] = {"frontal": [], "side": []}
    for i, bag in enumerate(m.all(vehicle, "veds:Airbag")):
        path = f"{vehicle_path}/veds:Airbag[{i + 1}]"
        category = m.need_text(bag, "veds:AirbagCategoryCode", path)
        if category.upper() not in AIRBAG_CATEGORIES:
            raise _refuse(
                f"{path}/veds:AirbagCategoryCode",
                f"unknown airbag category {category!r}: VEDS gives "
                + ", ".join(sorted(AIRBAG_CATEGORIES)),
                "veds_airbag_category",
            )
        category = category.upper()
        deployed = m.boolean(bag, "veds:AirbagDeployedIndicator", path, required=False)
        if category in ("ROOF", "SEAT"):
            m.ignore(path, f"{category} airbags have no field in the notification")
        elif deployed is None:
            m.ignore(path, "no veds:AirbagDeployedIndicator: its state is unknown")
        else:
            groups["frontal" if category == "FRONT" else "side"].append(deployed)
    return groups


def _group_state(flags: list[bool]) -> AirbagState | None:
    """The state all reported airbags of a group share; None when they disagree or none."""
    if not flags or (any(flags) and not all(flags)):
        return None
    return AirbagState.DEPLOYED if flags[0] else AirbagState.NOT_DEPLOYED


def _occupants(m: _Mapper, vehicle: Element, vehicle_path: str) -> list[dict[str, Any]]:
    bags = _airbag_states(m, vehicle, vehicle_path)
    frontal = _group_state(bags["frontal"])
    side = _group_state(bags["side"])
    occupants: list[dict[str, Any]] = []
    seen: dict[Seat, str] = {}
    seats = m.all(vehicle, "veds:VehicleSeat")
    for i, seat_element in enumerate(seats):
        path = f"{vehicle_path}/veds:VehicleSeat[{i + 1}]"
        code_path = f"{path}/veds:VehicleSeatLocationCategoryCode"
        code = m.need_text(seat_element, "veds:VehicleSeatLocationCategoryCode", path)
        if code not in SEAT_CODES:
            raise _refuse(
                code_path,
                f"{code!r} is not a VEDS seat location code (1-9)",
                "veds_seat_code",
            )
        occupied = m.boolean(seat_element, "veds:VehicleSeatOccupiedIndicator", path, required=True)
        if not occupied:
            m.ignore(path, f"seat code {code} not occupied")
            continue
        seat = SEAT_CODES[code]
        if seat in seen:
            raise _refuse(
                code_path,
                f"seat code {code} appears twice (first at {seen[seat]})",
                "veds_seat_repeated",
            )
        seen[seat] = path
        index = len(occupants)
        prefix = f"occupants[{index}]"
        m.map(code_path, f"{prefix}.seat", seat.value, f"code {code}")
        m.paths[prefix] = path

        fastened = m.boolean(
            seat_element, "veds:VehicleSeatbeltFastenedIndicator", path, required=False
        )
        monitored = m.boolean(
            seat_element, "veds:VehicleSeatbeltMonitoredIndicator", path, required=False
        )
        occupant: dict[str, Any] = {"seat": seat.value}  # belt unknown: integrated over
        if fastened is None or monitored is False:
            why = "not reported" if fastened is None else "not monitored"
            m.assume(
                AssumptionCode.VEDS_BELT_NOT_REPORTED,
                f"{prefix}: belt {why} (seat code {code}): belt use unknown",
                index,
                field=f"{prefix}.belted",
            )
        else:
            occupant["belted"] = fastened
            m.map(f"{path}/veds:VehicleSeatbeltFastenedIndicator", f"{prefix}.belted", fastened)

        if seat.front_row:
            occupant["frontal_airbag"] = (frontal or AirbagState.NOT_DEPLOYED).value
        else:
            occupant["frontal_airbag"] = AirbagState.ABSENT.value
            m.map(
                f"{vehicle_path}/veds:Airbag",
                f"{prefix}.frontal_airbag",
                "absent",
                f"{seat.value}: no frontal airbag in front of it (VEDS FRONT airbags are the "
                "driver's and front passenger's)",
            )
        if side is not None:
            occupant["side_airbag"] = side.value
        occupants.append(occupant)

    if not occupants:
        raise _refuse(
            f"{vehicle_path}/veds:VehicleSeat",
            "no occupied seat: at least one occupied veds:VehicleSeat is needed to triage",
            "veds_missing",
        )
    _note_airbags(m, occupants, bags, frontal, side, vehicle_path)
    return occupants


def _note_airbags(
    m: _Mapper,
    occupants: list[dict[str, Any]],
    bags: dict[str, list[bool]],
    frontal: AirbagState | None,
    side: AirbagState | None,
    vehicle_path: str,
) -> None:
    """Record how the airbags were given to seats (VEDS airbags name no seat)."""
    element = f"{vehicle_path}/veds:Airbag"
    front_row = [i for i, o in enumerate(occupants) if Seat(o["seat"]).front_row]
    if front_row:
        if not bags["frontal"]:
            m.assume(
                AssumptionCode.VEDS_FRONTAL_AIRBAG_NOT_REPORTED,
                "no FRONT airbag reported: front-row frontal airbags taken as not deployed",
                field="occupants.frontal_airbag",
            )
        elif frontal is None:
            m.assume(
                AssumptionCode.VEDS_AIRBAG_AMBIGUOUS,
                f"FRONT airbags disagree ({sum(bags['frontal'])} of {len(bags['frontal'])} "
                "deployed) and name no seat: front-row frontal airbags taken as not deployed",
                field="occupants.frontal_airbag",
            )
        else:
            m.assume(
                AssumptionCode.VEDS_AIRBAG_BY_CATEGORY,
                f"every reported FRONT airbag ({len(bags['frontal'])}) is {frontal.value}: "
                "given to each front-row seat",
                field="occupants.frontal_airbag",
            )
        for i in front_row:
            m.map(element, f"occupants[{i}].frontal_airbag", occupants[i]["frontal_airbag"])
    if bags["side"] and side is None:
        m.assume(
            AssumptionCode.VEDS_AIRBAG_AMBIGUOUS,
            f"SIDE/CURTAIN airbags disagree ({sum(bags['side'])} of {len(bags['side'])} "
            "deployed) and name no seat: side airbags not reported",
            field="occupants.side_airbag",
        )
    elif side is not None:
        m.assume(
            AssumptionCode.VEDS_AIRBAG_BY_CATEGORY,
            f"every reported SIDE/CURTAIN airbag ({len(bags['side'])}) is {side.value}: "
            "given to each seat",
            field="occupants.side_airbag",
        )
        for i in range(len(occupants)):
            m.map(element, f"occupants[{i}].side_airbag", side.value)


def _first_time(m: _Mapper, parent: Element, name: str, path: str) -> tuple[str, str] | None:
    holder = m.one(parent, name, path, required=False)
    if holder is None:
        return None
    here = f"{path}/{name}" if path else name
    value = m.text(holder, "nc:DateTime", here, required=False)
    return (value, f"{here}/nc:DateTime") if value else None


def _occurred_at(
    m: _Mapper, root: Element, crash: Element, crash_path: str, received_at: datetime
) -> tuple[str, bool]:
    """The crash time as RFC 3339 text, and whether it was assumed."""
    own = _first_time(m, crash, "nc:ActivityDate", crash_path)
    if own is not None:
        m.map(own[1], "occurred_at", own[0])
        return own[0], False
    for name in ("nc:DocumentReceivedDate", "nc:DocumentPostDate"):
        found = _first_time(m, root, name, "")
        if found is not None:
            m.map(found[1], "occurred_at", found[0], "no incident time: this time used")
            m.assume(
                AssumptionCode.VEDS_CRASH_TIME_ASSUMED,
                f"no incident time: {found[1]} taken as the crash time",
                field="occurred_at",
            )
            m.paths["occurred_at"] = found[1]
            return found[0], True
    m.assume(
        AssumptionCode.VEDS_CRASH_TIME_ASSUMED,
        "no time in the document: the time the service received it taken as the crash time",
        field="occurred_at",
    )
    return received_at.isoformat(), True


def _event_id(m: _Mapper, crash: Element, crash_path: str, raw: bytes) -> str:
    ident = m.one(crash, "nc:ActivityIdentification", crash_path, required=False)
    if ident is not None:
        path = f"{crash_path}/nc:ActivityIdentification"
        value = m.text(ident, "nc:IdentificationID", path, required=False)
        if value is not None:
            if not _EVENT_ID.match(value):
                raise _refuse(
                    f"{path}/nc:IdentificationID",
                    "the incident id must be 1-128 printable ASCII characters without spaces "
                    "(it is the event_id)",
                    "veds_incident_id",
                )
            m.map(f"{path}/nc:IdentificationID", "event_id", value)
            return value
    digest = "veds-sha256:" + hashlib.sha256(raw).hexdigest()
    m.map("(the document)", "event_id", digest, "no incident id: SHA-256 of the document")
    return digest


def _model_year(m: _Mapper, vehicle: Element, vehicle_path: str) -> str | None:
    """The model year as written when it is one, else None and an assumption naming the
    element (a malformed year must not cost the crash its triage, nor reach NEMSIS)."""
    year = m.text(vehicle, "nc:ItemModelYearDate", vehicle_path, required=False)
    if year is None or (_YEAR.fullmatch(year) and MIN_MODEL_YEAR <= int(year) <= MAX_MODEL_YEAR):
        return year
    m.assume(
        AssumptionCode.VEDS_MODEL_YEAR_DROPPED,
        f"{vehicle_path}/nc:ItemModelYearDate {year[: veds_xml.MAX_NUMBER_CHARS]!r} is not a "
        f"model year (four ASCII digits, {MIN_MODEL_YEAR}-{MAX_MODEL_YEAR}): dropped",
        field="vehicle.model_year",
    )
    return None


def _vehicle_facts(m: _Mapper, vehicle: Element, vehicle_path: str) -> dict[str, str | None]:
    facts = {
        "make": m.text(vehicle, "nc:ItemMakeName", vehicle_path, required=False),
        "model": m.text(vehicle, "nc:ItemModelName", vehicle_path, required=False),
        "model_year": _model_year(m, vehicle, vehicle_path),
        "body_category_code": m.text(
            vehicle, "j:VehicleBodyCategoryCode", vehicle_path, required=False
        ),
    }
    m.assume(
        AssumptionCode.VEDS_VEHICLE_CLASS_ASSUMED,
        "the occupant models' default vehicle class (compact_sedan) used for "
        + (
            " ".join(v for v in (facts["make"], facts["model"], facts["model_year"]) if v)
            or "an unnamed vehicle"
        ),
        field="vehicle.model",
    )
    m.assume(
        AssumptionCode.VEDS_DRIVE_SIDE_ASSUMED,
        "no drive side in VEDS: left-hand drive assumed",
        field="vehicle.drive_side",
    )
    return facts


def _field_of(loc: tuple[Any, ...]) -> str:
    text = ""
    for part in loc:
        if isinstance(part, int):
            text += f"[{part}]"
        elif part not in ("summary",):
            text += f".{part}" if text else str(part)
    return text


def _element_for(m: _Mapper, field_path: str) -> str:
    """The element a JSON field came from (its nearest mapped parent's)."""
    probe = field_path
    while probe:
        if probe in m.paths:
            return m.paths[probe]
        cut = max(probe.rfind("."), probe.rfind("["))
        probe = probe[:cut] if cut > 0 else ""
    return field_path


def read_veds(raw: bytes, *, received_at: datetime) -> VedsNotification:
    """Read a VEDS document and map it to the service's notification.

    Parameters
    ----------
    raw : bytes
        The request body (``application/EmergencyCallData.VEDS+xml``).
    received_at : datetime
        When the service received it: the crash time when the document has none.

    Raises
    ------
    MalformedXml
        400: not one safe, well-formed UTF-8 XML document (see `parse_xml`).
    UnprocessableNotification
        422: not VEDS (root element or namespace), or an element the notification
        needs is missing or refused (unit, delta-V, PDOF, seat code, ...); each error
        names the element.
    """
    root = parse_xml(raw)
    ns, _, local = root.tag[1:].partition("}") if root.tag.startswith("{") else ("", "", root.tag)
    if local != "AutomatedCrashNotification" or ns not in VEDS_NAMESPACES:
        raise _refuse(
            _qualified(root.tag),
            "the root element must be veds:AutomatedCrashNotification in the VEDS namespace "
            f"({' or '.join(VEDS_NAMESPACES)}); got {local!r} in "
            f"{ns or 'no namespace'!r}",
            "veds_root",
        )
    m = _Mapper(veds_ns=ns)
    crash = m.need(root, "veds:Crash", "")
    crash_path = "veds:Crash"
    vehicle = m.need(crash, "veds:CrashVehicle", crash_path)
    vehicle_path = f"{crash_path}/veds:CrashVehicle"

    event_id = _event_id(m, crash, crash_path, raw)
    occurred_at, time_assumed = _occurred_at(m, root, crash, crash_path, received_at)
    crash_doc = _crash(m, crash, vehicle, crash_path, vehicle_path)
    occupants = _occupants(m, vehicle, vehicle_path)
    vehicle_facts = _vehicle_facts(m, vehicle, vehicle_path)
    if m.all(root, "veds:Person") or m.all(crash, "veds:CrashPerson"):
        m.ignore(
            "veds:Person",
            "persons are not linked to seats in VEDS: no occupant's age or sex is taken from them",
        )
    document: dict[str, Any] = {
        "event_id": event_id,
        "occurred_at": occurred_at,
        "crash": crash_doc,
        "occupants": occupants,
    }
    year = vehicle_facts["model_year"]  # a model year, or None (_model_year)
    if year is not None:
        document["vehicle"] = {"model_year": int(year)}
        m.map(f"{vehicle_path}/nc:ItemModelYearDate", "vehicle.model_year", int(year))
    try:
        notification = CrashNotificationIn.model_validate_json(json.dumps(document), strict=True)
    except ValidationError as exc:
        raise _unprocessable(
            [
                FieldError(
                    field=_element_for(m, _field_of(tuple(e["loc"]))),
                    reason=str(e["msg"]).removeprefix("Value error, "),
                    type=str(e["type"]),
                )
                for e in exc.errors()
            ]
        ) from exc
    mapping = {
        "veds_version": VEDS_NAMESPACES[ns],
        "namespace": ns,
        "vehicle": vehicle_facts,
        "mapped": m.mapped,
        "assumed": [
            {"code": a.code.value, "field": f, "message": a.message, "occupant": a.occupant}
            for a, f in zip(m.assumed, m.assumed_fields, strict=True)
        ],
        "ignored": m.ignored,
        "not_in_veds": [{"field": f, "code": code.value} for f, code in NOT_IN_VEDS],
    }
    source = ReceivedSource(
        format="veds",
        document=raw.decode("utf-8"),
        mapping=mapping,
        assumptions=tuple(m.assumed),
        occurred_at_assumed=time_assumed,
    )
    return VedsNotification(notification=notification, document=document, source=source)
