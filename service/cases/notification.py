"""Wire models of the v1 contract (pydantic v2), with descriptions and examples.

Units are in the field names. Axes are SAE J211 vehicle axes (x forward,
y right); PDOF is in degrees clockwise from straight ahead (0 frontal,
90 right side, 180 rear, 270 left side).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Annotated, Any, Final, Literal

from pydantic import (
    AfterValidator,
    AwareDatetime,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    StringConstraints,
    TypeAdapter,
    ValidationError,
    model_validator,
)
from pydantic_core import InitErrorDetails, PydanticCustomError

from models import limits
from models import notification as engine
from models.assumptions import Assumption, AssumptionCode
from service.cases.examples import EXAMPLE_NOTIFICATIONS
from service.jsonbody import loads_strict

__all__ = [
    "EXAMPLE_NOTIFICATIONS",
    "MAX_CLOCK_SKEW",
    "MIN_OCCURRED_AT",
    "AccelerationPulseIn",
    "CrashIn",
    "CrashNotificationIn",
    "DeltaVPulseIn",
    "OccupantIn",
    "ReceivedSource",
    "Rfc3339Text",
    "SourceFormat",
    "SummaryPulseIn",
    "VehicleIn",
]

#: The input limits are the engine's own (one set, ``models/limits.py``).
MAX_DELTA_V_KMH = limits.MAX_DELTA_V_KMH
MAX_ACCEL_G = limits.MAX_ABS_ACCELERATION_G
MIN_SAMPLE_RATE_HZ = limits.MIN_ACCELERATION_SAMPLE_RATE_HZ
MAX_SAMPLE_RATE_HZ = limits.MAX_ACCELERATION_SAMPLE_RATE_HZ
MIN_SERIES_SAMPLES, MAX_SERIES_SAMPLES = limits.MIN_SAMPLES, limits.MAX_SAMPLES
MIN_SERIES_MS, MAX_SERIES_MS = limits.MIN_RECORD_DURATION_MS, limits.MAX_RECORD_DURATION_MS
MIN_EDR_INTERVAL_MS, MAX_EDR_INTERVAL_MS = limits.MIN_EDR_INTERVAL_MS, limits.MAX_EDR_INTERVAL_MS
#: Occupants of one notification: one per seat, and the wire names nine seats
#: (VEDS VehicleSeatLocationCategoryCode 1-9).
MAX_OCCUPANTS: Final[int] = len(engine.Seat)
#: Hybrid III anthropometry used to map stature and mass to the nearer dummy
#: (defined once in the engine).
DUMMY_STATURE_MASS = engine.DUMMY_STATURE_MASS
#: Earliest accepted crash time. [R] No telematics unit or event data recorder in
#: service reports crashes from before 1990; earlier dates are clock or typing
#: errors (a unit whose clock never set reports 1970-01-01, a fuzzer 0001-01-01).
MIN_OCCURRED_AT = datetime(1990, 1, 1, tzinfo=UTC)
#: Clock-skew allowance: a crash may be reported up to this far in the future of
#: the service's clock. [R] Telematics units set their clocks from GNSS (well under
#: a second); 10 minutes covers a call center or service host whose NTP drifted.
MAX_CLOCK_SKEW = timedelta(minutes=10)

#: An RFC 3339 date-time with its offset ("2026-11-23T08:15:30Z"). pydantic alone
#: takes a bare number, or a string of digits, as a Unix time (fuzzing findings:
#: ``occurred_at: 0`` or ``"1"``; ``received_from=0.5`` listed every case).
_RFC3339 = re.compile(r"^[0-9]{4}-[0-9]{2}-[0-9]{2}[Tt ][0-9]{2}:[0-9]{2}")


_LAX_AWARE = TypeAdapter(AwareDatetime)


def _rfc3339_text(value: object) -> datetime:
    """Parse RFC 3339 text here (strict mode would refuse text handed on as a str)."""
    if isinstance(value, datetime):  # already parsed (a model built in Python)
        return value
    if not (isinstance(value, str) and _RFC3339.match(value)):
        raise ValueError(
            "must be an RFC 3339 date-time with a UTC offset, e.g. 2026-11-23T08:15:30Z"
        )
    try:
        return _LAX_AWARE.validate_python(value)
    except ValidationError as exc:
        raise ValueError(exc.errors()[0]["msg"]) from None


def _utc(value: datetime) -> datetime:
    try:
        return value.astimezone(UTC)
    except OverflowError as exc:  # 0001-01-01T00:00+14:00 has no UTC instant
        raise ValueError("the date-time is out of range once converted to UTC") from exc


#: An aware date-time given as RFC 3339 text, converted to UTC.
Rfc3339Text = Annotated[AwareDatetime, BeforeValidator(_rfc3339_text), AfterValidator(_utc)]


def _plausible_crash_time(value: datetime) -> datetime:
    latest = datetime.now(UTC) + MAX_CLOCK_SKEW
    if not MIN_OCCURRED_AT <= value <= latest:
        raise ValueError(
            f"must lie between {MIN_OCCURRED_AT:%Y-%m-%d} and now plus "
            f"{int(MAX_CLOCK_SKEW.total_seconds() // 60)} minutes of clock skew"
        )
    return value


class WireModel(BaseModel):
    """Base of the wire models: unknown fields refused, non-finite numbers refused."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


