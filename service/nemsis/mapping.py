"""A stored case as a NEMSIS v3.5.1 ``EMSDataSet``: one PatientCareReport per occupant.

What each element is filled from is in ``docs/api.md`` (the mapping table). In short:

- The ACN block (``eInjury.CollisionGroup``, NEMSIS's copy of VEDS 3.0) from the
  crash: incident id (``event_id``), time, delta-V in km/h (``VelocityUnit``
  9921001, the resultant the case was triaged on, to the integer NEMSIS carries),
  PDOF as a clock hour, multiple impacts, rollover, one seat group per occupant
  (seat, occupied, belt, airbag deployed); for a VEDS case also the vehicle's make,
  model, year and body type.
- Per occupant, from the tier of the occupant's decision: eInjury.04 2904013
  ("vehicle telemetry data consistent with severe injury") for the high and moderate
  tiers, eInjury.23 "high probability of injury" Yes for the high tier alone, and a
  narrative (eNarrative.01) that names the tier, the probability and the thresholds;
  the occupant's seat (eInjury.06) and airbags (eInjury.08); age and sex.
- Every other element NEMSIS requires: NV 7701003 "Not Recorded", except the
  elements NEMSIS allows no not-value, which describe the EMS unit's own response
  and carry the documented placeholders of :data:`~service.nemsis.codes.PLACEHOLDERS`.

A fact the case does not hold (a field the sender left out, or that a VEDS mapping
assumed rather than read) is never written as if known: its element is left out
(optional) or NV-coded (required), and the record's :class:`RecordReport` lists what
was left out and which placeholders were written (an XML comment in each report,
and the ``NEMSIS-Left-Out`` / ``NEMSIS-Placeholders`` headers of the HTTP answer).
"""

from __future__ import annotations

import math
import re
import uuid
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from decimal import ROUND_HALF_UP, Decimal
from typing import Any, Final

from lxml import etree
from pydantic import AwareDatetime, TypeAdapter, ValidationError

from models.notification import ChildRestraint, pediatric_crash_criterion
from models.tiers import HIGH_RISK_THRESHOLD, Tier
from service import __version__
from service.cases.result import StoredCase
from service.nemsis import codes
from service.nemsis.codes import NAMESPACE, NOT_RECORDED, Group, Kind, Leaf
from service.nemsis.veds_source import VedsFacts, veds_facts

__all__ = [
    "SCHEMA_LOCATION",
    "Agency",
    "NemsisRecord",
    "Omission",
    "RecordReport",
    "build_record",
    "narrative",
    "pdof_clock_hour",
    "report_number",
    "report_uuid",
]

XSI: Final = "http://www.w3.org/2001/XMLSchema-instance"
#: Where NEMSIS publishes the schema (``xsi:schemaLocation``; never fetched here).
SCHEMA_LOCATION: Final = (
    "https://nemsis.org/media/nemsis_v3/3.5.1.250403CP1/XSDs/NEMSIS_XSDs/EMSDataSet_v3.xsd"
)
#: Name of this software in eRecord.02 and .03.
SOFTWARE: Final = "aacn-triage"
#: Namespace of the PatientCareReport UUIDs (uuid5 of case id and occupant): the same
#: case gives the same UUIDs every time, so a receiving ePCR can recognise a re-sent record.
UUID_NAMESPACE: Final = uuid.UUID("6f1d3c52-5a0e-4e55-9d3b-6a0c2f4b8e17")
#: VEDS assumption codes whose field was not in the document (so it is unknown here).
#: ``veds_airbag_by_category`` is not among them: the state was reported, only not by seat.
UNREPORTED_VEDS_CODES: Final = frozenset(
    {
        "veds_crash_time_assumed",
        "veds_belt_not_reported",
        "veds_frontal_airbag_not_reported",
        "veds_airbag_ambiguous",
        "veds_drive_side_assumed",
        "veds_vehicle_class_assumed",
    }
)
#: Lengths of the eInjury strings (eInjury_v3.xsd: IncidentID, BodyType, Make, Model).
INCIDENT_ID_CHARS: Final = (2, 100)
VEHICLE_TEXT_CHARS: Final = {"eInjury.16": (2, 100), "eInjury.18": (2, 100), "eInjury.19": (1, 100)}
#: Model years eInjury.20 takes (eInjury_v3.xsd ``Year``).
YEAR_RANGE: Final = (1900, 2050)
#: Ages ePatient.15 takes (ePatient_v3.xsd ``Age``), in its unit.
AGE_RANGE: Final = (1, 120)
#: Months in a year (ages under one year are written in months, ePatient.16 Months).
MONTHS_PER_YEAR: Final = 12
_AWARE: Final = TypeAdapter(AwareDatetime)
_AGENCY_TEXT = re.compile(r"^[\x20-\x7e]+$")
_STATE_CODE = re.compile(r"^[0-9]{2}$")


