"""The orchestrator: which engine answers, intervals, assumptions, determinism."""

from __future__ import annotations

import dataclasses

import pytest

from models.field.features import FieldMode
from models.impact_mode import ImpactMode
from models.notification import (
    AirbagState,
    Body,
    CrashNotification,
    DriveSide,
    Occupant,
    Seat,
    SummaryPulse,
)
from models.triage import (
    LPM_THRESHOLDS,
    EngineModels,
    IntervalMethod,
    Method,
    UnknownVehicleModel,
    load_engine_models,
    simulate_notification,
    triage,
)


@pytest.fixture(scope="module")
def models() -> EngineModels:
    return load_engine_models()


def _notification(
    delta_v: float = 56.0,
    pdof: float = 0.0,
    *,
    occupants: tuple[Occupant, ...] | None = None,
    vehicle_model: str = "compact_sedan",
    rollover: bool = False,
) -> CrashNotification:
    occupant = Occupant(
        seat=Seat.DRIVER,
        body=Body.MALE_50TH,
        belted=True,
        frontal_airbag=AirbagState.DEPLOYED,
        age_years=40,
    )
    return CrashNotification(
        event_id="e1",
        vehicle_model=vehicle_model,
        drive_side=DriveSide.LEFT,
        pulse=SummaryPulse(delta_v_kmh=delta_v, pdof_deg=pdof),
        multiple_impacts=False,
        rollover=rollover,
        occupants=occupants or (occupant,),
    )


def test_in_coverage_occupants_are_answered_by_their_occupant_model(
    models: EngineModels,
) -> None:
    result = triage(_notification(56.0, 0.0), models)
    occ = result.occupants[0]
    assert occ.method is Method.LPM
    assert occ.impact.mode is ImpactMode.FRONTAL
    assert occ.iss is not None
    assert occ.region_ais is not None
    assert set(occ.region_ais) == {
        "head_neck",
        "face",
        "chest",
        "abdomen",
        "extremities",
        "external",
    }
    assert occ.measures is not None
    assert {"hic15", "nij", "chest_deflection_mm"} <= set(occ.measures)
    lo, hi = occ.triage.probability_ci95
    assert lo <= occ.triage.probability <= hi
    assert models.field is not None
    assert occ.triage.threshold == models.field.threshold()
    assert occ.triage.outcome == "ISS15+"
    assert occ.region_risk is not None
    assert result.vehicle is not None
    assert result.vehicle.probability >= occ.triage.probability * 0.5
    assert occ.triage.operating_point == models.field.default_operating_point
    assert occ.occupant_model is not None, "the occupant model's own decision is kept"
    assert occ.occupant_model.threshold == LPM_THRESHOLDS[ImpactMode.FRONTAL]
    assert occ.occupant_model.outcome == "ISS15+"
    m_lo, m_hi = occ.occupant_model.probability_ci95
    assert m_lo <= occ.occupant_model.probability <= m_hi
    assert occ.baseline.threshold == models.baseline.threshold, "baseline kept as second opinion"
    assert "lpm_code" in result.models
    assert "lpm_parameters:compact_sedan" in result.models


def test_measure_intervals_contain_the_point_estimate(models: EngineModels) -> None:
    occ = triage(_notification(45.0, 270.0), models).occupants[0]
    assert occ.method is Method.LPM
    assert occ.impact.mode is ImpactMode.NEAR_SIDE
    assert occ.measures is not None
    assert occ.measures_ci95 is not None
    for key, value in occ.measures.items():
        lo, hi = occ.measures_ci95[key]
        assert lo <= value <= hi or occ.point_outside_interval, key
    widths = [hi - lo for lo, hi in occ.measures_ci95.values()]
    assert max(widths) > 0.0, "sensor uncertainty moves at least one measure"