# --------------------------------------------------------------------------- pulses


def _check_series(values: list[float], name: str, bound: float) -> None:
    for i, v in enumerate(values):
        if not math.isfinite(v):
            raise ValueError(f"{name}[{i}] is not a finite number")
        if abs(v) > bound:
            raise ValueError(f"{name}[{i}] = {v} exceeds the plausible magnitude {bound}")


class AccelerationPulseIn(WireModel):
    """Vehicle acceleration histories from the crash sensor (SAE J211 axes)."""

    kind: Literal["acceleration"] = Field(description="Pulse kind tag.")
    sample_rate_hz: float = Field(
        gt=MIN_SAMPLE_RATE_HZ,
        le=MAX_SAMPLE_RATE_HZ,
        description="Sampling rate of both series, Hz.",
        examples=[10000.0],
    )
    longitudinal_g: list[float] = Field(
        min_length=MIN_SERIES_SAMPLES,
        max_length=MAX_SERIES_SAMPLES,
        description="x (forward) acceleration, g, from time zero. A frontal crash "
        "decelerates: negative values.",
    )
    lateral_g: list[float] = Field(
        min_length=MIN_SERIES_SAMPLES,
        max_length=MAX_SERIES_SAMPLES,
        description="y (right) acceleration, g, same length as `longitudinal_g`.",
    )

    @model_validator(mode="after")
    def _consistent(self) -> AccelerationPulseIn:
        if len(self.longitudinal_g) != len(self.lateral_g):
            raise ValueError("longitudinal_g and lateral_g must have the same length")
        _check_series(self.longitudinal_g, "longitudinal_g", MAX_ACCEL_G)
        _check_series(self.lateral_g, "lateral_g", MAX_ACCEL_G)
        duration_ms = 1000.0 * (len(self.longitudinal_g) - 1) / self.sample_rate_hz
        if not MIN_SERIES_MS <= duration_ms <= MAX_SERIES_MS:
            raise ValueError(
                f"the series spans {duration_ms:.1f} ms; it must span "
                f"{MIN_SERIES_MS:g} to {MAX_SERIES_MS:g} ms"
            )
        return self

    def to_engine(self) -> engine.AccelerationPulse:
        return engine.AccelerationPulse(
            sample_rate_hz=self.sample_rate_hz,
            longitudinal_g=tuple(self.longitudinal_g),
            lateral_g=tuple(self.lateral_g),
        )


