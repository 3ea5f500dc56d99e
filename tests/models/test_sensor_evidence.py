"""Posture and seat position from the notification's evidence (models.sensor_evidence)."""

from __future__ import annotations

import dataclasses
import math

import pytest

from models.assumptions import Assumption, AssumptionCode
from models.lpm.domain import SEAT_TRACK_RANGE_MM
from models.notification import (
    NEUTRAL_LUMBAR_FLEXION_DEG,
    AirbagState,
    Body,
    Occupant,
    Seat,
    SeatTrackSource,
    summary_notification,
)
from models.sensor_evidence import (
    FOREMOST_SWITCH_POINT_MM,
    UNSENSED_POSTURE_SD_DEG,
    resolve_sensor_evidence,
    seat_track_range_mm,
    uniform_sd,
)
from models.triage import EngineModels, load_engine_models, triage

DRIVER = Occupant(
    seat=Seat.DRIVER,
    body=Body.MALE_50TH,
    belted=True,
    frontal_airbag=AirbagState.DEPLOYED,
    age_years=40,
)


@pytest.fixture(scope="module")
def models() -> EngineModels:
    return load_engine_models()


def test_a_sensed_occupant_is_returned_unchanged() -> None:
    notes: list[Assumption] = []
    assert resolve_sensor_evidence(DRIVER, 0, notes) is DRIVER
    assert notes == []


def test_uniform_sd_is_width_over_root_12() -> None:
    assert uniform_sd(-120.0, 120.0) == pytest.approx(240.0 / math.sqrt(12.0))
    assert uniform_sd(0.0, 25.0) == pytest.approx(7.2168783649)
    assert UNSENSED_POSTURE_SD_DEG == pytest.approx(7.2168783649)


@pytest.mark.parametrize(
    ("source", "low", "high"),
    [
        (SeatTrackSource.NOT_SENSED, *SEAT_TRACK_RANGE_MM),
        (SeatTrackSource.FOREMOST_SWITCH_ON, FOREMOST_SWITCH_POINT_MM, SEAT_TRACK_RANGE_MM[1]),
        (SeatTrackSource.FOREMOST_SWITCH_OFF, SEAT_TRACK_RANGE_MM[0], FOREMOST_SWITCH_POINT_MM),
    ],
)
def test_seat_evidence_becomes_the_centre_and_spread_of_its_range(
    source: SeatTrackSource, low: float, high: float
) -> None:
    notes: list[Assumption] = []
    occ = dataclasses.replace(DRIVER, seat_track_mm=99.0, seat_track_source=source)
    out = resolve_sensor_evidence(occ, 2, notes)
    assert seat_track_range_mm(source) == (low, high)
    assert out.seat_track_source is SeatTrackSource.SENSOR
    assert out.seat_track_mm == pytest.approx(0.5 * (low + high))
    assert out.seat_track_sd_mm == pytest.approx((high - low) / math.sqrt(12.0))
    assert len(notes) == 1
    assert notes[0].message.startswith("occupants[2]: ")
    assert notes[0].occupant == 2
    assert f"{low:g} to {high:g} mm" in notes[0].message
    assert notes[0].code is (
        AssumptionCode.SEAT_POSITION_NOT_SENSED
        if source is SeatTrackSource.NOT_SENSED
        else AssumptionCode.SEAT_TRACK_SWITCH
    )


def test_the_switch_ranges_split_the_track() -> None:
    on = seat_track_range_mm(SeatTrackSource.FOREMOST_SWITCH_ON)
    off = seat_track_range_mm(SeatTrackSource.FOREMOST_SWITCH_OFF)
    assert off[1] == on[0]
    assert (off[0], on[1]) == seat_track_range_mm(SeatTrackSource.NOT_SENSED)
    with pytest.raises(ValueError, match="reading"):
        seat_track_range_mm(SeatTrackSource.SENSOR)


def test_an_unsensed_posture_is_neutral_with_the_range_spread_and_explicit_sds_are_kept() -> None:
    notes: list[Assumption] = []
    occ = dataclasses.replace(DRIVER, posture_lumbar_flexion_deg=20.0, posture_sensed=False)
    out = resolve_sensor_evidence(occ, 0, notes)
    assert out.posture_sensed
    assert out.posture_lumbar_flexion_deg == NEUTRAL_LUMBAR_FLEXION_DEG
    assert out.posture_sd_deg == pytest.approx(UNSENSED_POSTURE_SD_DEG)
    assert "posture not sensed" in notes[0].message
    assert notes[0].code is AssumptionCode.POSTURE_NOT_SENSED
    own = dataclasses.replace(
        occ,
        posture_sd_deg=3.0,
        seat_track_sd_mm=10.0,
        seat_track_source=SeatTrackSource.NOT_SENSED,
    )
    out = resolve_sensor_evidence(own, 0, [])
    assert (out.posture_sd_deg, out.seat_track_sd_mm) == (3.0, 10.0)