def test_out_of_coverage_occupants_get_the_field_model_and_a_note(models: EngineModels) -> None:
    result = triage(_notification(40.0, 50.0), models)
    occ = result.occupants[0]
    assert occ.method is Method.FIELD
    assert not occ.impact.in_lpm_coverage
    assert occ.triage.outcome == "ISS15+"
    assert occ.occupant_model is None
    assert occ.iss is None
    assert occ.interval_method is None
    assert any("outside every occupant model" in a.message for a in result.assumptions)
    assert set(result.models) == {
        "baseline",
        "field_model",
        "delta_v_measurement",
        "triage_code",
    }


def test_severity_rises_with_delta_v(models: EngineModels) -> None:
    probabilities = [
        triage(_notification(dv, 0.0), models).occupants[0].triage.probability
        for dv in (15.0, 35.0, 56.0, 80.0)
    ]
    assert probabilities == sorted(probabilities)
    assert probabilities[-1] > probabilities[0]


def test_case_triage_is_the_worst_occupant(models: EngineModels) -> None:
    driver = Occupant(
        seat=Seat.DRIVER, body=Body.MALE_50TH, belted=True, frontal_airbag=AirbagState.DEPLOYED
    )
    passenger = Occupant(
        seat=Seat.FRONT_PASSENGER,
        body=Body.FEMALE_5TH,
        belted=False,
        frontal_airbag=AirbagState.NOT_DEPLOYED,
    )
    result = triage(_notification(50.0, 270.0, occupants=(driver, passenger)), models)
    modes = [o.impact.mode for o in result.occupants]
    assert modes == [ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE]
    worst = max(result.occupants, key=lambda o: (o.triage.iss15_plus, o.triage.probability))
    assert result.triage == worst.triage


def test_out_of_domain_sensor_values_are_clamped_and_reported(models: EngineModels) -> None:
    occupant = Occupant(
        seat=Seat.DRIVER,
        body=Body.MALE_50TH,
        belted=True,
        frontal_airbag=AirbagState.DEPLOYED,
        posture_lumbar_flexion_deg=40.0,
        seat_track_mm=-250.0,
    )
    result = triage(_notification(occupants=(occupant,), rollover=True), models)
    text = " ".join(a.message for a in result.assumptions)
    assert "clamped to 25 deg" in text
    assert "clamped to -120 mm" in text
    assert "rollover" in text


def test_rollover_and_multiple_impacts_change_the_probability(models: EngineModels) -> None:
    """They are in the field data: each raises the decided probability (not only a note)."""
    plain = triage(_notification(30.0, 0.0), models).occupants[0]
    rolled = triage(_notification(30.0, 0.0, rollover=True), models).occupants[0]
    multi = triage(
        dataclasses.replace(_notification(30.0, 0.0), multiple_impacts=True), models
    ).occupants[0]
    assert rolled.field_mode is FieldMode.ROLLOVER
    assert rolled.impact.mode is ImpactMode.FRONTAL, "the occupant model still sees the pulse"
    assert rolled.triage.probability > plain.triage.probability
    assert multi.triage.probability > plain.triage.probability


def test_unknown_vehicle_model(models: EngineModels) -> None:
    with pytest.raises(UnknownVehicleModel):
        triage(_notification(vehicle_model="bus"), models)


def test_bit_for_bit_determinism(models: EngineModels) -> None:
    a = triage(_notification(48.0, 10.0), models)
    b = triage(_notification(48.0, 10.0), models)
    assert a == b  # timings are excluded from the comparison
    assert dataclasses.replace(a, timings_ms={}) == dataclasses.replace(b, timings_ms={})


def test_simulate_notification_keeps_histories(models: EngineModels) -> None:
    pulse, sims, _ = simulate_notification(_notification(56.0, 0.0), models)
    assert pulse.delta_v_kmh == pytest.approx(56.0)
    result = sims[0].result
    assert result is not None
    assert "head_accel_g" in result.histories