class DeltaVPulseIn(WireModel):
    """A 49 CFR 563 EDR record: cumulative delta-V at a fixed interval.

    Decided on its maximum delta-V (the largest resultant over the record). A record
    that is not physical is refused (422 naming the field): more than 500 g implied
    between two samples, or a delta-V that turns back more than 3 times by more than
    the noise (the larger of 2 km/h and 10 % of the maximum).
    """

    kind: Literal["delta_v"] = Field(description="Pulse kind tag.")
    interval_ms: float = Field(
        default=10.0,
        ge=MIN_EDR_INTERVAL_MS,
        le=MAX_EDR_INTERVAL_MS,
        description="Interval between samples, ms (10 ms in 49 CFR 563 Table I).",
    )
    longitudinal_kmh: list[float] = Field(
        min_length=MIN_SERIES_SAMPLES,
        max_length=1000,
        description="Cumulative x delta-V from time zero, km/h (negative in a frontal crash).",
    )
    lateral_kmh: list[float] = Field(
        min_length=MIN_SERIES_SAMPLES,
        max_length=1000,
        description="Cumulative y delta-V from time zero, km/h, same length.",
    )

    @model_validator(mode="after")
    def _consistent(self) -> DeltaVPulseIn:
        if len(self.longitudinal_kmh) != len(self.lateral_kmh):
            raise ValueError("longitudinal_kmh and lateral_kmh must have the same length")
        _check_series(self.longitudinal_kmh, "longitudinal_kmh", MAX_DELTA_V_KMH)
        _check_series(self.lateral_kmh, "lateral_kmh", MAX_DELTA_V_KMH)
        for i, (x, y) in enumerate(zip(self.longitudinal_kmh, self.lateral_kmh, strict=True)):
            if math.hypot(x, y) > MAX_DELTA_V_KMH:
                raise ValueError(
                    f"resultant delta-V at sample {i} is {math.hypot(x, y):.1f} km/h, above "
                    f"{MAX_DELTA_V_KMH:g} km/h"
                )
        duration_ms = self.interval_ms * (len(self.longitudinal_kmh) - 1)
        if not MIN_SERIES_MS <= duration_ms <= MAX_SERIES_MS:
            raise ValueError(
                f"the record spans {duration_ms:.1f} ms; it must span "
                f"{MIN_SERIES_MS:g} to {MAX_SERIES_MS:g} ms"
            )
        return self

    def to_engine(self) -> engine.DeltaVPulse:
        return engine.DeltaVPulse(
            interval_ms=self.interval_ms,
            longitudinal_kmh=tuple(self.longitudinal_kmh),
            lateral_kmh=tuple(self.lateral_kmh),
        )


class SummaryPulseIn(WireModel):
    """Crash summary: the engine builds a haversine pulse a(t) = A sin^2(pi t / T)."""

    kind: Literal["summary"] = Field(description="Pulse kind tag.")
    delta_v_kmh: float = Field(
        gt=0.0, le=MAX_DELTA_V_KMH, description="Resultant delta-V, km/h.", examples=[56.0]
    )
    pdof_deg: float = Field(
        ge=0.0,
        lt=360.0,
        description="Principal direction of force, deg clockwise from straight ahead "
        "(0 frontal, 90 right side, 180 rear, 270 left side).",
        examples=[0.0],
    )
    duration_ms: float | None = Field(
        default=None,
        ge=20.0,
        le=400.0,
        description="Pulse duration T, ms; omitted: chosen by the engine from delta-V.",
    )
    delta_v_source: Literal["measured", "reconstructed"] = Field(
        default="measured",
        description="Where `delta_v_kmh` comes from. `measured` (the default: what a telematics "
        "unit sends): by the vehicle's own sensors, the airbag module's EDR record or the "
        "telematics unit's accelerometer. `reconstructed`: from the vehicle's crush after the "
        "crash (WinSMASH), as the field data's. The field risk models learned reconstructed "
        "delta-V, which reads about a fifth lower than measured: a measured value is read "
        "through the delta-V measurement model (`delta_v_measured`). Acceleration and EDR "
        "delta-V pulses are measured by nature.",
        examples=["measured"],
    )
    delta_v_axes: Literal["resultant", "longitudinal"] = Field(
        default="resultant",
        description="`resultant` (the default): the magnitude of the velocity change. "
        "`longitudinal`: its component along the vehicle's long axis only (49 CFR 563 requires "
        "only the longitudinal record); read as the resultant along `pdof_deg` "
        "(|longitudinal| / |cos PDOF|), refused (422) for a PDOF more than 60 deg from the long "
        "axis, where the longitudinal record does not carry the crash.",
    )

    def to_engine(self) -> engine.SummaryPulse:
        return engine.SummaryPulse(
            delta_v_kmh=self.delta_v_kmh,
            pdof_deg=self.pdof_deg,
            duration_ms=self.duration_ms,
            delta_v_source=self.delta_v_source,
            delta_v_axes=self.delta_v_axes,
        )