@dataclass(frozen=True)
class Agency:
    """The EMS agency a record is handed to (NEMSIS makes its identity mandatory).

    Attributes
    ----------
    state_id : str
        dAgency.01, EMS Agency Unique State ID (1-50 characters).
    number : str
        dAgency.02 and eResponse.01, EMS Agency Number (1-15 characters).
    state : str
        dAgency.04, the ANSI (FIPS) code of the state that assigned the number, 2 digits.
    """

    state_id: str
    number: str
    state: str

    def problems(self) -> list[tuple[str, str]]:
        """``(field, reason)`` of each value NEMSIS would refuse (empty: valid)."""
        out = []
        for name, value, longest in (("state_id", self.state_id, 50), ("number", self.number, 15)):
            if not (1 <= len(value) <= longest and _AGENCY_TEXT.match(value)):
                out.append((name, f"must be 1-{longest} printable ASCII characters"))
        if not _STATE_CODE.match(self.state):
            out.append(("state", "must be the two-digit ANSI state code, e.g. 09"))
        return out


@dataclass(frozen=True)
class Omission:
    """An element left out of a report: the case does not know it, or it does not fit."""

    occupant: int | None
    element: str
    reason: str


@dataclass(frozen=True)
class RecordReport:
    """What a record took from the case, what it left out, which placeholders it holds.

    Attributes
    ----------
    filled : tuple of (int or None, str, str)
        ``(occupant, element, source)`` of each element filled from the case (occupant
        None: every report of the case).
    left_out : tuple of Omission
    placeholders : tuple of str
        The elements carrying a :data:`~service.nemsis.codes.PLACEHOLDERS` value (in
        every report).
    """

    filled: tuple[tuple[int | None, str, str], ...]
    left_out: tuple[Omission, ...]
    placeholders: tuple[str, ...] = tuple(codes.PLACEHOLDERS)

    def left_out_elements(self) -> list[str]:
        """Each element left out of some report, once, in element order."""
        return sorted({o.element for o in self.left_out}, key=_element_order)


@dataclass(frozen=True)
class NemsisRecord:
    """A case's EMSDataSet document and its report."""

    case_id: str
    document: bytes
    report: RecordReport


def _element_order(name: str) -> tuple[str, int]:
    section, _, number = name.partition(".")
    return section, int(number) if re.fullmatch(r"[0-9]{1,9}", number) else 0


def report_uuid(case_id: str, occupant: int) -> str:
    """The PatientCareReport UUID of an occupant (uuid5: the same every time)."""
    return str(uuid.uuid5(UUID_NAMESPACE, f"{case_id}/{occupant}"))


def report_number(case_id: str, occupant: int) -> str:
    """eRecord.01: the case id and the occupant's position from 1."""
    return f"{case_id}-{occupant + 1}"


def pdof_clock_hour(pdof_deg: float) -> int:
    """PDOF in degrees clockwise from straight ahead as a clock hour 1-12 (12 frontal).

    The nearest hour, halves rounded up (15 deg is 1 o'clock); the inverse of
    :func:`service.cases.veds.clock_to_pdof_deg` on whole hours.
    """
    hour = math.floor((pdof_deg % 360.0) / 30.0 + 0.5) % 12
    return 12 if hour == 0 else hour


def _integer_kmh(delta_v_kmh: float) -> int:
    """eInjury.22 holds an integer: km/h to the nearest, halves up."""
    return int(Decimal(repr(delta_v_kmh)).quantize(Decimal(1), rounding=ROUND_HALF_UP))


