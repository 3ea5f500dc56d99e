"""Feature set 2 of the field risk models: the impact's side and how many impacts.

Feature set 1 (:mod:`models.field.risk_features`, served by ``field_iss15``
3.0.0 and 3.1.0) is left as it was fitted: its code is checksummed into those
artifacts, and any change to it would refuse them at load. Feature set 2 adds
two candidate columns after set 1's (set 1's columns keep their indices):

- ``pdof_relative_deg`` (group ``pdof_relative``): the direction of the delta-V
  seen from the occupant's side, degrees in (-180, 180]: 0 straight ahead,
  +90 from the occupant's own side (near side), -90 from the other side (far
  side), 180 from behind. A middle-seat occupant takes either side as the far
  side, as :func:`models.field.risk_features.crash_mode_codes` does. Set 1's
  crash-mode indicators cut the circle at 45-degree lines; the angle lets a
  tree split where the data say (an oblique near-side impact, say).
- ``impact_count`` (group ``impact_count``): the harmful events of the vehicle,
  clamped to :data:`IMPACT_COUNT_CLAMP`. A notification sends it where the
  vehicle counts its events (``crash.impact_count``; a VEDS document's pulses);
  unknown, a single impact is one event, and multiple impacts take the fitted
  population's median count of vehicles with two or more (imputed and named).

An artifact of feature set 2 records the checksum of both modules
(:data:`FEATURE_SOURCES`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from models.arrays import FloatArray
from models.field.risk_features import (
    ALL_COLUMNS,
    FEATURE_GROUPS,
    RiskImputation,
    RiskInputs,
    design_columns,
    inputs_arrays,
)

__all__ = [
    "ALL_COLUMNS_2",
    "FEATURE_GROUPS_2",
    "FEATURE_SET_SOURCES",
    "IMPACT_COUNT_CLAMP",
    "IMPACT_GROUPS",
    "ImpactRiskInputs",
    "design_columns_2",
    "impact_count_values",
    "inputs_arrays_2",
    "relative_pdof_deg",
]

#: Harmful events counted, clamped. [R] NASS-CDS 1997-2014 occupants: 99 % of
#: them are in vehicles of 6 events or fewer (663 at 6, 531 above).
IMPACT_COUNT_CLAMP: Final[tuple[float, float]] = (1.0, 6.0)

#: The groups feature set 2 adds, in design order after set 1's.
IMPACT_GROUPS: Final[Mapping[str, tuple[str, ...]]] = {
    "pdof_relative": ("pdof_relative_deg",),
    "impact_count": ("impact_count",),
}

#: Every candidate column of feature set 2 (set 1's first, unchanged).
ALL_COLUMNS_2: Final[tuple[str, ...]] = ALL_COLUMNS + tuple(
    c for cols in IMPACT_GROUPS.values() for c in cols
)

#: Candidate groups of feature set 2.
FEATURE_GROUPS_2: Final[Mapping[str, tuple[str, ...]]] = {**FEATURE_GROUPS, **IMPACT_GROUPS}

#: Feature code modules (under ``models/``) of each feature set, by its columns.
FEATURE_SET_SOURCES: Final[Mapping[tuple[str, ...], tuple[str, ...]]] = {
    ALL_COLUMNS: ("field/risk_features.py",),
    ALL_COLUMNS_2: ("field/risk_features.py", "field/risk_impacts.py"),
}


@dataclass(frozen=True)
class ImpactRiskInputs(RiskInputs):
    """:class:`RiskInputs` with the vehicle's impact count.

    Attributes
    ----------
    impact_count : int or None
        Harmful events of the vehicle where counted (None: from
        ``multiple_impacts``, see :func:`impact_count_values`).
    """

    impact_count: int | None = None


def _wrap_deg(x: FloatArray) -> FloatArray:
    """Angles to (-180, 180]."""
    out: FloatArray = 180.0 - np.mod(180.0 - x, 360.0)
    return out


def relative_pdof_deg(pdof_deg: FloatArray, seat_side: Sequence[str]) -> FloatArray:
    """Direction of the delta-V from the occupant's side, deg in (-180, 180].

    Parameters
    ----------
    pdof_deg : ndarray, shape (n,)
        Clockwise from straight ahead (90: from the right).
    seat_side : sequence of str
        ``left``, ``middle`` or ``right``.

    Returns
    -------
    ndarray, shape (n,)
        +90: from the occupant's side; -90: from the other; a middle seat
        takes either side as the other (``-|angle|``).
    """
    s = _wrap_deg(np.asarray(pdof_deg, dtype=np.float64))
    side = np.asarray(seat_side, dtype=object)
    rel = np.where(side == "right", s, np.where(side == "left", -s, -np.abs(s)))
    return _wrap_deg(rel)


def impact_count_values(
    counts: Sequence[int | None], multiple: Sequence[bool], imputed_multiple: float
) -> tuple[FloatArray, tuple[bool, ...]]:
    """Impact counts with unknowns resolved: (counts (n,), imputed per occupant).

    A known count is taken (clamped); unknown, a single impact is 1 and
    multiple impacts take `imputed_multiple` (the fitted population's median
    count of vehicles with two or more events).
    """
    out, imputed = [], []
    for c, m in zip(counts, multiple, strict=True):
        if c is not None and math.isfinite(float(c)):
            out.append(float(c))
            imputed.append(False)
        else:
            out.append(imputed_multiple if m else 1.0)
            imputed.append(bool(m))
    return np.clip(np.array(out, dtype=np.float64), *IMPACT_COUNT_CLAMP), tuple(imputed)


def design_columns_2(a: Mapping[str, FloatArray | Sequence[str]]) -> FloatArray:
    """Every candidate column of feature set 2 (:data:`ALL_COLUMNS_2`).

    Parameters
    ----------
    a : mapping of str to array, each shape (n,)
        What :func:`models.field.risk_features.design_columns` takes, and
        ``impact_count`` (known or resolved, :func:`impact_count_values`).

    Returns
    -------
    ndarray, shape (n, len(ALL_COLUMNS_2))
    """
    x1 = design_columns(a)
    rel = relative_pdof_deg(np.asarray(a["pdof_deg"], dtype=np.float64), list(a["seat_side"]))
    count = np.clip(np.asarray(a["impact_count"], dtype=np.float64), *IMPACT_COUNT_CLAMP)
    x = np.column_stack([x1, rel, count])
    assert x.shape[1] == len(ALL_COLUMNS_2)
    return x


def inputs_arrays_2(
    inputs: Sequence[RiskInputs], imputation: RiskImputation, imputed_multiple: float
) -> tuple[dict[str, FloatArray | list[str]], tuple[tuple[str, ...], ...]]:
    """:func:`models.field.risk_features.inputs_arrays` and the impact count.

    An occupant given as plain :class:`RiskInputs` has no count (resolved
    from ``multiple_impacts``); an imputed count is named ``impact_count``.
    """
    arrays, imputed = inputs_arrays(inputs, imputation)
    counts = [f.impact_count if isinstance(f, ImpactRiskInputs) else None for f in inputs]
    values, guessed = impact_count_values(
        counts, [f.multiple_impacts for f in inputs], imputed_multiple
    )
    arrays["impact_count"] = values
    named = tuple(
        names + (("impact_count",) if g else ()) for names, g in zip(imputed, guessed, strict=True)
    )
    return arrays, named