PulseIn = Annotated[
    AccelerationPulseIn | DeltaVPulseIn | SummaryPulseIn,
    Field(discriminator="kind", description="The crash pulse, told apart by `kind`."),
]


# ------------------------------------------------------------------- notification


#: VIN 10th character -> model year in the 1980-2009 cycle (49 CFR 565.15; I, O, Q,
#: U, Z and 0 are not used); the 2010-2039 cycle adds 30 years.
_VIN_YEAR_CODES: Final[str] = "ABCDEFGHJKLMNPRSTVWXY123456789"


def vin_model_year(vin: str) -> int | None:
    """Model year of a 17-character VIN (49 CFR 565.15), None when its code is not a year.

    The 10th character cycles every 30 years; the 7th tells the cycles apart for
    passenger cars, multipurpose vehicles and light trucks: a letter there means
    model year 2010 or later, a digit 1980-2009.
    """
    k = _VIN_YEAR_CODES.find(vin[9])
    if k < 0:
        return None
    return 1980 + k + (30 if vin[6].isalpha() else 0)


class VehicleIn(WireModel):
    """The vehicle that crashed."""

    model: str = Field(
        default="compact_sedan",
        min_length=1,
        max_length=64,
        description="Occupant-model parameter set (vehicle class). Default `compact_sedan`: "
        "a compact sedan of the 2010 Toyota Yaris class.",
    )
    vin: Annotated[str, StringConstraints(pattern=r"^[A-HJ-NPR-Z0-9]{17}$")] | None = Field(
        default=None, description="Vehicle identification number (17 characters, no I, O, Q)."
    )
    drive_side: engine.DriveSide = Field(
        default=engine.DriveSide.LEFT,
        description="Side the driver sits on: `left` for left-hand-drive vehicles.",
    )
    model_year: int | None = Field(
        default=None,
        ge=1950,
        le=2100,
        description="Vehicle model year (the field risk models use it: newer vehicles protect "
        "better). Omitted: read from the VIN's 10th character where a VIN is sent, else the "
        "field risk models' median (reported as an assumption).",
        examples=[2019],
    )

    def engine_model_year(self) -> int | None:
        """`model_year`, else the VIN's (None without either)."""
        if self.model_year is not None:
            return self.model_year
        return None if self.vin is None else vin_model_year(self.vin)


class CrashIn(WireModel):
    """What the vehicle measured of the crash."""

    pulse: PulseIn
    multiple_impacts: bool = Field(
        default=False,
        description="More than one impact event. Implied by an `impact_count` of 2 or more.",
    )
    impact_count: int | None = Field(
        default=None,
        ge=1,
        le=50,
        description="Impact (harmful) events the vehicle counted, where it counts them (the "
        "field risk models use it, up to 6: their data's range). Omitted: one for a single "
        "impact; for multiple impacts their data's median (reported as "
        "`impact_count_imputed`).",
        examples=[2],
    )
    rollover: bool = Field(
        default=False,
        description="The vehicle rolled over. Implied by `rollover_quarter_turns` above 0 when "
        "left out; `false` with quarter turns above 0 is refused.",
    )
    rollover_quarter_turns: int | None = Field(
        default=None,
        ge=0,
        le=40,
        description="Quarter turns of the rollover where the vehicle senses them (used by the "
        "field risk models). Above 0 they are a rollover (`rollover` true, or left out). "
        "Omitted with `rollover`: their median (reported).",
        examples=[2],
    )

    @model_validator(mode="before")
    @classmethod
    def _quarter_turns_imply_rollover(cls, data: Any) -> Any:
        """Quarter turns above 0 with `rollover` left out say the vehicle rolled over
        (a quarter turn is a rollover, as a VEDS document's turns are)."""
        if isinstance(data, dict) and "rollover" not in data:
            turns = data.get("rollover_quarter_turns")
            if isinstance(turns, int) and not isinstance(turns, bool) and turns > 0:
                return {**data, "rollover": True}
        return data

    @model_validator(mode="after")
    def _rollover_agrees(self) -> CrashIn:
        """Quarter turns above 0 with an explicit `rollover` false: refused, naming them."""
        turns = self.rollover_quarter_turns
        if turns and not self.rollover:
            raise ValidationError.from_exception_data(
                type(self).__name__,
                [
                    InitErrorDetails(
                        type=PydanticCustomError(
                            "value_error",
                            "{turns} quarter turns contradict rollover false (a quarter turn "
                            "is a rollover): send rollover true, or leave it out",
                            {"turns": turns},
                        ),
                        loc=("rollover_quarter_turns",),
                        input=turns,
                    )
                ],
            )
        return self

    @model_validator(mode="after")
    def _impacts_agree(self) -> CrashIn:
        if self.impact_count is None:
            return self
        if self.impact_count >= 2 and "multiple_impacts" in self.model_fields_set:
            if not self.multiple_impacts:
                raise ValueError(
                    f"impact_count {self.impact_count} contradicts multiple_impacts false"
                )
        if self.impact_count == 1 and self.multiple_impacts:
            raise ValueError("impact_count 1 contradicts multiple_impacts true")
        return self

    @property
    def multiple(self) -> bool:
        """Multiple impacts: said, or implied by an impact count of 2 or more."""
        return self.multiple_impacts or (self.impact_count or 0) >= 2