def _nemsis_time(at: datetime) -> str:
    """``DateTimeType``: seconds and a numeric offset (``+00:00``, never ``Z``)."""
    if at.tzinfo is None:  # a store that drops the offset keeps UTC
        at = at.replace(tzinfo=UTC)
    return at.isoformat()


def _comment_text(text: str) -> str:
    """Text that may stand in an XML comment (no ``--``, no trailing ``-``)."""
    while "--" in text:
        text = text.replace("--", "- -")
    return " " + text.rstrip("-") + "\n"


# ------------------------------------------------------------------ the facts


@dataclass
class _Facts:
    """What the stored case knows, field by field (module docstring)."""

    case: StoredCase
    unreported: frozenset[str]
    veds: VedsFacts | None = None
    filled: list[tuple[int | None, str, str]] = field(default_factory=list)
    left_out: list[Omission] = field(default_factory=list)

    @classmethod
    def of(cls, case: StoredCase) -> _Facts:
        assumed = (case.source_mapping or {}).get("assumed") or []
        unreported = frozenset(
            str(a.get("field"))
            for a in assumed
            if isinstance(a, Mapping) and a.get("code") in UNREPORTED_VEDS_CODES
        )
        document = case.source_document if case.source_format == "veds" else None
        return cls(
            case=case, unreported=unreported, veds=veds_facts(document) if document else None
        )

    @property
    def notification(self) -> Mapping[str, Any]:
        return self.case.notification

    def occupant(self, i: int) -> Mapping[str, Any]:
        occupants = self.notification.get("occupants") or []
        return occupants[i] if i < len(occupants) and isinstance(occupants[i], Mapping) else {}

    def given(self, path: str, occupant: int | None = None) -> Any:
        """The value of a notification field the sender gave, else None.

        `path` is dotted below the notification, or below the occupant when `occupant`
        is given. A field absent from the notification as received, or one a VEDS
        mapping assumed, is not given.
        """
        full = f"occupants[{occupant}].{path}" if occupant is not None else path
        if full in self.unreported or (
            occupant is not None and f"occupants.{path}" in self.unreported
        ):
            return None
        node: Any = self.occupant(occupant) if occupant is not None else self.notification
        for part in path.split("."):
            if not isinstance(node, Mapping) or part not in node:
                return None
            node = node[part]
        return node

    def fill(self, element: str, source: str, occupant: int | None = None) -> None:
        self.filled.append((occupant, element, source))

    def leave_out(self, element: str, reason: str, occupant: int | None = None) -> None:
        self.left_out.append(Omission(occupant, element, reason))


def _occurred_at(facts: _Facts) -> datetime | None:
    """The crash time as the sender gave it (its own offset), parsed as the contract does."""
    text = facts.given("occurred_at")
    if not isinstance(text, str):
        return None
    try:
        return _AWARE.validate_python(text)
    except ValidationError:
        return None


def _airbags_deployed(facts: _Facts, i: int) -> bool | None:
    """Whether any airbag at the occupant's seat deployed; None when not known."""
    frontal = facts.given("frontal_airbag", i)
    side = facts.given("side_airbag", i)
    if "deployed" in (frontal, side):
        return True
    if frontal in ("not_deployed", "absent") and side in ("not_deployed", "absent"):
        return False
    return None


# ------------------------------------------------------------------ writing


class _Writer:
    """Appends NEMSIS elements (namespace, not-values) to a parent."""

    @staticmethod
    def add(parent: etree._Element, name: str, text: str | None = None, **attrs: str) -> Any:
        element = etree.SubElement(parent, f"{{{NAMESPACE}}}{name}", attrs)
        if text is not None:
            element.text = text
        return element

    @classmethod
    def not_recorded(cls, parent: etree._Element, name: str) -> None:
        element = cls.add(parent, name, NV=NOT_RECORDED)
        element.set(f"{{{XSI}}}nil", "true")

    @classmethod
    def template(
        cls, parent: etree._Element, node: Group | Leaf, values: Mapping[str, Sequence[str]]
    ) -> None:
        """Write a template node: its values, else its not-value (module docstring)."""
        if isinstance(node, Group):
            group = cls.add(parent, node.name)
            for child in node.children:
                cls.template(group, child, values)
            return
        given = values.get(node.name)
        if given:
            for value in given:
                cls.add(parent, node.name, value)
        elif node.kind is Kind.NOT_RECORDED:
            cls.not_recorded(parent, node.name)
        else:  # pragma: no cover - a defect of this module, caught by the tests
            raise KeyError(f"{node.name} is mandatory and was given no value")


