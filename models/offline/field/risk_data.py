"""The NASS-CDS occupant rows as the field risk models' inputs and outcomes.

:func:`risk_arrays` turns the fitted population's rows into the raw input
arrays that :func:`models.field.risk_impacts.design_columns_2` takes (the same
function the service builds its rows with), unknown inputs imputed by the
population's values (:func:`population_imputation`), as the service imputes
them. :func:`outcomes` gives the 0/1 outcomes: ISS 15+ and, per body region,
AIS 3+ (AIS 2+ where AIS 3+ is too rare to fit, :data:`MIN_REGION_POSITIVES`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
import pandas as pd

from models.arrays import FloatArray
from models.field.risk_features import RiskImputation
from models.field.risk_impacts import IMPACT_COUNT_CLAMP
from models.field.unknowns import AGE_BANDS_YEARS
from models.offline.field.occupants import ISS15_PLUS, REGIONS, pdof_from_components_deg

__all__ = [
    "MIN_REGION_POSITIVES",
    "Outcome",
    "outcomes",
    "impact_count_imputation",
    "population_imputation",
    "risk_arrays",
]

#: Fewest occupants with the outcome for a region's AIS 3+ to be fitted; below
#: it the region's outcome is AIS 2+ (named in the answer). [R] About 10
#: positives per candidate column of the design (some 30 columns).
MIN_REGION_POSITIVES: Final[int] = 300


@dataclass(frozen=True)
class Outcome:
    """A 0/1 outcome of the fitted population.

    Attributes
    ----------
    name : str
        ``iss15`` or ``region_<region>``.
    label : str
        ``ISS15+`` or e.g. ``head AIS3+``.
    ais_level : int or None
        The region's AIS threshold (3, or 2 where AIS 3+ is too rare).
    y : ndarray, shape (n,)
    """

    name: str
    label: str
    ais_level: int | None
    y: FloatArray


def population_imputation(rows: pd.DataFrame) -> RiskImputation:
    """Values for unknown inputs: the fitted population's medians and shares."""
    rolled = rows["rollover_quarter_turns"] > 0
    latest = rows["year"] == rows["year"].max()
    return RiskImputation(
        age_years=float(rows["age_years"].median()),
        female=float(rows["female"].mean()),
        stature_cm=float(rows["stature_cm"].median()),
        mass_kg=float(rows["mass_kg"].median()),
        quarter_turns=float(rows.loc[rolled, "rollover_quarter_turns"].median()),
        model_year=float(rows.loc[latest, "model_year"].median()),
        accident_year=float(rows["year"].max()),
    )


def impact_count_imputation(rows: pd.DataFrame) -> float:
    """The impact count taken for multiple impacts of unknown count: the median
    harmful events of the rows with two or more."""
    n = rows["n_events"].to_numpy(dtype=np.float64)
    return float(np.median(np.clip(n[n >= 2], *IMPACT_COUNT_CLAMP)))


def risk_arrays(rows: pd.DataFrame, imputation: RiskImputation) -> dict[str, object]:
    """Raw input arrays of the rows (unknowns imputed), each shape (n,).

    The direction of the delta-V comes from its components (what a
    notification's pulse gives); rolled means at least one quarter turn
    (unknown quarter turns: not rolled); multiple impacts means two or more
    harmful events, and the impact count is their number (clamped as served).
    """
    imp = imputation
    qt = rows["rollover_quarter_turns"].fillna(0.0).to_numpy(dtype=np.float64)
    return {
        "delta_v_kmh": rows["delta_v_kmh"].to_numpy(dtype=np.float64),
        "pdof_deg": pdof_from_components_deg(
            rows["delta_v_long_kmh"].to_numpy(dtype=np.float64),
            rows["delta_v_lat_kmh"].to_numpy(dtype=np.float64),
        ),
        "seat_row": rows["seat_row"].to_numpy(dtype=np.float64),
        "seat_side": rows["seat_side"].astype(str).tolist(),
        "driver": (rows["role"] == "driver").to_numpy(dtype=np.float64),
        "belted": (rows["belt"] != "none").to_numpy(dtype=np.float64),  # a child seat restrains
        "restraint": rows["belt"].astype(str).tolist(),
        "airbag": rows["frontal_airbag"].astype(str).tolist(),
        "rollover": (qt > 0).astype(np.float64),
        "quarter_turns": qt,
        "multiple_impacts": (rows["n_events"] >= 2).to_numpy(dtype=np.float64),
        "impact_count": np.clip(rows["n_events"].to_numpy(dtype=np.float64), *IMPACT_COUNT_CLAMP),
        "age_years": rows["age_years"].to_numpy(dtype=np.float64),
        "female": rows["female"].fillna(imp.female).to_numpy(dtype=np.float64),
        "stature_cm": _by_age_band(rows, "stature_cm", imp.stature_cm),
        "mass_kg": _by_age_band(rows, "mass_kg", imp.mass_kg),
        "model_year": rows["model_year"].fillna(imp.model_year).to_numpy(dtype=np.float64),
        "accident_year": rows["year"].to_numpy(dtype=np.float64),
    }


def _by_age_band(rows: pd.DataFrame, column: str, default: float) -> FloatArray:
    """A body measure with unknowns taken as the median of the row's age band
    (:data:`models.field.unknowns.AGE_BANDS_YEARS`: a child's unknown stature
    is not an adult's), else `default`."""
    band = np.searchsorted(AGE_BANDS_YEARS, rows["age_years"].to_numpy(), side="right") - 1
    values = rows[column]
    fill = values.groupby(band).transform("median")
    out: FloatArray = values.fillna(fill).fillna(default).to_numpy(dtype=np.float64)
    return out


def outcomes(rows: pd.DataFrame) -> list[Outcome]:
    """ISS 15+ and each region's AIS 3+ (or 2+ where too rare), in that order."""
    out = [Outcome("iss15", "ISS15+", None, (rows["iss"] >= ISS15_PLUS).to_numpy(dtype=np.float64))]
    for region in REGIONS:
        ais = rows[f"max_ais_{region}"].to_numpy(dtype=np.float64)
        level = 3 if int((ais >= 3).sum()) >= MIN_REGION_POSITIVES else 2
        out.append(
            Outcome(
                f"region_{region}", f"{region} AIS{level}+", level, (ais >= level).astype(float)
            )
        )
    return out