class OccupantIn(WireModel):
    """One occupant (front or second row) and the restraints around them."""

    seat: engine.Seat = Field(description="Seat of the occupant.")
    body: engine.Body | None = Field(
        default=None,
        description="Anthropometric class. Omitted: the nearer of the two to `stature_cm` "
        "and `mass_kg`, or `male_50th` when neither is known (reported as an assumption).",
    )
    stature_cm: float | None = Field(
        default=None,
        ge=limits.MIN_STATURE_CM,
        le=limits.MAX_STATURE_CM,
        description="Occupant stature, cm.",
    )
    mass_kg: float | None = Field(
        default=None, ge=limits.MIN_MASS_KG, le=limits.MAX_MASS_KG, description="Occupant mass, kg."
    )
    age_years: float | None = Field(
        default=None, ge=0.0, le=limits.MAX_AGE_YEARS, description="Age, years."
    )
    sex: engine.Sex | None = Field(default=None, description="Sex of the occupant.")
    belted: bool | None = Field(
        default=None,
        description="Seat belt fastened, as the belt buckle switch senses it. Omitted or null: "
        "unknown (many rear belts are not monitored): the field risk model integrates over belt "
        "use at this seat (`inputs_integrated`), the occupant models take unbelted "
        "(`belt_unknown`).",
    )
    child_restraint: engine.ChildRestraint | None = Field(
        default=None,
        description="How a child is restrained, where known: a rear-facing, forward-facing or "
        "booster seat, a child seat of unknown kind, the lap-shoulder belt, or none. The field "
        "data know only 'child seat', so the four seat kinds are decided alike; the kind is "
        "kept for the record and the EMS handover (NEMSIS eInjury.07). Given, it decides the "
        "restraint over `belted` (a child seat counts as restrained); `lap_shoulder_belt` with "
        "`belted: false`, or `none` with `belted: true`, is refused.",
    )
    child_restraint_unsecured: bool | None = Field(
        default=None,
        description="The child seat or belt was not secured, where a person said so (a car "
        "cannot sense it). With an age of 0-9 it is the field triage guideline's pediatric "
        "criterion (unrestrained or in an unsecured child seat).",
    )
    frontal_airbag: engine.AirbagState = Field(
        description="Frontal airbag in front of this occupant."
    )
    side_airbag: engine.AirbagState | None = Field(
        default=None,
        description="Side (thorax) and curtain airbags on this occupant's side of the car "
        "(VEDS AirbagCategoryCode SIDE / CURTAIN). They act in a near-side crash. Omitted: "
        "none assumed (the conservative choice; reported as an assumption).",
    )
    airbag_fire_time_ms: float | None = Field(
        default=None, ge=0.0, le=300.0, description="Time from time zero to airbag firing, ms."
    )
    pretensioner_fired: bool | None = Field(
        default=None, description="Belt pretensioner fired (EDR Table II)."
    )
    posture_lumbar_flexion_deg: float | None = Field(
        default=None,
        ge=-20.0,
        le=60.0,
        description="Lumbar flexion from a posture sensor, deg: neutral 5.8, forward leaning up "
        "to 25. Values outside the occupant models' range are clamped (reported as an "
        "assumption). Omitted: not sensed; the neutral posture is used, with the spread of the "
        "whole 0-25 deg range in the intervals (reported).",
    )
    seat_track_mm: float | None = Field(
        default=None,
        ge=-300.0,
        le=300.0,
        description="Seat track position from a seat position sensor, relative to mid track, "
        "mm, positive forward. Omitted: see `seat_track_foremost`; with neither, the seat may be "
        "anywhere on its track (mid track used, the whole track's spread in the intervals; "
        "reported).",
    )
    seat_track_foremost: bool | None = Field(
        default=None,
        description="Seat track position switch, foremost (49 CFR 563 Table II): true when the "
        "seat is in the forward part of its travel. Used when `seat_track_mm` is omitted: the "
        "seat is then anywhere in that part of the track (reported).",
    )
    posture_sd_deg: float | None = Field(
        default=None, gt=0.0, le=30.0, description="Posture sensor standard deviation, deg."
    )
    seat_track_sd_mm: float | None = Field(
        default=None, gt=0.0, le=200.0, description="Seat position sensor standard deviation, mm."
    )

    def resolved_body(self, index: int = 0) -> tuple[engine.Body, Assumption | None]:
        """The dummy class to use and, when it was not given, how it was chosen."""
        if self.body is not None:
            return self.body, None
        body = engine.nearest_body(self.stature_cm, self.mass_kg)
        if body is None:
            return engine.Body.MALE_50TH, Assumption(
                AssumptionCode.BODY_UNKNOWN,
                f"occupants[{index}]: body unknown: Hybrid III 50th male assumed",
                index,
            )
        return body, Assumption(
            AssumptionCode.BODY_FROM_STATURE_MASS,
            f"occupants[{index}]: body mapped from stature/mass to the nearer dummy: {body.value}",
            index,
        )

    def _seat_track_source(self) -> engine.SeatTrackSource:
        if self.seat_track_mm is not None:
            return engine.SeatTrackSource.SENSOR
        if self.seat_track_foremost is None:
            return engine.SeatTrackSource.NOT_SENSED
        if self.seat_track_foremost:
            return engine.SeatTrackSource.FOREMOST_SWITCH_ON
        return engine.SeatTrackSource.FOREMOST_SWITCH_OFF

    @model_validator(mode="after")
    def _restraint_agrees(self) -> OccupantIn:
        cr = self.child_restraint
        if cr is engine.ChildRestraint.LAP_SHOULDER_BELT and self.belted is False:
            raise ValueError("`child_restraint` lap_shoulder_belt contradicts `belted: false`")
        if cr is engine.ChildRestraint.NONE and self.belted is True:
            raise ValueError("`child_restraint` none contradicts `belted: true`")
        return self

    def resolved_belted(self) -> bool:
        """The belt state the occupant models take (unknown: unbelted, the conservative)."""
        if self.child_restraint is not None and self.child_restraint is not (
            engine.ChildRestraint.NONE
        ):
            return True
        return bool(self.belted)

    def to_engine(self, index: int = 0) -> tuple[engine.Occupant, Assumption | None]:
        body, note = self.resolved_body(index)
        return (
            engine.Occupant(
                seat=self.seat,
                body=body,
                belted=self.resolved_belted(),
                belt_known=self.belted is not None or self.child_restraint is not None,
                child_restraint=self.child_restraint,
                child_restraint_unsecured=self.child_restraint_unsecured,
                frontal_airbag=self.frontal_airbag,
                side_airbag=self.side_airbag,
                age_years=self.age_years,
                sex=self.sex,
                airbag_fire_time_ms=self.airbag_fire_time_ms,
                pretensioner_fired=self.pretensioner_fired,
                posture_lumbar_flexion_deg=(
                    engine.NEUTRAL_LUMBAR_FLEXION_DEG
                    if self.posture_lumbar_flexion_deg is None
                    else self.posture_lumbar_flexion_deg
                ),
                seat_track_mm=0.0 if self.seat_track_mm is None else self.seat_track_mm,
                posture_sd_deg=self.posture_sd_deg,
                seat_track_sd_mm=self.seat_track_sd_mm,
                posture_sensed=self.posture_lumbar_flexion_deg is not None,
                seat_track_source=self._seat_track_source(),
                stature_cm=self.stature_cm,
                mass_kg=self.mass_kg,
            ),
            note,
        )