# ------------------------------------------------------------------ eInjury


def _seat_group(facts: _Facts, parent: etree._Element, i: int) -> None:
    """eInjury.SeatGroup of occupant `i` (.26 seat, .27 occupied, .28 belt, .29 airbag)."""
    w = _Writer
    seat = str(facts.occupant(i).get("seat", ""))
    code = codes.SEAT_LOCATION.get(seat)
    if code is None:
        facts.leave_out("eInjury.SeatGroup", f"seat {seat!r} has no NEMSIS seat location", i)
        return
    group = w.add(parent, "eInjury.SeatGroup")
    w.add(group, "eInjury.26", code)
    w.add(group, "eInjury.27", codes.ACN_YES_NO[True])
    facts.fill("eInjury.26", f"occupants[{i}].seat", None)
    belted = facts.given("belted", i)
    if isinstance(belted, bool):
        w.add(group, "eInjury.28", codes.ACN_YES_NO[belted])
        facts.fill("eInjury.28", f"occupants[{i}].belted", None)
    else:
        facts.leave_out("eInjury.28", f"belt of occupants[{i}] not reported", None)
    deployed = _airbags_deployed(facts, i)
    if deployed is None:
        facts.leave_out("eInjury.29", f"airbags at occupants[{i}]'s seat not all reported", None)
    else:
        w.add(group, "eInjury.29", codes.ACN_YES_NO[deployed])
        facts.fill("eInjury.29", f"occupants[{i}].frontal_airbag, side_airbag", None)


def _delta_velocities(facts: _Facts, group: etree._Element) -> None:
    """eInjury.22: the triaged delta-V; every pulse of a VEDS document, in its order."""
    triaged = facts.case.result.pulse.delta_v_kmh
    pulses: tuple[float, ...] = (triaged,)
    source = "result.pulse.delta_v_kmh (km/h, nearest integer)"
    # a VEDS case's pulses, when the triaged one (the largest) is among them
    if facts.veds is not None and facts.veds.delta_v_kmh and max(facts.veds.delta_v_kmh) == triaged:
        pulses = facts.veds.delta_v_kmh
        source = "source_document: each veds:VehicleCrashPulse in order (km/h, nearest integer)"
    for ordinal, delta_v_kmh in enumerate(pulses, start=1):
        _Writer.add(
            group,
            "eInjury.22",
            str(_integer_kmh(delta_v_kmh)),
            VelocityUnit=codes.VELOCITY_UNIT_KMH,
            DeltaVelocityOrdinal=str(ordinal),
        )
    facts.fill("eInjury.22", source)


def _empty_seat_groups(facts: _Facts, group: etree._Element) -> None:
    """eInjury.SeatGroup with eInjury.27 "N" for each seat a VEDS document reports empty."""
    if facts.veds is None:
        return
    taken = {
        codes.SEAT_LOCATION.get(str(facts.occupant(i).get("seat", "")))
        for i in range(len(facts.case.result.occupants))
    }
    for code in facts.veds.empty_seats:
        location = codes.VEDS_SEAT_LOCATION.get(code)
        if location is None or location in taken:
            continue
        taken.add(location)
        seat = _Writer.add(group, "eInjury.SeatGroup")
        _Writer.add(seat, "eInjury.26", location)
        _Writer.add(seat, "eInjury.27", codes.ACN_YES_NO[False])
        facts.fill("eInjury.27", f"source_document: seat code {code} not occupied")


