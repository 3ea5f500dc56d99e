"""NEMSIS v3.5.1 code lists and the element template of a patient care report.

Every code here is copied from the shipped schemas (``service/nemsis/xsd/``, release
3.5.1.250403CP1; the file and simple type are named with each table), so a test can
check each against the XSD's enumeration.

The template (:data:`SECTIONS`) lists, in schema order, the elements of a
``PatientCareReport`` that this service writes: every element the XSD requires
(``minOccurs`` >= 1), and the optional ones it can fill. Each is of one kind:

- ``NOT_RECORDED``: required and nillable; written ``xsi:nil="true" NV="7701003"``
  ("Not Recorded") unless the case gives a value. Every nillable required element of
  v3.5.1 allows 7701003 (checked against the XSD's ``NV`` unions).
- ``MANDATORY``: required and not nillable (NEMSIS usage "Mandatory": no not-value
  allowed); the mapping must give a value, either from the case or a documented
  placeholder (:data:`PLACEHOLDERS`).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Final

__all__ = [
    "CHILD_RESTRAINT_EQUIPMENT",
    "AGE_UNIT_MONTHS",
    "AGE_UNIT_YEARS",
    "AIRBAG_DEPLOYMENT",
    "COMPLAINT_TRAFFIC_INCIDENT",
    "NAMESPACE",
    "NOT_RECORDED",
    "PLACEHOLDERS",
    "SEAT_LOCATION",
    "SEAT_ROW_LOCATION",
    "SEAT_ROW_LOCATION_RIGHT_HAND_DRIVE",
    "SECTIONS",
    "SEX",
    "TRIAGE_CHILD_UNRESTRAINED",
    "TRIAGE_TELEMETRY_SEVERE",
    "VEDS_SEAT_LOCATION",
    "VELOCITY_UNIT_KMH",
    "YES_NO",
    "ACN_YES_NO",
    "Group",
    "Kind",
    "Leaf",
    "Placeholder",
]

#: Namespace of every NEMSIS v3 element.
NAMESPACE: Final = "http://www.nemsis.org"
#: NV (not value) "Not Recorded" (commonTypes_v3.xsd, ``NV.NotRecorded``).
NOT_RECORDED: Final = "7701003"

#: eInjury.21, .23 (commonTypes_v3.xsd ``YesNoValues``): 9923001 No, 9923003 Yes.
YES_NO: Final[dict[bool, str]] = {False: "9923001", True: "9923003"}
#: eInjury.25, .27-.29 (eInjury_v3.xsd ``ACNYesNoType``).
ACN_YES_NO: Final[dict[bool, str]] = {False: "N", True: "Y"}
#: eInjury.22 ``VelocityUnit`` (commonTypes_v3.xsd ``VelocityUnits``): Kilometers per Hour.
VELOCITY_UNIT_KMH: Final = "9921001"
#: eInjury.04 (eInjury_v3.xsd ``TraumaTriageCriteriaSteps3and4``): "Auto Crash: Vehicle
#: telemetry data consistent with severe injury".
TRIAGE_TELEMETRY_SEVERE: Final = "2904013"
#: eInjury.04: "Auto Crash: Child (age 0-9 years) unrestrained or in unsecured child
#: safety seat" (the 2021 guideline's pediatric crash criterion).
TRIAGE_CHILD_UNRESTRAINED: Final = "2904029"
#: eInjury.07 "Use of Occupant Safety Equipment" (eInjury_v3.xsd
#: ``UseOfOccupantSafetyEquipment``) of the wire's `child_restraint`: infant seats rear
#: and forward facing, booster, a seat of unknown kind as Other, the lap-shoulder belt,
#: none.
CHILD_RESTRAINT_EQUIPMENT: Final[dict[str, str]] = {
    "rear_facing_seat": "2907009",  # Infant Car Seat Rear Facing
    "forward_facing_seat": "2907007",  # Infant Car Seat Forward Facing
    "booster": "2907001",  # Child Booster Seat
    "child_seat_unknown_kind": "2907017",  # Other
    "lap_shoulder_belt": "2907027",  # Shoulder and Lap Belt Used
    "none": "2907015",  # None
}
#: eDispatch.01 (eDispatch_v3.xsd ``DispatchReason``): "Traffic/Transportation Incident".
COMPLAINT_TRAFFIC_INCIDENT: Final = "2301069"
#: ePatient.16 (ePatient_v3.xsd ``AgeUnits``): Years, Months.
AGE_UNIT_YEARS: Final = "2516009"
AGE_UNIT_MONTHS: Final = "2516007"
#: ePatient.25 (commonTypes_v3.xsd ``Sex``), by the notification's ``sex``.
SEX: Final[dict[str, str]] = {"female": "9919001", "male": "9919003"}

#: eInjury.26 "ACN Vehicle Seat Location" (eInjury_v3.xsd ``SeatLocation``), by the
#: notification's seat name. Every seat NEMSIS has is here, so that seats the wire
#: contract adds (front middle, third row) map without a change here; a seat name that
#: is not here is left out of the record and said so, never guessed.
SEAT_LOCATION: Final[dict[str, str]] = {
    "driver": "2926001",  # Driver Front Seat
    "front_middle": "2926003",  # Front Row Middle Seat
    "front_passenger": "2926005",  # Passenger Front Seat
    "rear_left": "2926007",  # Second Row Left Seat
    "rear_middle": "2926009",  # Second Row Middle Seat
    "rear_right": "2926011",  # Second Row Right Seat
    "third_row_left": "2926013",  # Third Row Left Seat
    "third_row_middle": "2926015",  # Third Row Middle Seat
    "third_row_right": "2926017",  # Third Row Right Seat
}
#: VEDS ``VehicleSeatLocationCategoryCode`` (1 driver, 2 front passenger, 3-5 second row
#: left/middle/right, 6-8 third row, 9 front middle) and its eInjury.26 code: NEMSIS's
#: ACN block is VEDS's, seat for seat.
VEDS_SEAT_LOCATION: Final[dict[str, str]] = {
    "1": "2926001",
    "2": "2926005",
    "3": "2926007",
    "4": "2926009",
    "5": "2926011",
    "6": "2926013",
    "7": "2926015",
    "8": "2926017",
    "9": "2926003",
}
#: eInjury.06 "Location of Patient in Vehicle" (eInjury_v3.xsd ``SeatRowLocation``), by
#: seat name for a left-hand-drive vehicle (the driver on the left). Right-hand drive
#: swaps the front row's sides (:func:`service.nemsis.mapping` does).
SEAT_ROW_LOCATION: Final[dict[str, str]] = {
    "driver": "2906001",  # Front Seat-Left Side
    "front_middle": "2906003",  # Front Seat-Middle
    "front_passenger": "2906005",  # Front Seat-Right Side
    "rear_left": "2906013",  # Second Seat-Left Side
    "rear_middle": "2906015",  # Second Seat-Middle
    "rear_right": "2906017",  # Second Seat-Right Side
    "third_row_left": "2906021",  # Third Row-Left Side
    "third_row_middle": "2906023",  # Third Row-Middle
    "third_row_right": "2906025",  # Third Row-Right Side
}
#: Front-row eInjury.06 codes of a right-hand-drive vehicle (the driver on the right).
SEAT_ROW_LOCATION_RIGHT_HAND_DRIVE: Final[dict[str, str]] = {
    "driver": "2906005",
    "front_passenger": "2906001",
}
#: eInjury.08 "Airbag Deployment" (eInjury_v3.xsd ``AirbagDeployment``).
AIRBAG_DEPLOYMENT: Final[dict[str, str]] = {
    "front": "2908001",  # Airbag Deployed Front
    "side": "2908003",  # Airbag Deployed Side
    "none_deployed": "2908007",  # No Airbag Deployed
    "none_present": "2908009",  # No Airbag Present
}


@dataclass(frozen=True)
class Placeholder:
    """A value written where NEMSIS allows no not-value and a crash notification cannot know.

    Attributes
    ----------
    element : str
    value : str
        The value written; ``"received_at"`` stands for the time the service received
        the notification.
    meaning : str
        What the value means in NEMSIS's words.
    why : str
        Why this value: the receiving agency's ePCR replaces it.
    """

    element: str
    value: str
    meaning: str
    why: str


_AGENCY: Final = "the receiving agency's record replaces it"

#: The MANDATORY elements of a patient care report that a crash notification cannot know
#: (they describe the EMS unit's own response). NEMSIS allows them no not-value, so a
#: schema-valid record carries these placeholders; each record lists them (XML comment,
#: ``NEMSIS-Placeholders`` header) and ``docs/api.md`` documents them.
PLACEHOLDERS: Final[dict[str, Placeholder]] = {
    p.element: p
    for p in (
        Placeholder(
            "eResponse.05",
            "2205001",
            "Emergency Response (Primary Response Area)",
            "what a crash notification requests; whether the responding unit is in its "
            f"primary area is the agency's: {_AGENCY}",
        ),
        Placeholder(
            "eResponse.07",
            "2207015",
            "Ground Transport (ALS Equipped)",
            f"the responding unit's capability is not known here: {_AGENCY}",
        ),
        Placeholder(
            "eResponse.13",
            "UNASSIGNED",
            "EMS Vehicle (Unit) Number",
            f"no unit is assigned when the record is written: {_AGENCY}",
        ),
        Placeholder(
            "eResponse.14",
            "UNASSIGNED",
            "EMS Unit Call Sign",
            f"no unit is assigned when the record is written: {_AGENCY}",
        ),
        Placeholder(
            "eResponse.23",
            "2223001",
            "Emergent (Immediate Response)",
            f"the mode a crash notification asks for; the unit's actual mode is the agency's: "
            f"{_AGENCY}",
        ),
        Placeholder(
            "eTimes.03",
            "received_at",
            "Unit Notified by Dispatch Date/Time",
            f"the time the service received the notification, not a unit's: {_AGENCY}",
        ),
        Placeholder(
            "eTimes.13",
            "received_at",
            "Unit Back in Service Date/Time",
            f"the time the service received the notification, not a unit's: {_AGENCY}",
        ),
        Placeholder(
            "eDisposition.27",
            "4227001",
            "Patient Contact Made",
            "one record per occupant reported in the vehicle; whether the crew made contact "
            f"is the agency's: {_AGENCY}",
        ),
    )
}


class Kind(Enum):
    """How the template writes an element (module docstring)."""

    NOT_RECORDED = "not_recorded"
    MANDATORY = "mandatory"


@dataclass(frozen=True)
class Leaf:
    """One element of the template."""

    name: str
    kind: Kind = Kind.NOT_RECORDED


@dataclass(frozen=True)
class Group:
    """A group element of the template and its children, in schema order."""

    name: str
    children: tuple[Leaf | Group, ...]


def _nv(*names: str) -> tuple[Leaf, ...]:
    return tuple(Leaf(n) for n in names)


_M = Kind.MANDATORY

#: The sections of a PatientCareReport in schema order (EMSDataSet_v3.xsd), each with the
#: elements written (module docstring). ``eInjury`` is built by the mapping itself (its
#: ACN block repeats per seat), as is ``eNarrative`` (the occupant's tier in words); they
#: are listed empty here to keep the order.
SECTIONS: Final[tuple[Group, ...]] = (
    Group(
        "eRecord",
        (
            Leaf("eRecord.01", _M),
            Group(
                "eRecord.SoftwareApplicationGroup",
                (Leaf("eRecord.02", _M), Leaf("eRecord.03", _M), Leaf("eRecord.04", _M)),
            ),
        ),
    ),
    Group(
        "eResponse",
        (
            Group("eResponse.AgencyGroup", (Leaf("eResponse.01", _M),)),
            *_nv("eResponse.03", "eResponse.04"),
            Group("eResponse.ServiceGroup", (Leaf("eResponse.05", _M),)),
            Leaf("eResponse.07", _M),
            *_nv("eResponse.08", "eResponse.09", "eResponse.10", "eResponse.11", "eResponse.12"),
            Leaf("eResponse.13", _M),
            Leaf("eResponse.14", _M),
            Leaf("eResponse.23", _M),
            Leaf("eResponse.24"),
        ),
    ),
    Group("eDispatch", (Leaf("eDispatch.01", _M), Leaf("eDispatch.02"))),
    Group(
        "eTimes",
        (
            Leaf("eTimes.01"),
            Leaf("eTimes.03", _M),
            *_nv("eTimes.05", "eTimes.06", "eTimes.07", "eTimes.09", "eTimes.11", "eTimes.12"),
            Leaf("eTimes.13", _M),
        ),
    ),
    Group(
        "ePatient",
        (
            *_nv("ePatient.07", "ePatient.08", "ePatient.09", "ePatient.14"),
            Group("ePatient.AgeGroup", _nv("ePatient.15", "ePatient.16")),
            Leaf("ePatient.25"),
        ),
    ),
    Group("ePayment", _nv("ePayment.01", "ePayment.50")),
    Group(
        "eScene",
        _nv(
            "eScene.01",
            "eScene.06",
            "eScene.07",
            "eScene.08",
            "eScene.09",
            "eScene.18",
            "eScene.19",
            "eScene.21",
        ),
    ),
    Group(
        "eSituation",
        (
            *_nv("eSituation.01", "eSituation.02", "eSituation.07", "eSituation.08"),
            *_nv("eSituation.09", "eSituation.10", "eSituation.11", "eSituation.12"),
            *_nv("eSituation.13", "eSituation.18", "eSituation.20"),
        ),
    ),
    Group("eInjury", ()),
    Group(
        "eArrest",
        _nv(
            *(f"eArrest.{n:02d}" for n in (1, 2, 3, 4, 7, 9, 11, 12, 14, 16, 17, 18, 20, 21, 22)),
        ),
    ),
    Group("eHistory", _nv("eHistory.01", "eHistory.17")),
    Group("eNarrative", ()),
    Group(
        "eVitals",
        (
            Group(
                "eVitals.VitalGroup",
                (
                    *_nv("eVitals.01", "eVitals.02"),
                    Group(
                        "eVitals.CardiacRhythmGroup", _nv("eVitals.03", "eVitals.04", "eVitals.05")
                    ),
                    Group("eVitals.BloodPressureGroup", _nv("eVitals.06")),
                    Group("eVitals.HeartRateGroup", _nv("eVitals.10")),
                    *_nv("eVitals.12", "eVitals.14", "eVitals.16", "eVitals.18"),
                    Group(
                        "eVitals.GlasgowScoreGroup",
                        _nv("eVitals.19", "eVitals.20", "eVitals.21", "eVitals.22"),
                    ),
                    Leaf("eVitals.26"),
                    Group("eVitals.PainScaleGroup", _nv("eVitals.27")),
                    Group("eVitals.StrokeScaleGroup", _nv("eVitals.29", "eVitals.30")),
                    Leaf("eVitals.31"),
                ),
            ),
        ),
    ),
    Group("eProtocols", (Group("eProtocols.ProtocolGroup", _nv("eProtocols.01")),)),
    Group(
        "eMedications",
        (
            Group(
                "eMedications.MedicationGroup",
                (
                    *_nv(
                        "eMedications.01", "eMedications.02", "eMedications.03", "eMedications.04"
                    ),
                    Group("eMedications.DosageGroup", _nv("eMedications.05", "eMedications.06")),
                    *_nv("eMedications.07", "eMedications.08", "eMedications.10"),
                ),
            ),
        ),
    ),
    Group(
        "eProcedures",
        (
            Group(
                "eProcedures.ProcedureGroup",
                _nv(
                    *(f"eProcedures.{n:02d}" for n in (1, 2, 3, 5, 6, 7, 8, 10)),
                ),
            ),
        ),
    ),
    Group(
        "eDisposition",
        (
            Group(
                "eDisposition.DestinationGroup",
                _nv("eDisposition.05", "eDisposition.06", "eDisposition.07"),
            ),
            Group(
                "eDisposition.IncidentDispositionGroup",
                (
                    Leaf("eDisposition.27", _M),
                    *_nv("eDisposition.28", "eDisposition.29", "eDisposition.30"),
                ),
            ),
            *_nv(*(f"eDisposition.{n}" for n in (16, 17, 18, 19, 20, 21, 22, 23))),
            Group(
                "eDisposition.HospitalTeamActivationGroup",
                _nv("eDisposition.24", "eDisposition.25"),
            ),
            Leaf("eDisposition.32"),
        ),
    ),
    Group(
        "eOutcome",
        (
            *_nv("eOutcome.01", "eOutcome.02"),
            Group("eOutcome.EmergencyDepartmentProceduresGroup", _nv("eOutcome.09", "eOutcome.19")),
            *_nv("eOutcome.10", "eOutcome.11"),
            Group("eOutcome.HospitalProceduresGroup", _nv("eOutcome.12", "eOutcome.20")),
            *_nv("eOutcome.13", "eOutcome.16", "eOutcome.18"),
        ),
    ),
)