class CrashNotificationIn(WireModel):
    """A crash notification as the call center forwards it."""

    event_id: str = Field(
        min_length=1,
        max_length=128,
        pattern=r"^[\x21-\x7e]+$",
        description="The sender's unique id of the crash event (printable ASCII, no spaces). "
        "Re-sending the same event_id with the same body returns the original case.",
    )
    occurred_at: Annotated[Rfc3339Text, AfterValidator(_plausible_crash_time)] = Field(
        description="Time of the crash, RFC 3339 with offset; from 1990 to the service's "
        "clock plus 10 minutes of clock-skew allowance."
    )
    vehicle: VehicleIn = Field(default_factory=VehicleIn, description="The vehicle.")
    crash: CrashIn = Field(description="The crash measurements.")
    occupants: list[OccupantIn] = Field(
        min_length=1,
        max_length=MAX_OCCUPANTS,
        description="Occupants, one per seat (up to nine: every seat the wire names). Every "
        "occupant gets the field risk model's decision; the front outboard seats' adults also "
        "the occupant models' explanation.",
    )

    model_config = ConfigDict(
        json_schema_extra={"examples": [EXAMPLE_NOTIFICATIONS["summary"]["value"]]}
    )

    @classmethod
    def from_json(cls, raw: bytes | str) -> tuple[CrashNotificationIn, Any]:
        """Validate a notification's JSON text strictly; also return the parsed document.

        Duplicate keys are refused before pydantic (`service.jsonbody.MalformedJson`);
        then pydantic's strict JSON mode: a number is not taken from a string
        (``"56"``), a boolean not from a number (``1``) or a word (``"yes"``).

        Raises
        ------
        service.jsonbody.MalformedJson
            Not one JSON document with unique keys.
        pydantic.ValidationError
            A field refused.
        """
        document = loads_strict(raw)
        return cls.model_validate_json(raw, strict=True), document

    @model_validator(mode="after")
    def _unique_seats(self) -> CrashNotificationIn:
        seen: set[engine.Seat] = set()
        for o in self.occupants:
            if o.seat in seen:
                raise ValueError(
                    f"seat {o.seat.value!r} is named twice in `occupants`: each seat may "
                    "appear once"
                )
            seen.add(o.seat)
        return self

    def to_engine(self) -> tuple[engine.CrashNotification, list[Assumption]]:
        """Convert to the engine's frozen input and the assumptions made on the way."""
        occupants: list[engine.Occupant] = []
        notes: list[Assumption] = []
        for i, occ in enumerate(self.occupants):
            converted, note = occ.to_engine(i)
            occupants.append(converted)
            if note is not None:
                notes.append(note)
        return (
            engine.CrashNotification(
                event_id=self.event_id,
                vehicle_model=self.vehicle.model,
                drive_side=self.vehicle.drive_side,
                pulse=self.crash.pulse.to_engine(),
                multiple_impacts=self.crash.multiple,
                rollover=self.crash.rollover,
                occupants=tuple(occupants),
                model_year=self.vehicle.engine_model_year(),
                rollover_quarter_turns=self.crash.rollover_quarter_turns,
                impact_count=self.crash.impact_count,
            ),
            notes,
        )


#: How a notification came in.
SourceFormat = Literal["json", "veds"]


@dataclass(frozen=True)
class ReceivedSource:
    """A notification that came in as another format than this contract's JSON.

    Attributes
    ----------
    format : {"veds"}
    document : str
        The document exactly as received (kept with the case for audit).
    mapping : dict
        Which of its elements became which fields, what was assumed, what was not
        used (JSON-serialisable; stored with the case).
    assumptions : tuple of Assumption
        What the mapping assumed; added to the answer's assumptions.
    occurred_at_assumed : bool
        The crash time is not the document's own (it had none): idempotency then
        fingerprints the notification without it, so that a re-sent document replays.
    """

    format: SourceFormat
    document: str
    mapping: dict[str, Any]
    assumptions: tuple[Assumption, ...] = ()
    occurred_at_assumed: bool = False

    def record(self) -> dict[str, Any]:
        """The JSON form kept with the case (and in the spool)."""
        return {"format": self.format, "document": self.document, "mapping": self.mapping}