def _vehicle_facts(facts: _Facts) -> dict[str, str]:
    """eInjury.16, .18-.20 from a VEDS case's vehicle (JSON notifications carry none)."""
    vehicle = (facts.case.source_mapping or {}).get("vehicle") or {}
    if not isinstance(vehicle, Mapping):
        vehicle = {}
    out: dict[str, str] = {}
    for element, key in (
        ("eInjury.16", "body_category_code"),
        ("eInjury.18", "make"),
        ("eInjury.19", "model"),
    ):
        value = vehicle.get(key)
        low, high = VEHICLE_TEXT_CHARS[element]
        if isinstance(value, str) and low <= len(value) <= high:
            out[element] = value
            facts.fill(element, f"source_mapping.vehicle.{key}")
        else:
            facts.leave_out(element, f"no vehicle {key.replace('_', ' ')} in the notification")
    year = vehicle.get("model_year")
    # four ASCII digits: a case stored with another script's digits ("٢٠١٠") is left out
    if isinstance(year, str) and re.fullmatch(r"[0-9]{4}", year.strip()):
        if YEAR_RANGE[0] <= int(year) <= YEAR_RANGE[1]:
            out["eInjury.20"] = year.strip()
            facts.fill("eInjury.20", "source_mapping.vehicle.model_year")
    if "eInjury.20" not in out:
        facts.leave_out("eInjury.20", "no model year (1900-2050) in the notification")
    return out


def _collision_group(facts: _Facts, parent: etree._Element, i: int) -> None:
    """eInjury.CollisionGroup (.11-.29) of the report of occupant `i`."""
    w = _Writer
    case = facts.case
    group = w.add(parent, "eInjury.CollisionGroup")
    first = i == 0  # case-level facts are recorded once
    note = facts if first else _Facts(case=case, unreported=facts.unreported, veds=facts.veds)
    note.leave_out("eInjury.11", "the ACN company is not in the notification")
    low, high = INCIDENT_ID_CHARS
    if low <= len(case.event_id) <= high:
        w.add(group, "eInjury.12", case.event_id)
        note.fill("eInjury.12", "event_id")
    else:
        note.leave_out("eInjury.12", f"event_id is not {low}-{high} characters")
    note.leave_out("eInjury.13", "no call-back number in the notification")
    occurred = _occurred_at(facts)
    if occurred is not None:
        w.add(group, "eInjury.14", _nemsis_time(occurred))
        note.fill("eInjury.14", "occurred_at")
    else:
        note.leave_out("eInjury.14", "the crash time was not in the notification")
    note.leave_out("eInjury.15", "no location in the notification")
    vehicle = _vehicle_facts(note)
    if "eInjury.16" in vehicle:
        w.add(group, "eInjury.16", vehicle["eInjury.16"])
    note.leave_out("eInjury.17", "no manufacturer in the notification")
    for element in ("eInjury.18", "eInjury.19", "eInjury.20"):
        if element in vehicle:
            w.add(group, element, vehicle[element])
    multiple = facts.given("crash.multiple_impacts")
    count = facts.given("crash.impact_count")
    if isinstance(multiple, bool):
        w.add(group, "eInjury.21", codes.YES_NO[multiple])
        note.fill("eInjury.21", "crash.multiple_impacts")
    elif isinstance(count, int):  # a count alone says it: 2 or more are multiple impacts
        w.add(group, "eInjury.21", codes.YES_NO[count >= 2])
        note.fill("eInjury.21", "crash.impact_count (2 or more: yes)")
    else:
        note.leave_out("eInjury.21", "multiple impacts not reported")
    pulse = case.result.pulse
    _delta_velocities(note, group)
    high = case.result.occupants[i].triage.tier is Tier.HIGH
    w.add(group, "eInjury.23", codes.YES_NO[high])
    facts.fill("eInjury.23", f"result.occupants[{i}].triage.tier (high: yes)", i)
    w.add(group, "eInjury.24", str(pdof_clock_hour(pulse.pdof_deg)))
    note.fill("eInjury.24", "result.pulse.pdof_deg (clock hour)")
    rollover = facts.given("crash.rollover")
    turns = facts.given("crash.rollover_quarter_turns")
    if isinstance(rollover, bool):
        w.add(group, "eInjury.25", codes.ACN_YES_NO[rollover])
        note.fill("eInjury.25", "crash.rollover")
    elif isinstance(turns, int) and not isinstance(turns, bool) and turns > 0:
        w.add(group, "eInjury.25", codes.ACN_YES_NO[True])  # a quarter turn is a rollover
        note.fill("eInjury.25", "crash.rollover_quarter_turns (above 0: yes)")
    else:
        note.leave_out("eInjury.25", "rollover not reported")
    for seat in range(len(case.result.occupants)):
        _seat_group(note, group, seat)
    _empty_seat_groups(note, group)


