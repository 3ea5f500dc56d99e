"""The wire of an outcome: what a registry writes, what the service answers."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from typing import Annotated, Any, Final, Literal, get_args

from pydantic import AfterValidator, BaseModel, ConfigDict, Field, field_validator

from models.notification import Seat
from service.cases.notification import Rfc3339Text
from service.jsonbody import loads_strict
from service.outcomes.iss import ISS_MAX, MAIS_MAX, POSSIBLE_ISS, iss_mais_agree
from service.problems import FieldError

__all__ = [
    "DISPOSITIONS",
    "ISS_NOT_NEEDED",
    "SOURCES",
    "Disposition",
    "OutcomeIn",
    "OutcomeOut",
    "OutcomeRecord",
    "Source",
]

#: Where the occupant went (the receiving hospital's disposition, or the EMS outcome).
Disposition = Literal[
    "admitted_ward",
    "admitted_icu",
    "operating_room",
    "discharged_from_ed",
    "transferred_out",
    "died_in_hospital",
    "not_transported",
    "no_injury",
    "other",
]
DISPOSITIONS: Final[tuple[str, ...]] = get_args(Disposition)
#: Who recorded the outcome.
Source = Literal["trauma_registry", "ems", "hospital", "other"]
SOURCES: Final[tuple[str, ...]] = get_args(Source)
#: EMS outcomes that may come without an ISS: the occupant never reached a hospital to be
#: coded. They count as ISS < 15 (``service.outcomes.quality``); "no injury" is ISS 0.
ISS_NOT_NEEDED: Final[frozenset[str]] = frozenset({"not_transported", "no_injury"})
#: Largest survey weight accepted. [R] National survey weights (NASS-CDS) reach a few
#: thousand; a million is beyond any, and keeps weighted sums exact in a float.
MAX_WEIGHT: Final[float] = 1e6
#: Earliest accepted recording time: no case is older (``cases.notification.MIN_OCCURRED_AT``).
MIN_RECORDED_AT: Final = datetime(1990, 1, 1, tzinfo=UTC)
#: Clock-skew allowance of `recorded_at` (as for a crash time).
MAX_CLOCK_SKEW: Final = timedelta(minutes=10)


def _not_future(value: datetime) -> datetime:
    if not MIN_RECORDED_AT <= value <= datetime.now(UTC) + MAX_CLOCK_SKEW:
        raise ValueError(
            f"must lie between {MIN_RECORDED_AT:%Y-%m-%d} and now (an outcome is recorded "
            "after the fact)"
        )
    return value


class OutcomeIn(BaseModel):
    """An occupant's outcome as the trauma registry, the hospital or EMS recorded it."""

    model_config = ConfigDict(
        extra="forbid",
        allow_inf_nan=False,
        frozen=True,
        json_schema_extra={
            "examples": [
                {
                    "iss": 17,
                    "mais": 3,
                    "died": False,
                    "disposition": "admitted_icu",
                    "source": "trauma_registry",
                    "recorded_at": "2026-12-01T10:00:00Z",
                }
            ]
        },
    )

    iss: int | None = Field(
        default=None,
        ge=0,
        le=ISS_MAX,
        description="Injury Severity Score, 0-75; only values that can occur (sums of three "
        "squares of AIS 0-5, or 75: not 7, 15, 23, ...). Omitted only for an EMS outcome "
        "`not_transported` or `no_injury` (ISS 0).",
        examples=[17],
    )
    mais: int | None = Field(
        default=None,
        ge=0,
        le=MAIS_MAX,
        description="Maximum AIS, 0-6, where known; must agree with `iss`.",
        examples=[3],
    )
    died: bool | None = Field(default=None, description="Died of the crash, where known.")
    disposition: Disposition | None = Field(
        default=None, description="The hospital disposition, or the EMS outcome, where known."
    )
    source: Source = Field(description="Who recorded the outcome.", examples=["trauma_registry"])
    recorded_at: Annotated[Rfc3339Text, AfterValidator(_not_future)] = Field(
        description="When the source recorded it (RFC 3339 with offset)."
    )
    weight: float = Field(
        default=1.0,
        gt=0.0,
        le=MAX_WEIGHT,
        description="Weight of the occupant in the quality figures (a survey weight; 1 "
        "when the outcomes are a census).",
    )

    @field_validator("iss")
    @classmethod
    def _possible_iss(cls, value: int | None) -> int | None:
        if value is not None and value not in POSSIBLE_ISS:
            raise ValueError(
                f"ISS {value} cannot occur: an ISS is a sum of three squares of AIS 1-5 "
                "(or 75), and 0-75 has gaps (7, 15, 23, 28, ...)"
            )
        return value

    @classmethod
    def from_json(cls, raw: bytes | str) -> OutcomeIn:
        """Validate an outcome's JSON strictly (unique keys; numbers not from strings)."""
        loads_strict(raw)
        return cls.model_validate_json(raw, strict=True)

    def problems(self) -> list[FieldError]:
        """What the fields say against each other, each naming its field (empty: none)."""
        out: list[FieldError] = []
        if self.iss is None and self.disposition not in ISS_NOT_NEEDED:
            out.append(
                FieldError(
                    field="iss",
                    reason="an ISS is needed unless the disposition is not_transported or "
                    "no_injury",
                    type="missing",
                )
            )
        if (
            self.iss is not None
            and self.mais is not None
            and not iss_mais_agree(self.iss, self.mais)
        ):
            out.append(
                FieldError(
                    field="mais",
                    reason=f"MAIS {self.mais} cannot come with ISS {self.iss}",
                    type="iss_mais_disagree",
                )
            )
        if self.disposition == "no_injury" and (
            (self.iss or 0) > 0 or (self.mais or 0) > 0 or self.died
        ):
            out.append(
                FieldError(
                    field="disposition",
                    reason="no_injury comes with ISS 0, MAIS 0 and no death",
                    type="disposition_disagrees",
                )
            )
        if self.iss is None and self.died:
            out.append(
                FieldError(
                    field="iss",
                    reason="a death needs its ISS, so that it counts in the figures",
                    type="missing",
                )
            )
        return out

    def content(self) -> dict[str, Any]:
        """The outcome's content in canonical form (its fingerprint's input)."""
        iss = 0 if self.iss is None and self.disposition == "no_injury" else self.iss
        return {
            "iss": iss,
            "mais": self.mais,
            "died": self.died,
            "disposition": self.disposition,
            "source": self.source,
            "recorded_at": self.recorded_at.astimezone(UTC).isoformat(),
            "weight": float(self.weight),
        }


class OutcomeOut(BaseModel):
    """One revision of an occupant's outcome, with who wrote it and when."""

    case_id: str = Field(description="The case.")
    seat: Seat = Field(description="The occupant's seat.")
    revision: int = Field(description="1 for the first outcome, +1 per correction.")
    current: bool = Field(description="The latest revision: the one the figures use.")
    iss: int | None = Field(description="Injury Severity Score.")
    mais: int | None = Field(description="Maximum AIS.")
    died: bool | None = Field(description="Died of the crash.")
    disposition: Disposition | None = Field(description="Hospital disposition or EMS outcome.")
    source: Source = Field(description="Who recorded the outcome.")
    recorded_at: datetime = Field(description="When the source recorded it.")
    weight: float = Field(description="Weight in the quality figures.")
    written_by: str = Field(description="The API key's name, or the import's account and file.")
    written_at: datetime = Field(description="When the service stored this revision.")
    channel: Literal["api", "import"] = Field(description="How it came in.")


class OutcomeRecord(BaseModel):
    """An occupant's current outcome and every revision (the audit trail)."""

    current: OutcomeOut = Field(description="The latest revision.")
    history: list[OutcomeOut] = Field(description="Every revision, first written first.")