def test_intervals_come_from_the_surrogates_when_shipped(models: EngineModels) -> None:
    assert models.surrogates is not None, "the shipped surrogates load and verify"
    result = triage(_notification(40.0, 0.0), models)
    occ = result.occupants[0]
    assert occ.interval_method is IntervalMethod.PCE_BOOTSTRAP
    assert occ.occupant_model is not None
    lo, hi = occ.occupant_model.probability_ci95
    assert lo < hi, "non-degenerate"
    assert lo <= occ.occupant_model.probability <= hi or occ.point_outside_interval
    assert occ.iss is not None
    assert occ.iss.ci95 is not None
    assert occ.iss.ci95[0] < occ.iss.ci95[1]
    assert occ.measures_ci95 is not None
    assert occ.measures is not None
    for key, (m_lo, m_hi) in occ.measures_ci95.items():
        assert m_lo < m_hi, key
    assert "surrogates" in result.models


def test_flagged_when_the_direct_estimate_is_outside_the_surrogate_interval(
    models: EngineModels,
) -> None:
    for dv, pdof in ((40.0, 0.0), (30.0, 270.0), (45.0, 180.0), (25.0, 90.0)):
        result = triage(_notification(dv, pdof), models)
        occ = result.occupants[0]
        assert occ.occupant_model is not None
        lo, hi = occ.occupant_model.probability_ci95
        inside = lo - 2e-3 <= occ.occupant_model.probability <= hi + 2e-3
        assert occ.iss is not None
        assert occ.iss.ci95 is not None
        iss_inside = occ.iss.ci95[0] - 0.5 <= occ.iss.estimate <= occ.iss.ci95[1] + 0.5
        assert occ.point_outside_interval == (not (inside and iss_inside))
        if occ.point_outside_interval:
            assert any(
                "outside the surrogate's 95% interval" in a.message for a in result.assumptions
            )


def test_without_surrogates_the_interval_comes_from_direct_runs() -> None:
    bare = load_engine_models(use_surrogates=False)
    occ = triage(_notification(40.0, 0.0), bare).occupants[0]
    assert occ.interval_method is IntervalMethod.LPM_SENSOR_BOX
    assert occ.occupant_model is not None
    lo, hi = occ.occupant_model.probability_ci95
    assert lo <= occ.occupant_model.probability <= hi


@pytest.mark.parametrize("pdof", [90.0, 270.0])
def test_a_minor_side_crash_is_not_sent_to_a_trauma_center(
    models: EngineModels, pdof: float
) -> None:
    result = triage(_notification(8.0, pdof), models)
    occ = result.occupants[0]
    assert occ.method is Method.LPM
    assert occ.impact.mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE)
    assert occ.iss.estimate < 15
    assert occ.triage.iss15_plus is False
    assert occ.occupant_model is not None
    assert occ.occupant_model.iss15_plus is False


@pytest.mark.parametrize("seat", [Seat.REAR_LEFT, Seat.REAR_MIDDLE, Seat.REAR_RIGHT])
def test_second_row_occupants_are_answered_by_the_field_model(
    models: EngineModels, seat: Seat
) -> None:
    """A family car: the front row keeps its occupant models, the second row gets the
    same field model without an occupant-model explanation, with the reason, and nothing
    is refused."""
    driver = Occupant(
        seat=Seat.DRIVER, body=Body.MALE_50TH, belted=True, frontal_airbag=AirbagState.DEPLOYED
    )
    child = Occupant(
        seat=seat, body=Body.FEMALE_5TH, belted=True, frontal_airbag=AirbagState.ABSENT
    )
    result = triage(_notification(56.0, 0.0, occupants=(driver, child)), models)
    front, rear = result.occupants
    assert front.method is Method.LPM
    assert rear.method is Method.FIELD
    assert rear.impact.mode is ImpactMode.FRONTAL
    assert not rear.impact.in_lpm_coverage
    assert rear.triage.outcome == front.triage.outcome == "ISS15+"
    assert rear.region_risk is not None
    assert rear.occupant_model is None
    assert any(f"{seat.value} seat" in a.message for a in result.assumptions)