def _seat_row_location(facts: _Facts, i: int) -> str | None:
    """eInjury.06 of occupant `i`; None when its side of the car is not known."""
    seat = str(facts.occupant(i).get("seat", ""))
    if seat in codes.SEAT_ROW_LOCATION_RIGHT_HAND_DRIVE:
        side = facts.given("vehicle.drive_side")
        if side == "right":
            return codes.SEAT_ROW_LOCATION_RIGHT_HAND_DRIVE[seat]
        if side != "left":
            return None
    return codes.SEAT_ROW_LOCATION.get(seat)


def _airbag_deployment(facts: _Facts, i: int) -> list[str] | None:
    """eInjury.08 codes of occupant `i`; None when not known."""
    frontal = facts.given("frontal_airbag", i)
    side = facts.given("side_airbag", i)
    deployed = [
        codes.AIRBAG_DEPLOYMENT[name]
        for name, state in (("front", frontal), ("side", side))
        if state == "deployed"
    ]
    if deployed:
        return deployed
    if frontal == side == "absent":
        return [codes.AIRBAG_DEPLOYMENT["none_present"]]
    if frontal in ("not_deployed", "absent") and side in ("not_deployed", "absent"):
        return [codes.AIRBAG_DEPLOYMENT["none_deployed"]]
    return None


def _injury(facts: _Facts, parent: etree._Element, i: int) -> None:
    """The eInjury section of occupant `i`'s report."""
    w = _Writer
    section = w.add(parent, "eInjury")
    w.not_recorded(section, "eInjury.01")
    w.not_recorded(section, "eInjury.03")
    criteria = []
    if facts.case.result.occupants[i].triage.tier in (Tier.HIGH, Tier.MODERATE):
        criteria.append(codes.TRIAGE_TELEMETRY_SEVERE)
        facts.fill("eInjury.04", f"result.occupants[{i}].triage.tier (high, moderate: 2904013)", i)
    if _pediatric_criterion(facts, i):
        criteria.append(codes.TRIAGE_CHILD_UNRESTRAINED)
        facts.fill(
            "eInjury.04",
            f"occupants[{i}].age_years, child_restraint, belted, child_restraint_unsecured "
            "(a child of 0-9 unrestrained or in an unsecured seat: 2904029)",
            i,
        )
    for code in criteria:
        w.add(section, "eInjury.04", code)
    if not criteria:
        w.not_recorded(section, "eInjury.04")
    row = _seat_row_location(facts, i)
    if row is not None:
        w.add(section, "eInjury.06", row)
        facts.fill("eInjury.06", f"occupants[{i}].seat, vehicle.drive_side", i)
    else:
        facts.leave_out("eInjury.06", "the side of the car of this seat is not known", i)
    restraint = facts.given("child_restraint", i)
    if isinstance(restraint, str) and restraint in codes.CHILD_RESTRAINT_EQUIPMENT:
        w.add(section, "eInjury.07", codes.CHILD_RESTRAINT_EQUIPMENT[restraint])
        facts.fill("eInjury.07", f"occupants[{i}].child_restraint", i)
    bags = _airbag_deployment(facts, i)
    if bags is None:
        facts.leave_out("eInjury.08", "the airbags at this seat are not all reported", i)
    else:
        for code in bags:
            w.add(section, "eInjury.08", code)
        facts.fill("eInjury.08", f"occupants[{i}].frontal_airbag, side_airbag", i)
    _collision_group(facts, section, i)


