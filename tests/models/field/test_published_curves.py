"""The shipped field model against published field risk curves given in mph (issue 32).

The curves and tolerances, with their reasons, are in
:mod:`models.offline.field.published`. Each check is also run on the retired
artifact 1.0.0 (fitted on mph read as km/h): the NHTSA checks refuse it, so a
units defect of that kind cannot ship again unseen.
"""

from __future__ import annotations

import pytest

from models.field.features import FieldInputs
from models.field.model import FieldModel, load_default
from models.field.versions import artifact_for_version
from models.offline.field.fit import calibration_design
from models.offline.field.published import (
    AUGENSTEIN_MAIS3_AT_30_MPH,
    NHTSA_ALL,
    NHTSA_FRONTAL,
    NHTSA_LOGIT_TOLERANCE,
    PublishedCurve,
    augenstein_check,
    curve_check,
)
from models.units import KM_PER_MILE, kmh_to_mph, mph_to_kmh

RETIRED = "1.0.0"


@pytest.fixture(scope="module")
def occupants() -> tuple[FieldInputs, ...]:
    return calibration_design().inputs


@pytest.fixture(scope="module")
def retired() -> FieldModel:
    return FieldModel.from_artifact(artifact_for_version(RETIRED))


def test_the_conversion_is_the_international_mile() -> None:
    assert KM_PER_MILE == 1.609344
    assert mph_to_kmh(25.0) == pytest.approx(40.2336)
    assert kmh_to_mph(mph_to_kmh(30.0)) == pytest.approx(30.0, rel=1e-15)


def test_the_published_curves_are_as_quoted() -> None:
    """NHTSA frontal: 10 % at about 29.5 mph, 20 % at 34.5, 50 % at 43 (the source)."""
    assert NHTSA_FRONTAL.probability(29.5) == pytest.approx(0.10, abs=0.01)
    assert NHTSA_FRONTAL.probability(34.5) == pytest.approx(0.20, abs=0.01)
    assert NHTSA_FRONTAL.probability(43.0) == pytest.approx(0.50, abs=0.01)
    assert NHTSA_ALL.probability(25.0) == pytest.approx(0.054, abs=0.001)


@pytest.mark.parametrize("curve", [NHTSA_ALL, NHTSA_FRONTAL], ids=["all", "frontal"])
def test_the_shipped_model_follows_nhtsas_curve(
    curve: PublishedCurve, occupants: tuple[FieldInputs, ...]
) -> None:
    check = curve_check(load_default(), occupants, curve)
    assert check.passed, check.failures


@pytest.mark.parametrize("curve", [NHTSA_ALL, NHTSA_FRONTAL], ids=["all", "frontal"])
def test_the_retired_model_is_refused_by_nhtsas_curve(
    curve: PublishedCurve, occupants: tuple[FieldInputs, ...], retired: FieldModel
) -> None:
    """1.0.0 read 25 mph (40 km/h) as 40 mph: 2.2-2.5 too high in the logit at every speed."""
    check = curve_check(retired, occupants, curve)
    assert not check.passed
    assert all(d > NHTSA_LOGIT_TOLERANCE for d in check.logit_differences)


def test_the_shipped_model_orders_the_crash_modes_as_augenstein(
    occupants: tuple[FieldInputs, ...],
) -> None:
    check = augenstein_check(load_default(), occupants)
    assert check.passed, check.failures
    assert set(check.model) == set(AUGENSTEIN_MAIS3_AT_30_MPH)