@pytest.mark.parametrize(
    ("seat", "pdof", "mode"),
    [
        (Seat.REAR_LEFT, 270.0, ImpactMode.NEAR_SIDE),
        (Seat.REAR_LEFT, 90.0, ImpactMode.FAR_SIDE),
        (Seat.REAR_RIGHT, 90.0, ImpactMode.NEAR_SIDE),
        (Seat.REAR_MIDDLE, 90.0, ImpactMode.FAR_SIDE),
        (Seat.REAR_MIDDLE, 270.0, ImpactMode.FAR_SIDE),
    ],
)
def test_second_row_impact_modes(seat: Seat, pdof: float, mode: ImpactMode) -> None:
    from models.impact_mode import classify_impact

    impact = classify_impact(pdof, seat, DriveSide.LEFT)
    assert impact.mode is mode
    assert not impact.in_lpm_coverage


def test_every_case_records_the_code_that_turned_it_into_an_answer(models: EngineModels) -> None:
    """The orchestration's own checksum (over its sources, as stored) and the
    surrogate evaluation's, beside the models they call; a baseline-only answer
    records the orchestration too."""
    from pathlib import Path

    import models as engine_package
    from models.codehash import source_tree_sha256
    from models.surrogate.evaluate import EVALUATION_VERSION, evaluation_sha256
    from models.triage import TRIAGE_SOURCES, triage_code_sha256

    root = Path(engine_package.__file__).resolve().parent
    expected = source_tree_sha256([root / rel for rel in TRIAGE_SOURCES])
    assert triage_code_sha256() == expected
    lpm = triage(_notification(), models)
    assert lpm.models["triage_code"].sha256 == expected
    assert lpm.models["surrogate_evaluation"].version == EVALUATION_VERSION
    assert lpm.models["surrogate_evaluation"].sha256 == evaluation_sha256()
    rear_seat = dataclasses.replace(_notification().occupants[0], seat=Seat.REAR_LEFT)
    baseline_only = triage(_notification(occupants=(rear_seat,)), models)
    assert set(baseline_only.models) == {
        "baseline",
        "field_model",
        "delta_v_measurement",
        "triage_code",
    }


def test_the_triage_code_checksum_covers_the_whole_package() -> None:
    """Every module of models/triage/ that decides an answer is in TRIAGE_SOURCES: a
    module added to the package cannot escape the checksum cases record."""
    from pathlib import Path

    import models as engine_package
    from models.triage import TRIAGE_SOURCES

    root = Path(engine_package.__file__).resolve().parent
    modules = {f"triage/{p.name}" for p in (root / "triage").glob("*.py")}
    off_the_answer = {"triage/__init__.py", "triage/simulation.py"}
    assert modules - off_the_answer == {s for s in TRIAGE_SOURCES if s.startswith("triage/")}
    assert len(set(TRIAGE_SOURCES)) == len(TRIAGE_SOURCES)
    for rel in TRIAGE_SOURCES:
        assert (root / rel).is_file(), rel


def test_the_package_has_one_face() -> None:
    """Every public name of models.triage is importable from the package itself."""
    import models.triage as face

    missing = [name for name in face.__all__ if not hasattr(face, name)]
    assert not missing
    assert face.triage.__module__ == "models.triage.run"
    assert face.simulate_notification.__module__ == "models.triage.simulation"


def test_a_model_year_beyond_the_field_data_is_said(models: EngineModels) -> None:
    """A 2024 vehicle: the field risk models take 2015, their newest model year, and say so."""
    note = dataclasses.replace(_notification(40.0, 0.0), model_year=2024)
    result = triage(note, models)
    codes = [a.code.value for a in result.assumptions]
    assert models.field is not None
    if "model_year" in models.field.used_inputs:  # type: ignore[union-attr]
        assert "model_year_beyond_data" in codes
        same = triage(dataclasses.replace(note, model_year=2015), models)
        assert same.triage.probability == result.triage.probability