def _pediatric_criterion(facts: _Facts, i: int) -> bool:
    """The guideline's pediatric crash criterion from occupant `i`'s stored fields."""
    age = facts.given("age_years", i)
    restraint = facts.given("child_restraint", i)
    belted = facts.given("belted", i)
    unsecured = facts.given("child_restraint_unsecured", i)
    try:
        kind = ChildRestraint(restraint) if isinstance(restraint, str) else None
    except ValueError:
        kind = None
    return pediatric_crash_criterion(
        float(age) if isinstance(age, int | float) and not isinstance(age, bool) else None,
        kind,
        belted if isinstance(belted, bool) else None,
        unsecured if isinstance(unsecured, bool) else None,
    )


#: The narrative's words for each tier (``models.tiers``).
NARRATIVE_TIERS: Final = {
    Tier.HIGH: "HIGH RISK (at or above the high-risk threshold {high})",
    Tier.MODERATE: "MODERATE RISK (at or above the operating threshold {threshold}, below the "
    "high-risk threshold {high}: the 2021 field triage guideline's telemetry criterion)",
    Tier.NONE: "NO TELEMETRY INDICATION (below the operating threshold {threshold})",
}


def _pct_text(p: float) -> str:
    return f"{100.0 * p:.1f} %"


def narrative(case: StoredCase, i: int) -> str:
    """eNarrative.01 of occupant `i`: the tier in words, its probability and thresholds."""
    d = case.result.occupants[i].triage
    seat = str(case.result.occupants[i].seat.value).replace("_", " ")
    tier = d.tier or Tier.NONE
    high = d.high_threshold if d.high_threshold is not None else HIGH_RISK_THRESHOLD
    words = NARRATIVE_TIERS[tier].format(threshold=_pct_text(d.threshold), high=_pct_text(high))
    low, up = d.probability_ci95
    text = (
        f"Automatic crash notification, occupant {i + 1} of {len(case.result.occupants)} "
        f"({seat}): {words}. P(ISS 15+) {_pct_text(d.probability)} (95 % interval "
        f"{_pct_text(low)} to {_pct_text(up)}), {d.model}"
        + (f" at operating point {d.operating_point}" if d.operating_point else "")
        + f". Recommendation: {d.recommendation}"
        + _delta_v_words(case)
    )
    if case.tiers_derived:
        text += (
            " (Case stored before risk tiers: the tier is that of the stored probability and "
            "threshold, the high-risk threshold at its default.)"
        )
    return text


def _delta_v_words(case: StoredCase) -> str:
    """The delta-V and where it came from (measured by the vehicle, or reconstructed)."""
    source = case.result.pulse.delta_v_source
    source_words = {
        "measured": "measured by the vehicle (EDR or telematics)",
        "reconstructed": "reconstructed from the vehicle's crush",
    }.get(str(source), str(source))
    return f" Delta-V {case.result.pulse.delta_v_kmh:.1f} km/h, {source_words}."


def _narrative(facts: _Facts, parent: etree._Element, i: int) -> None:
    section = _Writer.add(parent, "eNarrative")
    _Writer.add(section, "eNarrative.01", narrative(facts.case, i))
    facts.fill("eNarrative.01", f"result.occupants[{i}].triage (tier, probability, thresholds)", i)


# ------------------------------------------------------------------ the report


def _patient_values(facts: _Facts, i: int) -> dict[str, list[str]]:
    """Template values of occupant `i` (ePatient and eSituation)."""
    values: dict[str, list[str]] = {}
    age = facts.given("age_years", i)
    if isinstance(age, int | float) and not isinstance(age, bool):
        # completed years; under one year, completed months (MONTHS_PER_YEAR, exact)
        years, months = math.floor(age), math.floor(age * MONTHS_PER_YEAR)
        if AGE_RANGE[0] <= years <= AGE_RANGE[1]:
            values["ePatient.15"] = [str(years)]
            values["ePatient.16"] = [codes.AGE_UNIT_YEARS]
            facts.fill("ePatient.15", f"occupants[{i}].age_years (completed years)", i)
        elif years < AGE_RANGE[0] and months >= AGE_RANGE[0]:
            values["ePatient.15"] = [str(months)]
            values["ePatient.16"] = [codes.AGE_UNIT_MONTHS]
            facts.fill("ePatient.15", f"occupants[{i}].age_years x 12 (completed months)", i)
        else:
            facts.leave_out("ePatient.15", "age under one month: Not Recorded", i)
    sex = facts.given("sex", i)
    if isinstance(sex, str) and sex in codes.SEX:
        values["ePatient.25"] = [codes.SEX[sex]]
        facts.fill("ePatient.25", f"occupants[{i}].sex", i)
    occurred = _occurred_at(facts)
    if occurred is not None:
        values["eSituation.01"] = [_nemsis_time(occurred)]
        facts.fill("eSituation.01", "occurred_at (the injury's onset is the crash)", i)
    return values


