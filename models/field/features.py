"""What the field risk model sees of an occupant, built one way for the fit and the service.

A notification becomes :class:`FieldInputs` in :func:`field_inputs` (the crash
mode from the PDOF, the seat and the rollover flag; delta-V from the processed
pulse; belt, age, sex, stature and mass of the occupant), and inputs become a
design-matrix row in :func:`design_matrix`. The offline fit builds its matrix
from the calibration rows through these same two functions, so the features a
request is scored on are the features the model was fitted on.

Design-matrix columns (:data:`FEATURE_NAMES`): an intercept; delta-V (km/h)
and its logarithm (risk rises steeply at low delta-V and about linearly in the
logit higher up; the fit keeps the slope positive everywhere); belted; one
indicator per crash mode other than frontal (near side, far side, rear,
rollover); age (years); multiple impacts; body mass index (kg/m^2). Unknown
age or body mass index is imputed by the calibration data's median (recorded
in the artifact); the answer says which inputs were imputed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Final

import numpy as np

from models.arrays import FloatArray
from models.impact_mode import ImpactMode
from models.limits import MAX_AGE_YEARS, MAX_DELTA_V_KMH
from models.notification import Occupant, Sex

__all__ = [
    "BMI_RANGE",
    "FEATURE_NAMES",
    "MAX_DELTA_V_KMH",
    "MIN_LOG_DELTA_V_KMH",
    "FieldInputs",
    "FieldMode",
    "Imputation",
    "design_matrix",
    "field_inputs",
    "field_mode",
]


class FieldMode(StrEnum):
    """Crash mode of an occupant as the field data know it (NASS-CDS ``crash_mode``)."""

    FRONTAL = "frontal"
    NEAR_SIDE = "near_side"
    FAR_SIDE = "far_side"
    REAR = "rear"
    ROLLOVER = "rollover"


#: Design-matrix columns, in order.
FEATURE_NAMES: Final[tuple[str, ...]] = (
    "intercept",
    "delta_v_kmh",
    "log_delta_v",
    "belted",
    "near_side",
    "far_side",
    "rear",
    "rollover",
    "age_years",
    "multiple_impacts",
    "bmi",
)

#: The crash modes with an indicator column (frontal is the reference).
_MODE_COLUMNS: Final[tuple[FieldMode, ...]] = (
    FieldMode.NEAR_SIDE,
    FieldMode.FAR_SIDE,
    FieldMode.REAR,
    FieldMode.ROLLOVER,
)

#: Floor of delta-V inside the logarithm, km/h. [R] Below the 49 CFR 563 event
#: trigger (8 km/h) the log term would run to minus infinity at rest; 1 km/h keeps
#: it finite; every calibration row is above it (smallest 3 km/h).
MIN_LOG_DELTA_V_KMH: Final[float] = 1.0

#: Body mass index range the model is evaluated in, kg/m^2. [R] The calibration
#: rows span 13.6-65.8; a stature and mass outside it (a typing slip, a child's
#: stature with an adult's mass) is clamped instead of extrapolated.
BMI_RANGE: Final[tuple[float, float]] = (13.0, 66.0)


@dataclass(frozen=True)
class FieldInputs:
    """One occupant as the field model sees it.

    Attributes
    ----------
    delta_v_kmh : float
        Resultant delta-V of the vehicle, km/h (0-200).
    mode : FieldMode
        Crash mode: rollover when reported, else the impact mode from the PDOF.
    belted : bool
    multiple_impacts : bool
    age_years : float or None
        None: imputed.
    sex : Sex or None
        Used through the sex offset of the model (borrowed from NASS-CDS
        1997-2000); None: no offset.
    stature_cm, mass_kg : float or None
        Give the body mass index when both are known; else it is imputed.
    """

    delta_v_kmh: float
    mode: FieldMode
    belted: bool
    multiple_impacts: bool
    age_years: float | None = None
    sex: Sex | None = None
    stature_cm: float | None = None
    mass_kg: float | None = None

    @property
    def bmi(self) -> float | None:
        """Body mass index, kg/m^2, when stature and mass are both known."""
        if self.stature_cm is None or self.mass_kg is None or self.stature_cm <= 0.0:
            return None
        return self.mass_kg / (self.stature_cm / 100.0) ** 2


@dataclass(frozen=True)
class Imputation:
    """Values used for unknown inputs (the calibration data's medians).

    Attributes
    ----------
    age_years : float
    bmi : float
        kg/m^2.
    """

    age_years: float
    bmi: float


def field_mode(impact_mode: ImpactMode, rollover: bool) -> FieldMode:
    """Crash mode of the field data from the occupant's impact mode and the rollover flag.

    The calibration file codes a rolled vehicle as ``roll`` whatever the
    direction of its planar impact, so a reported rollover wins.
    """
    if rollover:
        return FieldMode.ROLLOVER
    return FieldMode(impact_mode.value)


def field_inputs(
    occupant: Occupant,
    delta_v_kmh: float,
    impact_mode: ImpactMode,
    *,
    multiple_impacts: bool,
    rollover: bool,
) -> FieldInputs:
    """The field model's view of one occupant of a notification.

    Parameters
    ----------
    occupant : Occupant
    delta_v_kmh : float
        Resultant delta-V of the processed pulse, km/h.
    impact_mode : ImpactMode
        The occupant's impact mode (:func:`models.impact_mode.classify_impact`).
    multiple_impacts, rollover : bool
        The notification's flags.

    Returns
    -------
    FieldInputs
    """
    return FieldInputs(
        delta_v_kmh=float(delta_v_kmh),
        mode=field_mode(impact_mode, rollover),
        belted=bool(occupant.belted),
        multiple_impacts=bool(multiple_impacts),
        age_years=occupant.age_years,
        sex=occupant.sex,
        stature_cm=occupant.stature_cm,
        mass_kg=occupant.mass_kg,
    )


def _check(name: str, value: float, lo: float, hi: float) -> float:
    x = float(value)
    if not math.isfinite(x) or not lo <= x <= hi:
        raise ValueError(f"`{name}` must be finite and in [{lo:g}, {hi:g}], got {value!r}.")
    return x


def design_matrix(
    inputs: Sequence[FieldInputs], imputation: Imputation
) -> tuple[FloatArray, tuple[tuple[str, ...], ...]]:
    """Design-matrix rows of `inputs`, with the names of the inputs imputed per row.

    Parameters
    ----------
    inputs : sequence of FieldInputs
        n occupants.
    imputation : Imputation
        Values for unknown age and body mass index.

    Returns
    -------
    X : ndarray, shape (n, len(FEATURE_NAMES))
        Columns per :data:`FEATURE_NAMES`.
    imputed : tuple of tuple of str
        Per row, the inputs that were imputed (``age_years``, ``bmi``).

    Raises
    ------
    ValueError
        A delta-V or age that is not finite or out of range (naming it).
    """
    x = np.zeros((len(inputs), len(FEATURE_NAMES)))
    imputed: list[tuple[str, ...]] = []
    for i, f in enumerate(inputs):
        dv = _check("delta_v_kmh", f.delta_v_kmh, 0.0, MAX_DELTA_V_KMH)
        missing = []
        if f.age_years is None:
            age = imputation.age_years
            missing.append("age_years")
        else:
            age = _check("age_years", f.age_years, 0.0, MAX_AGE_YEARS)
        bmi = f.bmi
        if bmi is None or not math.isfinite(bmi):
            bmi = imputation.bmi
            missing.append("bmi")
        bmi = min(max(bmi, BMI_RANGE[0]), BMI_RANGE[1])
        row = [
            1.0,
            dv,
            math.log(max(dv, MIN_LOG_DELTA_V_KMH)),
            float(f.belted),
            *(float(f.mode is m) for m in _MODE_COLUMNS),
            age,
            float(f.multiple_impacts),
            bmi,
        ]
        x[i] = row
        imputed.append(tuple(missing))
    return x, tuple(imputed)