def _width(ci: tuple[float, float] | None) -> float:
    assert ci is not None
    return ci[1] - ci[0]


def test_without_readings_the_answer_is_the_spread_mean_and_its_intervals_are_wider(
    models: EngineModels,
) -> None:
    """The field decision does not depend on posture or seat; the occupant model's
    measures stay on the direct run at the nominal posture and mid track, its
    P(ISS >= 15) becomes the mean over the spread its interval propagates, the
    intervals take the whole range of posture and seat position, and the answer
    says so."""
    sensed = triage(summary_notification((DRIVER,), 56.0, 0.0), models)
    blind_occ = dataclasses.replace(
        DRIVER, posture_sensed=False, seat_track_source=SeatTrackSource.NOT_SENSED
    )
    blind = triage(summary_notification((blind_occ,), 56.0, 0.0), models)
    a, b = sensed.occupants[0], blind.occupants[0]
    assert a.method == b.method == "lpm"
    assert a.interval_method == b.interval_method == "pce_bootstrap"
    assert b.triage == a.triage, "the field model does not see posture or seat"
    assert b.measures == a.measures
    assert a.occupant_model is not None
    assert b.occupant_model is not None
    lo, hi = b.occupant_model.probability_ci95
    assert lo <= b.occupant_model.probability <= hi
    assert _width(b.occupant_model.probability_ci95) > _width(a.occupant_model.probability_ci95)
    assert any("mean over the unsensed" in x.message for x in blind.assumptions)
    assert b.iss is not None
    assert a.iss is not None
    assert _width(b.iss.ci95) > _width(a.iss.ci95)
    assert b.measures_ci95 is not None
    assert a.measures_ci95 is not None
    assert _width(b.measures_ci95["hic15"]) > _width(a.measures_ci95["hic15"])
    assert any("posture not sensed" in x.message for x in blind.assumptions)
    assert any("seat position not sensed" in x.message for x in blind.assumptions)
    assert not any("not sensed" in x.message for x in sensed.assumptions)


def test_a_foremost_switch_puts_the_seat_in_the_forward_part_of_the_track(
    models: EngineModels,
) -> None:
    """Switch on: the direct run is at the centre of the forward range, as a reading
    there would be; the intervals take the range's spread (80 mm wide: SD 23 mm,
    about the default sensor's 25.5 mm) instead of the sensor's, and the answer says so."""
    lo, hi = seat_track_range_mm(SeatTrackSource.FOREMOST_SWITCH_ON)
    switch = dataclasses.replace(DRIVER, seat_track_source=SeatTrackSource.FOREMOST_SWITCH_ON)
    reading = dataclasses.replace(DRIVER, seat_track_mm=0.5 * (lo + hi))
    by_switch = triage(summary_notification((switch,), 56.0, 0.0), models)
    by_reading = triage(summary_notification((reading,), 56.0, 0.0), models)
    a, b = by_switch.occupants[0], by_reading.occupants[0]
    assert a.triage.probability == b.triage.probability
    assert a.measures == b.measures
    assert a.measures_ci95 != b.measures_ci95
    note = next(
        x.message for x in by_switch.assumptions if "seat track switch says foremost" in x.message
    )
    assert f"{lo:g} to {hi:g} mm" in note
    assert "SD 23 mm" in note
    assert not any("seat track" in x.message for x in by_reading.assumptions)


def test_simulate_runs_the_same_nominal_occupant_as_triage(models: EngineModels) -> None:
    """``aacn-triage simulate`` shows the run the triage decided on: with a foremost
    switch, the seat at the centre of the forward range, not mid track."""
    from models.triage import simulate_notification

    switch = dataclasses.replace(DRIVER, seat_track_source=SeatTrackSource.FOREMOST_SWITCH_ON)
    notification = summary_notification((switch,), 56.0, 0.0)
    _, sims, notes = simulate_notification(notification, models)
    answer = triage(notification, models).occupants[0]
    assert sims[0].result is not None
    assert sims[0].occupant.seat_track_mm == pytest.approx(80.0)
    assert answer.measures is not None
    assert sims[0].result.measures.hic15 == answer.measures["hic15"]
    assert any("seat track switch says foremost" in n.message for n in notes)