def _report_comment(facts: _Facts, i: int, n: int) -> str:
    seat = str(facts.occupant(i).get("seat", "?"))
    mine = [f for f in facts.filled if f[0] in (None, i)]
    gone = [o for o in facts.left_out if o.occupant in (None, i)]
    lines = [
        f"aacn-triage {__version__}: case {facts.case.case_id}, occupant {i + 1} of {n} "
        f"(seat {seat}).",
        "Filled from the case: " + "; ".join(f"{e} <- {s}" for _, e, s in mine) + ".",
        "Left out (not known, never guessed): "
        + ("; ".join(f"{o.element} ({o.reason})" for o in gone) or "none")
        + ".",
        "Placeholders (NEMSIS allows no not-value; the receiving agency's record replaces "
        "them): " + ", ".join(codes.PLACEHOLDERS) + ".",
        f'Every other required element: NV="{NOT_RECORDED}" (Not Recorded).',
    ]
    return "".join(_comment_text(line) for line in lines)


def _report(facts: _Facts, parent: etree._Element, i: int, base: Mapping[str, list[str]]) -> None:
    """One PatientCareReport: occupant `i`."""
    case = facts.case
    n = len(case.result.occupants)
    pcr = _Writer.add(parent, "PatientCareReport", UUID=report_uuid(case.case_id, i))
    values = {
        **base,
        "eRecord.01": [report_number(case.case_id, i)],
        **_patient_values(facts, i),
    }
    for section in codes.SECTIONS:
        if section.name == "eInjury":
            _injury(facts, pcr, i)
        elif section.name == "eNarrative":
            _narrative(facts, pcr, i)
        else:
            _Writer.template(pcr, section, values)
    pcr.insert(0, etree.Comment(_report_comment(facts, i, n)))


def _placeholder_values(case: StoredCase) -> dict[str, list[str]]:
    received = _nemsis_time(case.received_at)
    return {
        element: [received if p.value == "received_at" else p.value]
        for element, p in codes.PLACEHOLDERS.items()
    }


def build_record(case: StoredCase, agency: Agency) -> NemsisRecord:
    """The EMSDataSet of a stored case, handed to `agency`, and its report.

    Deterministic: the same case and agency give the same bytes (no clock is read;
    the report UUIDs are uuid5 of the case id). Not validated here
    (:func:`service.nemsis.validate.validate`).
    """
    facts = _Facts.of(case)
    root = etree.Element(
        f"{{{NAMESPACE}}}EMSDataSet",
        {f"{{{XSI}}}schemaLocation": f"{NAMESPACE} {SCHEMA_LOCATION}"},
        nsmap={None: NAMESPACE, "xsi": XSI},  # type: ignore[dict-item]  # stubs: no None
    )
    header = _Writer.add(root, "Header")
    demographic = _Writer.add(header, "DemographicGroup")
    _Writer.add(demographic, "dAgency.01", agency.state_id)
    _Writer.add(demographic, "dAgency.02", agency.number)
    _Writer.add(demographic, "dAgency.04", agency.state)
    base = {
        **_placeholder_values(case),
        "eRecord.02": [SOFTWARE],
        "eRecord.03": [SOFTWARE],
        "eRecord.04": [__version__],
        "eResponse.01": [agency.number],
        "eDispatch.01": [codes.COMPLAINT_TRAFFIC_INCIDENT],
    }
    for i in range(len(case.result.occupants)):
        _report(facts, header, i, base)
    document = etree.tostring(root, xml_declaration=True, encoding="UTF-8", pretty_print=True)
    report = RecordReport(filled=tuple(facts.filled), left_out=tuple(facts.left_out))
    return NemsisRecord(case_id=case.case_id, document=document, report=report)
