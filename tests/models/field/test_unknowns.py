"""Feature set 3 (children) and the donor table unknown inputs are integrated over."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from models.codehash import source_tree_sha256
from models.field import risk_children, risk_features, risk_impacts
from models.field.risk_children import (
    ALL_COLUMNS_3,
    ChildRiskInputs,
    Restraint,
    child_columns,
    inputs_arrays_3,
)
from models.field.risk_features import AirbagCode, RiskImputation, SeatSide
from models.field.risk_impacts import ALL_COLUMNS_2
from models.field.risk_model import feature_code_sha256
from models.field.unknowns import (
    DONORS_PER_OCCUPANT,
    MIN_DONORS,
    DonorTable,
    build_donors,
    pick_donors,
    seat_group,
    substitute,
)

_IMPUTATION = RiskImputation(
    age_years=35.0,
    female=0.5,
    stature_cm=170.0,
    mass_kg=75.0,
    quarter_turns=4.0,
    model_year=2010.0,
    accident_year=2014.0,
)


def test_feature_set_3_keeps_set_2_and_adds_the_child_columns() -> None:
    assert ALL_COLUMNS_3[: len(ALL_COLUMNS_2)] == ALL_COLUMNS_2
    assert ALL_COLUMNS_3[len(ALL_COLUMNS_2) :] == ("age_0_4", "age_5_9", "age_10_15", "child_seat")
    paths = [Path(m.__file__) for m in (risk_features, risk_impacts, risk_children)]
    assert feature_code_sha256(ALL_COLUMNS_3) == source_tree_sha256(paths)
    assert feature_code_sha256() == feature_code_sha256(ALL_COLUMNS_3)


def test_child_columns_by_age_group_and_child_seat() -> None:
    x = child_columns(
        np.array([0.0, 4.9, 5.0, 9.5, 10.0, 15.9, 16.0, 40.0]), ["child_seat"] + ["belted"] * 7
    )
    assert x[:, :3].tolist() == [
        [1, 0, 0],
        [1, 0, 0],
        [0, 1, 0],
        [0, 1, 0],
        [0, 0, 1],
        [0, 0, 1],
        [0, 0, 0],
        [0, 0, 0],
    ]
    assert x[:, 3].tolist() == [1, 0, 0, 0, 0, 0, 0, 0]


def _occupant(**kw: object) -> ChildRiskInputs:
    base: dict[str, object] = {
        "delta_v_kmh": 40.0,
        "pdof_deg": 0.0,
        "seat_row": 2,
        "seat_side": SeatSide.LEFT,
        "driver": False,
        "belted": True,
        "frontal_airbag": AirbagCode.NONE,
        "rollover": False,
        "multiple_impacts": False,
        "age_years": 6.0,
        "restraint": Restraint.CHILD_SEAT,
    }
    base.update(kw)
    return ChildRiskInputs(**base)  # type: ignore[arg-type]


def test_a_child_seat_is_restrained_and_an_unknown_restraint_is_never_imputed() -> None:
    arrays, _ = inputs_arrays_3([_occupant()], _IMPUTATION, 2.0)
    assert arrays["restraint"] == ["child_seat"]
    assert arrays["belted"].tolist() == [1.0]  # type: ignore[union-attr]
    unbelted, _ = inputs_arrays_3([_occupant(restraint=Restraint.NONE)], _IMPUTATION, 2.0)
    assert unbelted["belted"].tolist() == [0.0]  # type: ignore[union-attr]
    with pytest.raises(ValueError, match="integrated"):
        inputs_arrays_3([_occupant(restraint=None)], _IMPUTATION, 2.0)


def test_seat_groups() -> None:
    assert seat_group(1, "left", True) == "driver"
    assert seat_group(1, "right", False) == "front_passenger"
    assert seat_group(1, "middle", False) == "front_middle"
    assert seat_group(2, "right", False) == "row2_outboard"
    assert seat_group(2, "middle", False) == "row2_middle"
    assert seat_group(3, "left", False) == "row3"


def _population(n: int = 3000, seed: int = 3) -> tuple[list[str], dict[str, object], np.ndarray]:
    rng = np.random.default_rng(seed)
    group = rng.choice(["driver", "front_passenger", "row2_outboard"], n).tolist()
    age = np.where(
        np.array(group) == "row2_outboard", rng.uniform(0, 40, n), rng.uniform(16, 90, n)
    ).round()
    restraint = np.where(age < 8, "child_seat", np.where(rng.random(n) < 0.8, "belted", "none"))
    values = {
        "age_years": age,
        "female": rng.integers(0, 2, n).astype(float),
        "stature_cm": np.clip(100 + 2 * age, 100, 190),
        "mass_kg": np.clip(15 + 2 * age, 15, 110),
        "restraint": restraint.tolist(),
    }
    return group, values, rng.uniform(1, 100, n)


def test_the_donor_table_is_drawn_by_weight_and_deterministic() -> None:
    group, values, w = _population()
    a = build_donors(group, values, w, per_group=200)
    b = build_donors(group, values, w, per_group=200)
    assert a.to_document() == b.to_document()
    assert len(a.group) == 600
    # a row carrying most of its group's weight is drawn most of the time
    heavy = w.copy()
    first = group.index("driver")
    heavy[first] = 1e6
    t = build_donors(group, values, heavy, per_group=200)
    drivers = np.flatnonzero(np.asarray(t.group) == "driver")
    same = t.age_years[drivers] == values["age_years"][first]  # type: ignore[index]
    assert same.mean() > 0.9
    assert DonorTable.from_document(a.to_document()).to_document() == a.to_document()


def test_donors_match_what_is_known_and_relax_only_when_too_few() -> None:
    group, values, w = _population()
    t = build_donors(group, values, w, per_group=300)
    picked = pick_donors(t, "row2_outboard")
    assert picked.size == DONORS_PER_OCCUPANT
    assert set(np.asarray(t.group)[picked]) == {"row2_outboard"}
    # spread over ages: a stratified sample of the group's donors, not one age
    assert np.ptp(t.age_years[picked]) > 20
    child = pick_donors(t, "row2_outboard", age_years=6.0)
    assert np.all((t.age_years[child] >= 5) & (t.age_years[child] < 10))
    seat = pick_donors(t, "row2_outboard", restraint="child_seat")
    assert set(np.asarray(t.restraint)[seat]) == {"child_seat"}
    # no driver is in a child seat: the seat group is relaxed, the restraint kept
    relaxed = pick_donors(t, "driver", restraint="child_seat")
    assert relaxed.size >= MIN_DONORS
    assert set(np.asarray(t.restraint)[relaxed]) == {"child_seat"}
    assert np.array_equal(pick_donors(t, "driver"), pick_donors(t, "driver"))


def test_substitute_expands_only_the_unknown_inputs() -> None:
    group, values, w = _population()
    t = build_donors(group, values, w, per_group=100)
    arrays = {
        "age_years": np.array([30.0, 50.0]),
        "female": np.array([1.0, 0.0]),
        "stature_cm": np.array([160.0, 180.0]),
        "mass_kg": np.array([60.0, 90.0]),
        "belted": np.array([1.0, 1.0]),
        "restraint": ["belted", "belted"],
        "seat_side": ["left", "right"],
    }
    donors = pick_donors(t, "driver")
    out, owner = substitute(arrays, [(0, None, ()), (1, donors, ("age_years", "restraint"))], t)
    assert owner.tolist() == [0] + [1] * donors.size
    assert out["age_years"][0] == 30.0  # type: ignore[index]
    assert np.array_equal(out["age_years"][1:], t.age_years[donors])  # type: ignore[index]
    assert np.all(out["mass_kg"][1:] == 90.0)  # type: ignore[index]
    assert out["restraint"][1:] == [t.restraint[j] for j in donors]
    belted = [float(t.restraint[j] != "none") for j in donors]
    assert out["belted"][1:].tolist() == belted  # type: ignore[union-attr]
    assert out["seat_side"] == ["left"] + ["right"] * donors.size


def test_a_measured_delta_v_stands_for_a_smaller_reconstruction() -> None:
    """The measurement model's nodes: weights summing to one, centred on the direction's
    ratio times the measurement (frontal and rear: the two NASS-CDS/EDR comparisons, 23 %
    and 19 % under, weighted by their cases; side: Johnson & Gabler's, nearly one), within
    the measurement's own tolerance; every node a positive delta-V."""
    from models.field.measurement import (
        LONGITUDINAL_RATIO,
        MEASURED_TOLERANCE_SD,
        SIDE_RATIO,
        over_reconstructed_nodes,
        reconstructed_nodes,
    )

    assert LONGITUDINAL_RATIO == pytest.approx((121 * 0.77 + 228 * 0.81) / 349, abs=5e-4)
    assert SIDE_RATIO == pytest.approx((1.129 + 1.024) / 2 / 1.10, abs=5e-4)
    for pdof, ratio in ((0.0, LONGITUDINAL_RATIO), (180.0, LONGITUDINAL_RATIO)):
        values, weights = reconstructed_nodes(50.0, pdof)
        assert weights.sum() == pytest.approx(1.0)
        assert float(values @ weights) == pytest.approx(50.0 * ratio, rel=1e-12)
    for pdof in (60.0, 90.0, 270.0, 300.0):
        values, weights = reconstructed_nodes(50.0, pdof)
        assert float(values @ weights) == pytest.approx(50.0 * SIDE_RATIO, rel=1e-12)
    # the sectors' edges: 45 deg is side, 135 deg is rear (crash_mode_codes' sectors)
    assert reconstructed_nodes(50.0, 45.0)[0][1] == pytest.approx(50.0 * SIDE_RATIO)
    assert reconstructed_nodes(50.0, 135.0)[0][1] == pytest.approx(50.0 * LONGITUDINAL_RATIO)
    values, weights = reconstructed_nodes(50.0)
    assert values.min() > 50.0 * LONGITUDINAL_RATIO * (1 - 3 * MEASURED_TOLERANCE_SD)
    assert values.max() < 50.0 * LONGITUDINAL_RATIO * (1 + 3 * MEASURED_TOLERANCE_SD)
    assert np.all(reconstructed_nodes(0.5)[0] >= 1.0)
    arrays = {
        "delta_v_kmh": np.array([30.0, 50.0]),
        "pdof_deg": np.array([0.0, 0.0]),
        "restraint": ["belted", "none"],
    }
    out, owner, w = over_reconstructed_nodes(
        arrays, np.array([0, 1]), np.array([1.0, 1.0]), {1: 50.0}
    )
    assert owner.tolist() == [0] + [1] * values.size
    assert out["delta_v_kmh"][0] == 30.0  # type: ignore[index]
    assert np.allclose(out["delta_v_kmh"][1:], values)  # type: ignore[index]
    assert np.allclose(w[1:], weights)
    assert out["restraint"] == ["belted"] + ["none"] * values.size


def test_the_earlier_measurement_model_still_reads_as_it_did() -> None:
    """1.1.0 (field model 3.3.0's): both eras' ratios mixed by the population's years, for
    every direction; an artifact names its version and is read through it."""
    from models.field.measurement import (
        EARLY_ERA_SHARE,
        ERA_RATIOS,
        MEASUREMENT_MODELS,
        reconstructed_nodes,
    )

    old = MEASUREMENT_MODELS["1.1.0"]
    mean_ratio = EARLY_ERA_SHARE * ERA_RATIOS[0] + (1 - EARLY_ERA_SHARE) * ERA_RATIOS[1]
    for pdof in (0.0, 90.0):
        values, weights = reconstructed_nodes(50.0, pdof, old)
        assert values.size == 6
        assert float(values @ weights) == pytest.approx(50.0 * mean_ratio, rel=1e-12)
