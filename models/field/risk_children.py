"""Feature set 3 of the field risk models: children and how they are restrained.

Feature sets 1 and 2 (:mod:`models.field.risk_features`,
:mod:`models.field.risk_impacts`) are left as they were fitted: their code is
checksummed into the artifacts that use them. Feature set 3 adds, after set
2's columns (whose indices stay):

- ``age_0_4``, ``age_5_9``, ``age_10_15`` (group ``child_age``): the child's
  age group. Set 1's age spline clamps every age below 16 to 16, so a child's
  age enters through these indicators only: a shared model with child terms.
  The groups are those of the 2021 National Guideline for the Field Triage
  of Injured Patients (a child of 0-9 is a criterion of its own) and of the
  child-restraint stages (rear- or forward-facing seats to about 4, boosters
  to about 9; NHTSA's "Car Seat Recommendations for Children").
- ``child_seat`` (group ``child_restraint``): restrained in a child seat of
  any kind (NASS-CDS codes every child restraint alike, so the model treats a
  rear-facing seat, a forward-facing seat and a booster alike). A child seat
  is a restraint: its ``belted`` column is 1.

The restraint state of an occupant is one of :class:`Restraint`; unknown
(``None``) is integrated over (:mod:`models.field.unknowns`), never imputed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Final

import numpy as np

from models.arrays import FloatArray
from models.field.risk_features import RiskImputation, RiskInputs
from models.field.risk_impacts import (
    ALL_COLUMNS_2,
    FEATURE_GROUPS_2,
    FEATURE_SET_SOURCES,
    ImpactRiskInputs,
    design_columns_2,
    inputs_arrays_2,
)

__all__ = [
    "ALL_COLUMNS_3",
    "CHILD_AGE_GROUPS_YEARS",
    "CHILD_GROUPS",
    "CHILD_MAX_AGE_YEARS",
    "FEATURE_GROUPS_3",
    "FEATURE_SET_SOURCES_3",
    "ChildRiskInputs",
    "Restraint",
    "design_columns_3",
    "inputs_arrays_3",
]

#: Below this age an occupant is a child, years. [R] NASS-CDS and the field
#: triage guideline's pediatric criteria take 15 and younger as children
#: (the occupant models and the adult calibration take 16 and older).
CHILD_MAX_AGE_YEARS: Final[float] = 16.0

#: The child age groups, [lo, hi) years (module docstring).
CHILD_AGE_GROUPS_YEARS: Final[tuple[tuple[str, float, float], ...]] = (
    ("age_0_4", 0.0, 5.0),
    ("age_5_9", 5.0, 10.0),
    ("age_10_15", 10.0, CHILD_MAX_AGE_YEARS),
)

#: The groups feature set 3 adds, in design order after set 2's.
CHILD_GROUPS: Final[Mapping[str, tuple[str, ...]]] = {
    "child_age": tuple(name for name, _, _ in CHILD_AGE_GROUPS_YEARS),
    "child_restraint": ("child_seat",),
}

#: Every candidate column of feature set 3 (set 2's first, unchanged).
ALL_COLUMNS_3: Final[tuple[str, ...]] = ALL_COLUMNS_2 + tuple(
    c for cols in CHILD_GROUPS.values() for c in cols
)

#: Candidate groups of feature set 3.
FEATURE_GROUPS_3: Final[Mapping[str, tuple[str, ...]]] = {**FEATURE_GROUPS_2, **CHILD_GROUPS}

#: Feature code modules (under ``models/``) of each feature set, by its columns.
FEATURE_SET_SOURCES_3: Final[Mapping[tuple[str, ...], tuple[str, ...]]] = {
    **FEATURE_SET_SOURCES,
    ALL_COLUMNS_3: ("field/risk_features.py", "field/risk_impacts.py", "field/risk_children.py"),
}


class Restraint(StrEnum):
    """How the field data know an occupant's restraint (NASS-CDS ``belt``)."""

    BELTED = "belted"
    NONE = "none"
    CHILD_SEAT = "child_seat"


@dataclass(frozen=True)
class ChildRiskInputs(ImpactRiskInputs):
    """Feature set 3's occupant: set 2's and the restraint state.

    Attributes
    ----------
    restraint : Restraint or None
        None: unknown (integrated over, :mod:`models.field.unknowns`); the
        inherited ``belted`` is then ignored.
    """

    restraint: Restraint | None = None


def restraint_of(inputs: RiskInputs) -> Restraint | None:
    """An occupant's restraint state (plain inputs: from ``belted``)."""
    if isinstance(inputs, ChildRiskInputs):
        return inputs.restraint
    return Restraint.BELTED if inputs.belted else Restraint.NONE


def child_columns(age_years: FloatArray, restraint: Sequence[str]) -> FloatArray:
    """Feature set 3's added columns, shape (n, 4).

    Parameters
    ----------
    age_years : ndarray, shape (n,)
    restraint : sequence of str
        :class:`Restraint` values.
    """
    age = np.asarray(age_years, dtype=np.float64)
    cols = [((age >= lo) & (age < hi)).astype(float) for _, lo, hi in CHILD_AGE_GROUPS_YEARS]
    seat = np.asarray(restraint, dtype=object) == Restraint.CHILD_SEAT.value
    return np.column_stack([*cols, seat.astype(float)])


def design_columns_3(a: Mapping[str, FloatArray | Sequence[str]]) -> FloatArray:
    """Every candidate column of feature set 3 (:data:`ALL_COLUMNS_3`).

    Parameters
    ----------
    a : mapping of str to array, each shape (n,)
        What :func:`models.field.risk_impacts.design_columns_2` takes (its
        ``belted`` is 1 for a child seat), and ``restraint`` (str).

    Returns
    -------
    ndarray, shape (n, len(ALL_COLUMNS_3))
    """
    x2 = design_columns_2(a)
    x = np.column_stack(
        [x2, child_columns(np.asarray(a["age_years"], dtype=np.float64), list(a["restraint"]))]
    )
    assert x.shape[1] == len(ALL_COLUMNS_3)
    return x


def inputs_arrays_3(
    inputs: Sequence[RiskInputs], imputation: RiskImputation, imputed_multiple: float
) -> tuple[dict[str, FloatArray | list[str]], tuple[tuple[str, ...], ...]]:
    """:func:`models.field.risk_impacts.inputs_arrays_2` and the restraint.

    Every input must be known here: unknown ones are resolved before, by
    integration over the fitted population (:mod:`models.field.unknowns`).
    """
    states = [restraint_of(f) for f in inputs]
    if any(s is None for s in states):
        raise ValueError("an unknown restraint is integrated over, not imputed")
    arrays, imputed = inputs_arrays_2(inputs, imputation, imputed_multiple)
    arrays["restraint"] = [str(s) for s in states]
    arrays["belted"] = np.array([float(s is not Restraint.NONE) for s in states])
    return arrays, imputed
