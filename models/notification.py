"""The engine's inputs: a crash notification as frozen, plain data.

These dataclasses are what `models.triage` consumes. They carry no validation
framework (the HTTP layer validates the wire format with pydantic and converts
into these); they hold SI-adjacent units named in every field.

Axes follow SAE J211 vehicle axes: x forward, y right, z down. The principal
direction of force (PDOF) is in degrees clockwise from straight ahead:
0 frontal, 90 right side, 180 rear, 270 left side
(`crash-data-and-triage.md` section 3).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

__all__ = [
    "NEUTRAL_LUMBAR_FLEXION_DEG",
    "AccelerationPulse",
    "AirbagState",
    "Body",
    "ChildRestraint",
    "CrashNotification",
    "DeltaVPulse",
    "DriveSide",
    "Occupant",
    "Pulse",
    "Seat",
    "SeatTrackSource",
    "Sex",
    "SummaryPulse",
    "DUMMY_STATURE_MASS",
    "nearest_body",
    "pediatric_crash_criterion",
    "summary_notification",
]

#: Neutral lumbar flexion of a seated occupant, deg. Reference paper
#: (occupant-injury-framework-paper.txt, section 2.4): "neutral 5.8 deg".
NEUTRAL_LUMBAR_FLEXION_DEG = 5.8


class Seat(StrEnum):
    """Seat of the occupant (VEDS VehicleSeatLocationCategoryCode 1-9).

    Codes 1-5: driver, front passenger, second row left, middle, right; 6-8:
    third row left, middle, right; 9: front row middle. The occupant models are
    of the driver's and front passenger's seats (:attr:`front_row`); every seat
    gets the field model's decision.
    """

    DRIVER = "driver"
    FRONT_PASSENGER = "front_passenger"
    REAR_LEFT = "rear_left"
    REAR_MIDDLE = "rear_middle"
    REAR_RIGHT = "rear_right"
    THIRD_ROW_LEFT = "third_row_left"
    THIRD_ROW_MIDDLE = "third_row_middle"
    THIRD_ROW_RIGHT = "third_row_right"
    FRONT_MIDDLE = "front_middle"

    @property
    def front_row(self) -> bool:
        """The driver's and the front passenger's seats (the occupant models' seats)."""
        return self in (Seat.DRIVER, Seat.FRONT_PASSENGER)

    @property
    def row(self) -> int:
        """Seat row, 1 (front) to 3."""
        if self in (Seat.DRIVER, Seat.FRONT_PASSENGER, Seat.FRONT_MIDDLE):
            return 1
        if self in (Seat.REAR_LEFT, Seat.REAR_MIDDLE, Seat.REAR_RIGHT):
            return 2
        return 3

    @property
    def middle(self) -> bool:
        """A middle seat (on neither side of the vehicle)."""
        return self in (Seat.FRONT_MIDDLE, Seat.REAR_MIDDLE, Seat.THIRD_ROW_MIDDLE)


class Body(StrEnum):
    """Anthropometric class of the occupant (Hybrid III family)."""

    MALE_50TH = "male_50th"
    FEMALE_5TH = "female_5th"


#: Hybrid III anthropometry used to map stature and mass to the nearer dummy
#: (occupant-lpm-notes.md section 2): 50th male 175 cm / 77.7 kg;
#: 5th female 151 cm / 49.1 kg [S].
DUMMY_STATURE_MASS: dict[Body, tuple[float, float]] = {
    Body.MALE_50TH: (175.0, 77.7),
    Body.FEMALE_5TH: (151.0, 49.1),
}


def nearest_body(stature_cm: float | None, mass_kg: float | None) -> Body | None:
    """The dummy nearer to a stature and mass (relative squared distance).

    Parameters
    ----------
    stature_cm : float or None
        Occupant stature, cm.
    mass_kg : float or None
        Occupant mass, kg.

    Returns
    -------
    Body or None
        None when neither is known.
    """
    if stature_cm is None and mass_kg is None:
        return None

    def distance(b: Body) -> float:
        stature, mass = DUMMY_STATURE_MASS[b]
        d = 0.0
        if stature_cm is not None:
            d += ((stature_cm - stature) / stature) ** 2
        if mass_kg is not None:
            d += ((mass_kg - mass) / mass) ** 2
        return d

    return min(DUMMY_STATURE_MASS, key=distance)


class Sex(StrEnum):
    """Occupant sex as reported by the vehicle or call taker."""

    MALE = "male"
    FEMALE = "female"


class ChildRestraint(StrEnum):
    """How a child is restrained, as the wire says it.

    The field data know only "child seat" (NASS-CDS codes every child
    restraint alike), so the field risk models take the four seat kinds alike;
    the kind is kept for the record and the EMS handover (NEMSIS eInjury.07).
    """

    REAR_FACING_SEAT = "rear_facing_seat"
    FORWARD_FACING_SEAT = "forward_facing_seat"
    BOOSTER = "booster"
    CHILD_SEAT_UNKNOWN_KIND = "child_seat_unknown_kind"
    LAP_SHOULDER_BELT = "lap_shoulder_belt"
    NONE = "none"

    @property
    def child_seat(self) -> bool:
        """A child seat of some kind (booster included)."""
        return self in (
            ChildRestraint.REAR_FACING_SEAT,
            ChildRestraint.FORWARD_FACING_SEAT,
            ChildRestraint.BOOSTER,
            ChildRestraint.CHILD_SEAT_UNKNOWN_KIND,
        )


class AirbagState(StrEnum):
    """State of an airbag at the occupant's seat (frontal, or side and curtain)."""

    DEPLOYED = "deployed"
    NOT_DEPLOYED = "not_deployed"
    ABSENT = "absent"


class SeatTrackSource(StrEnum):
    """What the notification knows of the seat's fore-aft position.

    A seat position sensor gives a reading (``seat_track_mm``). Many cars have
    only a seat track position switch, which tells whether the seat is in the
    forward part of its travel (49 CFR 563 Table II "seat track position switch,
    foremost, status"; a Hall-effect switch the airbag module reads). Without
    either, the position is not sensed.
    """

    SENSOR = "sensor"
    FOREMOST_SWITCH_ON = "foremost_switch_on"
    FOREMOST_SWITCH_OFF = "foremost_switch_off"
    NOT_SENSED = "not_sensed"


class DriveSide(StrEnum):
    """Side of the vehicle the driver sits on (left for left-hand drive)."""

    LEFT = "left"
    RIGHT = "right"


@dataclass(frozen=True)
class AccelerationPulse:
    """Vehicle acceleration histories, SAE J211 axes.

    Attributes
    ----------
    sample_rate_hz : float
        Sampling rate, Hz.
    longitudinal_g : tuple of float, shape (n,)
        x (forward) acceleration, g. A frontal crash decelerates: negative.
    lateral_g : tuple of float, shape (n,)
        y (right) acceleration, g. An impact on the left side pushes the
        vehicle to the right: positive.
    """

    sample_rate_hz: float
    longitudinal_g: tuple[float, ...]
    lateral_g: tuple[float, ...]
    kind: str = field(default="acceleration", init=False)


@dataclass(frozen=True)
class DeltaVPulse:
    """A 49 CFR 563 EDR record: cumulative delta-V at a fixed interval.

    Attributes
    ----------
    interval_ms : float
        Sampling interval, ms (10 ms in Part 563 Table I).
    longitudinal_kmh : tuple of float, shape (n,)
        Cumulative x delta-V, km/h (negative in a frontal crash).
    lateral_kmh : tuple of float, shape (n,)
        Cumulative y delta-V, km/h.
    """

    interval_ms: float
    longitudinal_kmh: tuple[float, ...]
    lateral_kmh: tuple[float, ...]
    kind: str = field(default="delta_v", init=False)


@dataclass(frozen=True)
class SummaryPulse:
    """Summary of the crash: resultant delta-V and its direction.

    Attributes
    ----------
    delta_v_kmh : float
        Magnitude of the velocity change, km/h.
    pdof_deg : float
        Principal direction of force, deg clockwise from straight ahead.
    duration_ms : float or None
        Pulse duration, ms; None lets the engine choose from delta-V.
    delta_v_source : str
        ``measured`` (the vehicle's EDR or telematics unit: what a telematics
        unit sends, the default) or ``reconstructed`` (from crush, as the field
        data's; :mod:`models.field.measurement`).
    delta_v_axes : str
        ``resultant`` (the default) or ``longitudinal`` (49 CFR 563 requires
        only the longitudinal record): a longitudinal value is read as the
        resultant along the PDOF (:func:`models.pulse.process_pulse`).
    """

    delta_v_kmh: float
    pdof_deg: float
    duration_ms: float | None = None
    delta_v_source: str = "measured"
    delta_v_axes: str = "resultant"
    kind: str = field(default="summary", init=False)


Pulse = AccelerationPulse | DeltaVPulse | SummaryPulse


@dataclass(frozen=True)
class Occupant:
    """One occupant (front or second row) and the restraint state around them.

    Attributes
    ----------
    seat : Seat
    body : Body
    belted : bool
    frontal_airbag : AirbagState
    side_airbag : AirbagState or None
        The side (thorax) and curtain airbag on this occupant's side of the car;
        it acts in a near-side crash. None: not reported (the occupant models
        then assume none, the conservative choice).
    age_years : float or None
        Unknown ages are imputed by the models that need them.
    sex : Sex or None
    airbag_fire_time_ms : float or None
        Time from time zero to airbag firing, ms.
    pretensioner_fired : bool or None
    posture_lumbar_flexion_deg : float
        Lumbar flexion, deg; neutral 5.8, forward leaning up to 25.
    seat_track_mm : float
        Seat track position relative to mid track, mm, positive forward.
    posture_sd_deg, seat_track_sd_mm : float or None
        Sensor standard deviations; None for the service defaults.
    posture_sensed : bool
        False when no posture reading was given: the engine then takes the
        neutral posture with the spread of the whole posture range
        (:mod:`models.sensor_evidence`).
    seat_track_source : SeatTrackSource
        Where the seat position comes from; anything but ``SENSOR`` makes the
        engine replace ``seat_track_mm`` and its SD by the range the evidence
        allows (:mod:`models.sensor_evidence`).
    stature_cm, mass_kg : float or None
        Occupant stature (cm) and mass (kg) where known (the field risk model
        may use them; the occupant models use `body`).
    belt_known : bool
        False: belt use unknown (an unmonitored belt); the field risk model
        integrates over belt use by seat, the occupant models take `belted`
        (False, the conservative choice).
    child_restraint : ChildRestraint or None
        How a child is restrained where said (a child seat counts as restrained).
    child_restraint_unsecured : bool or None
        The child seat or belt was not secured, where said (a car cannot sense it).
    """

    seat: Seat
    body: Body
    belted: bool
    frontal_airbag: AirbagState
    side_airbag: AirbagState | None = None
    age_years: float | None = None
    sex: Sex | None = None
    airbag_fire_time_ms: float | None = None
    pretensioner_fired: bool | None = None
    posture_lumbar_flexion_deg: float = NEUTRAL_LUMBAR_FLEXION_DEG
    seat_track_mm: float = 0.0
    posture_sd_deg: float | None = None
    seat_track_sd_mm: float | None = None
    posture_sensed: bool = True
    seat_track_source: SeatTrackSource = SeatTrackSource.SENSOR
    stature_cm: float | None = None
    mass_kg: float | None = None
    belt_known: bool = True
    child_restraint: ChildRestraint | None = None
    child_restraint_unsecured: bool | None = None

    @property
    def child(self) -> bool:
        """A child: age known under 16, or restrained in a child seat."""
        if self.age_years is not None:
            return self.age_years < 16.0
        return self.child_restraint is not None and self.child_restraint.child_seat

    @property
    def pediatric_crash_criterion(self) -> bool:
        """The field triage guideline's pediatric crash criterion: a child of 0-9 years
        unrestrained or in an unsecured child seat (2021 guideline; NEMSIS 2904029).

        A child seat (any kind) stands for a child under 10 where the age is unknown
        (NHTSA's car seat recommendations: boosters to about 9). Unrestrained: the
        restraint said to be none, or a belt sensed unfastened; unsecured: as a person
        said (a car cannot sense it).
        """
        return pediatric_crash_criterion(
            self.age_years,
            self.child_restraint,
            self.belted if self.belt_known else None,
            self.child_restraint_unsecured,
        )


def pediatric_crash_criterion(
    age_years: float | None,
    child_restraint: ChildRestraint | None,
    belted: bool | None,
    unsecured: bool | None,
) -> bool:
    """:attr:`Occupant.pediatric_crash_criterion` from its fields (`belted` None: unknown)."""
    if age_years is not None:
        young = age_years < 10.0
    else:
        young = child_restraint is not None and child_restraint.child_seat
    if not young:
        return False
    unrestrained = child_restraint is ChildRestraint.NONE or (
        child_restraint is None and belted is False
    )
    return unrestrained or bool(unsecured)


@dataclass(frozen=True)
class CrashNotification:
    """A whole notification: the crash and its occupants."""

    event_id: str
    vehicle_model: str
    drive_side: DriveSide
    pulse: Pulse
    multiple_impacts: bool
    rollover: bool
    occupants: tuple[Occupant, ...]
    #: Vehicle model year (VIN 10th character or VEDS); None: not sent.
    model_year: int | None = None
    #: Rollover quarter turns where the vehicle sends them; None: not sent.
    rollover_quarter_turns: int | None = None
    #: Harmful events (impacts) the vehicle counted; None: not sent.
    impact_count: int | None = None


def summary_notification(
    occupants: tuple[Occupant, ...],
    delta_v_kmh: float,
    pdof_deg: float,
    *,
    event_id: str = "engine",
    vehicle_model: str = "compact_sedan",
    drive_side: DriveSide = DriveSide.LEFT,
) -> CrashNotification:
    """A single-impact notification with a summary pulse (the engine's reports and checks).

    Parameters
    ----------
    occupants : tuple of Occupant
    delta_v_kmh : float
        Resultant delta-V, km/h.
    pdof_deg : float
        Principal direction of force, deg clockwise from straight ahead.
    event_id, vehicle_model : str, optional
    drive_side : DriveSide, optional

    Returns
    -------
    CrashNotification
        No rollover, no multiple impacts.
    """
    return CrashNotification(
        event_id=event_id,
        vehicle_model=vehicle_model,
        drive_side=drive_side,
        pulse=SummaryPulse(delta_v_kmh=delta_v_kmh, pdof_deg=pdof_deg),
        multiple_impacts=False,
        rollover=False,
        occupants=occupants,
    )
