"""What the field risk models (ISS 15+, region AIS 3+) see of an occupant.

One notification occupant becomes :class:`RiskInputs`; inputs become design
columns in :func:`design_columns`, vectorised over occupants. The offline fit
(:mod:`models.offline.field.risk_fit`) builds its matrix from the NASS-CDS
1997-2014 occupant file through the same :func:`design_columns`, so the served
features are the fitted features. An artifact names the columns it uses (the
groups cross-validation kept); :func:`design_columns` builds every candidate.

Candidate columns (by group, :data:`FEATURE_GROUPS`):

- ``delta_v``: delta-V, km/h, as a restricted cubic spline (knots
  :data:`DELTA_V_KNOTS_KMH`), clamped to :data:`DELTA_V_CLAMP_KMH`;
- ``mode``: near side, far side, rear (frontal the reference), from the
  direction of the delta-V (PDOF) and the occupant's side: the nearest axis
  (0 front, 90 right, 180 rear, 270 left); a side impact on the occupant's
  side is near side; a middle-seat occupant takes a side impact as far side
  (as :func:`models.impact_mode.classify_impact` does for the rear middle);
- ``mode_delta_v``: delta-V slope by mode;
- ``lateral``: ``|sin PDOF|`` (the lateral share of the delta-V components);
- ``belt`` and ``belt_delta_v``: belted, and its delta-V slope;
- ``airbag``: frontal airbag deployed / not deployed (none the reference);
- ``seat``: driver, front middle, second row, third row;
- ``age``: restricted cubic spline of age (knots :data:`AGE_KNOTS_YEARS`);
- ``sex``: female; ``body``: stature (cm) and mass (kg), clamped;
- ``rollover``: rolled, and ``log(1 + quarter turns)``;
- ``multiple_impacts``; ``model_year`` (clamped); ``accident_year`` (a model
  constant at request time: the artifact's reference year).

Unknown inputs (age, sex, stature, mass, quarter turns of a reported rollover,
model year) take the imputation values of the artifact (medians or shares of
the fitted population) and are named per occupant.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Final

import numpy as np

from models.arrays import FloatArray
from models.limits import MAX_AGE_YEARS, MAX_DELTA_V_KMH

__all__ = [
    "AGE_KNOTS_YEARS",
    "ALL_COLUMNS",
    "DELTA_V_CLAMP_KMH",
    "DELTA_V_KNOTS_KMH",
    "FEATURE_GROUPS",
    "RiskImputation",
    "RiskInputs",
    "SeatSide",
    "AirbagCode",
    "crash_mode_codes",
    "design_columns",
    "inputs_arrays",
    "rcs_basis",
]


class SeatSide(StrEnum):
    """Side of the vehicle the seat is on (NASS-CDS ``seat_side``)."""

    LEFT = "left"
    MIDDLE = "middle"
    RIGHT = "right"


class AirbagCode(StrEnum):
    """Frontal airbag at the seat (NASS-CDS ``frontal_airbag``)."""

    DEPLOYED = "deployed"
    NOT_DEPLOYED = "not_deployed"
    NONE = "none"


#: Knots of the delta-V spline, km/h. [R] Harrell's 5/35/65/95 % quantiles of
#: the fitted population's delta-V (10, 18, 27, 52 km/h, rounded).
DELTA_V_KNOTS_KMH: Final[tuple[float, ...]] = (10.0, 18.0, 27.0, 52.0)

#: Delta-V range the model is evaluated in, km/h. [R] Above 100 km/h the data
#: hold a few dozen vehicles: the spline's linear tail is not extrapolated
#: further (the answer says so), below 1 km/h a notification is not a crash.
DELTA_V_CLAMP_KMH: Final[tuple[float, float]] = (1.0, 100.0)

#: Knots of the age spline, years. [R] 10/50/90 % quantiles of the adults (18, 33, 65).
AGE_KNOTS_YEARS: Final[tuple[float, ...]] = (18.0, 33.0, 65.0)

#: Clamps of stature (cm), mass (kg) and model year. [R] The adults' 0.5-99.5 %
#: range; model years outside the data's are not extrapolated.
STATURE_CLAMP_CM: Final[tuple[float, float]] = (145.0, 200.0)
MASS_CLAMP_KG: Final[tuple[float, float]] = (40.0, 160.0)
MODEL_YEAR_CLAMP: Final[tuple[float, float]] = (1980.0, 2015.0)

#: Candidate columns by group, in design order (``intercept`` is always first).
FEATURE_GROUPS: Final[Mapping[str, tuple[str, ...]]] = {
    "delta_v": ("delta_v_kmh", "delta_v_s1", "delta_v_s2"),
    "mode": ("near_side", "far_side", "rear"),
    "mode_delta_v": ("near_side_dv", "far_side_dv", "rear_dv"),
    "lateral": ("lateral_share",),
    "belt": ("belted",),
    "belt_delta_v": ("belted_dv",),
    "airbag": ("airbag_deployed", "airbag_not_deployed"),
    "seat": ("driver", "front_middle", "row2", "row3"),
    "age": ("age_years", "age_s1"),
    "sex": ("female",),
    "body": ("stature_cm", "mass_kg"),
    "rollover": ("rollover", "log1p_quarter_turns"),
    "multiple_impacts": ("multiple_impacts",),
    "model_year": ("model_year",),
    "accident_year": ("accident_year",),
}

#: Every candidate column, in order.
ALL_COLUMNS: Final[tuple[str, ...]] = ("intercept",) + tuple(
    c for cols in FEATURE_GROUPS.values() for c in cols
)


@dataclass(frozen=True)
class RiskInputs:
    """One occupant as the field risk models see it.

    Attributes
    ----------
    delta_v_kmh : float
        Resultant delta-V of the vehicle, km/h (0-200).
    pdof_deg : float
        Direction of the delta-V (principal direction of force), deg clockwise
        from straight ahead.
    seat_row : int
        1-3.
    seat_side : SeatSide
    driver : bool
    belted : bool
    frontal_airbag : AirbagCode
    rollover : bool
    multiple_impacts : bool
    quarter_turns : int or None
        Rollover quarter turns where sent (None: imputed if rolled, else 0).
    age_years : float or None
    female : bool or None
    stature_cm, mass_kg : float or None
    model_year : int or None
    """

    delta_v_kmh: float
    pdof_deg: float
    seat_row: int
    seat_side: SeatSide
    driver: bool
    belted: bool
    frontal_airbag: AirbagCode
    rollover: bool
    multiple_impacts: bool
    quarter_turns: int | None = None
    age_years: float | None = None
    female: bool | None = None
    stature_cm: float | None = None
    mass_kg: float | None = None
    model_year: int | None = None


@dataclass(frozen=True)
class RiskImputation:
    """Values for unknown inputs (of the fitted population; stored in the artifact).

    Attributes
    ----------
    age_years : float
        Median age, years.
    female : float
        Share of women.
    stature_cm, mass_kg : float
        Medians, cm and kg.
    quarter_turns : float
        Median quarter turns of rolled vehicles.
    model_year : float
        Median model year of the latest accident year.
    accident_year : float
        The reference accident year served (the latest year fitted).
    """

    age_years: float
    female: float
    stature_cm: float
    mass_kg: float
    quarter_turns: float
    model_year: float
    accident_year: float


def rcs_basis(x: FloatArray, knots: Sequence[float]) -> FloatArray:
    """Restricted (natural) cubic spline basis beyond the linear term (Harrell).

    Parameters
    ----------
    x : ndarray, shape (n,)
    knots : sequence of float
        k >= 3 increasing knots.

    Returns
    -------
    ndarray, shape (n, k - 2)
        Linear beyond the outer knots; scaled by ``(t_k - t_1)^2``.
    """
    t = np.asarray(knots, dtype=np.float64)
    k = t.size
    norm = (t[-1] - t[0]) ** 2
    cols = []
    for j in range(k - 2):
        c = (
            np.maximum(x - t[j], 0.0) ** 3
            - np.maximum(x - t[k - 2], 0.0) ** 3 * (t[k - 1] - t[j]) / (t[k - 1] - t[k - 2])
            + np.maximum(x - t[k - 1], 0.0) ** 3 * (t[k - 2] - t[j]) / (t[k - 1] - t[k - 2])
        )
        cols.append(c / norm)
    return np.column_stack(cols)


def crash_mode_codes(pdof_deg: FloatArray, side: Sequence[str]) -> tuple[FloatArray, ...]:
    """Near-side, far-side and rear indicators from the PDOF and the seat side.

    Parameters
    ----------
    pdof_deg : ndarray, shape (n,)
    side : sequence of str
        ``left``, ``middle`` or ``right`` per occupant.

    Returns
    -------
    near, far, rear : ndarray, shape (n,) each
    """
    p = np.asarray(pdof_deg, dtype=np.float64) % 360.0
    right = (p >= 45.0) & (p < 135.0)
    rear = (p >= 135.0) & (p < 225.0)
    left = (p >= 225.0) & (p < 315.0)
    s = np.asarray(side, dtype=object)
    near = (right & (s == "right")) | (left & (s == "left"))
    far = (right | left) & ~near
    return near.astype(float), far.astype(float), rear.astype(float)


def _check(name: str, x: FloatArray, lo: float, hi: float) -> None:
    bad = ~np.isfinite(x) | (x < lo) | (x > hi)
    if np.any(bad):
        raise ValueError(f"`{name}` must be finite and in [{lo:g}, {hi:g}], got {x[bad][0]!r}.")


def design_columns(a: Mapping[str, FloatArray | Sequence[str]]) -> FloatArray:
    """Every candidate design column (:data:`ALL_COLUMNS`) from raw input arrays.

    Parameters
    ----------
    a : mapping of str to array, each shape (n,)
        ``delta_v_kmh``, ``pdof_deg``, ``seat_row``, ``seat_side`` (str),
        ``driver``, ``belted``, ``airbag`` (str, :class:`AirbagCode` values),
        ``rollover``, ``quarter_turns``, ``multiple_impacts``, ``age_years``,
        ``female``, ``stature_cm``, ``mass_kg``, ``model_year``,
        ``accident_year``; all known (imputed already, :func:`inputs_arrays`).

    Returns
    -------
    ndarray, shape (n, len(ALL_COLUMNS))

    Raises
    ------
    ValueError
        Delta-V or age not finite or out of range (naming it).
    """
    dv_raw = np.asarray(a["delta_v_kmh"], dtype=np.float64)
    _check("delta_v_kmh", dv_raw, 0.0, MAX_DELTA_V_KMH)
    age_raw = np.asarray(a["age_years"], dtype=np.float64)
    _check("age_years", age_raw, 0.0, MAX_AGE_YEARS)
    n = dv_raw.size
    dv = np.clip(dv_raw, *DELTA_V_CLAMP_KMH)
    age = np.clip(age_raw, AGE_KNOTS_YEARS[0] - 2.0, MAX_AGE_YEARS)
    pdof = np.asarray(a["pdof_deg"], dtype=np.float64)
    near, far, rear = crash_mode_codes(pdof, list(a["seat_side"]))
    belted = np.asarray(a["belted"], dtype=np.float64)
    airbag = np.asarray(a["airbag"], dtype=object)
    row = np.asarray(a["seat_row"], dtype=np.float64)
    side = np.asarray(a["seat_side"], dtype=object)
    qt = np.asarray(a["quarter_turns"], dtype=np.float64)
    cols = [
        np.ones(n),
        dv,
        *rcs_basis(dv, DELTA_V_KNOTS_KMH).T,
        near,
        far,
        rear,
        near * dv,
        far * dv,
        rear * dv,
        np.abs(np.sin(np.radians(pdof))),
        belted,
        belted * dv,
        (airbag == AirbagCode.DEPLOYED.value).astype(float),
        (airbag == AirbagCode.NOT_DEPLOYED.value).astype(float),
        np.asarray(a["driver"], dtype=np.float64),
        ((row == 1) & (side == "middle")).astype(float),
        (row == 2).astype(float),
        (row == 3).astype(float),
        age,
        *rcs_basis(age, AGE_KNOTS_YEARS).T,
        np.asarray(a["female"], dtype=np.float64),
        np.clip(np.asarray(a["stature_cm"], dtype=np.float64), *STATURE_CLAMP_CM),
        np.clip(np.asarray(a["mass_kg"], dtype=np.float64), *MASS_CLAMP_KG),
        np.asarray(a["rollover"], dtype=np.float64),
        np.log1p(np.maximum(qt, 0.0)),
        np.asarray(a["multiple_impacts"], dtype=np.float64),
        np.clip(np.asarray(a["model_year"], dtype=np.float64), *MODEL_YEAR_CLAMP),
        np.asarray(a["accident_year"], dtype=np.float64),
    ]
    x = np.column_stack(cols)
    assert x.shape[1] == len(ALL_COLUMNS)
    return x


def inputs_arrays(
    inputs: Sequence[RiskInputs], imputation: RiskImputation
) -> tuple[dict[str, FloatArray | list[str]], tuple[tuple[str, ...], ...]]:
    """Raw input arrays of notification occupants, unknowns imputed and named.

    Parameters
    ----------
    inputs : sequence of RiskInputs
        n occupants.
    imputation : RiskImputation

    Returns
    -------
    arrays : dict
        As :func:`design_columns` takes them; ``accident_year`` is the
        imputation's reference year.
    imputed : tuple of tuple of str
        Per occupant, the inputs imputed (``age_years``, ``female``,
        ``stature_cm``, ``mass_kg``, ``quarter_turns``, ``model_year``).
    """
    imp = imputation
    cols: dict[str, list[float]] = {
        k: []
        for k in (
            "delta_v_kmh pdof_deg seat_row driver belted rollover quarter_turns multiple_impacts "
            "age_years female stature_cm mass_kg model_year accident_year"
        ).split()
    }
    sides: list[str] = []
    airbags: list[str] = []
    imputed: list[tuple[str, ...]] = []
    for f in inputs:
        miss: list[str] = []

        def known(name: str, value: float | None, default: float, miss: list[str] = miss) -> float:
            if value is None or not math.isfinite(float(value)):
                miss.append(name)
                return default
            return float(value)

        cols["delta_v_kmh"].append(float(f.delta_v_kmh))
        cols["pdof_deg"].append(float(f.pdof_deg))
        cols["seat_row"].append(float(f.seat_row))
        cols["driver"].append(float(f.driver))
        cols["belted"].append(float(f.belted))
        cols["rollover"].append(float(f.rollover))
        if f.rollover:
            qt = known("quarter_turns", f.quarter_turns, imp.quarter_turns)
        else:
            qt = 0.0
        cols["quarter_turns"].append(qt)
        cols["multiple_impacts"].append(float(f.multiple_impacts))
        cols["age_years"].append(known("age_years", f.age_years, imp.age_years))
        female = None if f.female is None else float(f.female)
        cols["female"].append(known("female", female, imp.female))
        cols["stature_cm"].append(known("stature_cm", f.stature_cm, imp.stature_cm))
        cols["mass_kg"].append(known("mass_kg", f.mass_kg, imp.mass_kg))
        my = None if f.model_year is None else float(f.model_year)
        cols["model_year"].append(known("model_year", my, imp.model_year))
        cols["accident_year"].append(imp.accident_year)
        sides.append(f.seat_side.value)
        airbags.append(f.frontal_airbag.value)
        imputed.append(tuple(miss))
    out: dict[str, FloatArray | list[str]] = {k: np.array(v) for k, v in cols.items()}
    out["seat_side"] = sides
    out["airbag"] = airbags
    return out, tuple(imputed)
