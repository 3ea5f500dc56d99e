"""NASS-CDS 1997-2014 occupants: the file, its population filter, its outcomes.

The file (``data/nass-cds-1997-2014-occupants.csv.gz``, provenance beside it)
holds every NASS-CDS occupant record of 1997-2014. The field risk models are
fitted on the occupants a notification describes and a field outcome exists
for (:func:`fit_population`, each rule named in :data:`POPULATION_RULES`):

- delta-V reconstructed and the injuries known (ISS not empty: NASS codes
  unknown injuries ISS 0, the file leaves them empty);
- age known, children included (feature set 3 gives children their own
  terms, :mod:`models.field.risk_children`; until field model 3.3.0 the
  population was adults of 16 and older);
- a seat a notification can name: rows 1-3, left, middle or right (NASS seat
  codes 11-13, 21-23, 31-33 and the row's other positions with a side; rows
  4-5 and "other" are not in VEDS);
- restraint known: belted, none, or a child seat (NASS-CDS codes every child
  restraint alike); unknown belt use is integrated over at request time
  (:mod:`models.field.unknowns`), from the known;
- frontal airbag state known (deployed, not deployed, none).

Outcomes: ISS >= 16 (ISS 15 cannot occur, so this is ISS 15+), and per body
region ``max_ais_<region> >= level``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Final

import numpy as np
import pandas as pd

from models.arrays import FloatArray
from models.offline.paths import DATA_DIR

__all__ = [
    "OCCUPANTS_CSV",
    "POPULATION_RULES",
    "REGIONS",
    "ISS15_PLUS",
    "crash_keys",
    "fit_population",
    "load_occupants",
    "pdof_from_components_deg",
]

OCCUPANTS_CSV: Final[Path] = DATA_DIR / "nass-cds-1997-2014-occupants.csv.gz"

#: ISS 15+ is ISS >= 16 in NASS-CDS (ISS 15 cannot occur: no sum of three
#: squared AIS severities of 1-5 is 15).
ISS15_PLUS: Final[int] = 16

#: Body regions with a ``max_ais_<region>`` column (AIS 1990 region codes 1-8).
REGIONS: Final[tuple[str, ...]] = (
    "head",
    "face",
    "neck",
    "thorax",
    "abdomen",
    "spine",
    "upper_extremity",
    "lower_extremity",
)

#: Minimum age of an adult, years [R] (the occupant models and the MAIS
#: calibration file take 16 and older as adult; the field risk models' data
#: hold children too since 3.3.0).
ADULT_AGE_YEARS: Final[float] = 16.0

#: The filter rules in order, as the model card states them.
POPULATION_RULES: Final[tuple[tuple[str, str], ...]] = (
    ("known", "delta-V reconstructed and ISS known (unknown injuries are empty, not ISS 0)"),
    ("age", "age known (children included)"),
    ("seat", "seat rows 1-3 with a side (left, middle, right): the seats VEDS can name"),
    ("belt", "restraint known: belted, none or a child seat (unknown excluded)"),
    ("airbag", "frontal airbag state known (deployed, not deployed, none)"),
)


def load_occupants(path: Path | None = None) -> pd.DataFrame:
    """The whole file, every occupant record, as the file gives it.

    Raises
    ------
    ValueError
        A column the fit needs is missing (named), or delta-V is not whole km/h.
    """
    df = pd.read_csv(OCCUPANTS_CSV if path is None else path)
    needed = (
        "year psu caseno vehno occno stratum ratwgt age_years female stature_cm mass_kg "
        "seat_code seat_row seat_side belt frontal_airbag delta_v_kmh delta_v_long_kmh "
        "delta_v_lat_kmh rollover_quarter_turns n_events model_year iss"
    ).split() + [f"max_ais_{r}" for r in REGIONS]
    missing = [c for c in needed if c not in df.columns]
    if missing:
        raise ValueError(f"occupant file lacks the column(s) {', '.join(missing)}")
    dv = df["delta_v_kmh"].dropna().to_numpy()
    if not np.all(dv == np.round(dv)):
        raise ValueError("delta_v_kmh is not whole km/h: not the NASS-CDS km/h column")
    return df


def pdof_from_components_deg(long_kmh: FloatArray, lat_kmh: FloatArray) -> FloatArray:
    """Principal direction of force from the delta-V components, deg in [0, 360).

    The file's sign convention: longitudinal < 0 for a force from the front,
    lateral < 0 for a force from the right; PDOF is clockwise from straight
    ahead (0 front, 90 right), so ``pdof = atan2(-lat, -long)``.
    """
    out: FloatArray = np.degrees(np.arctan2(-np.asarray(lat_kmh), -np.asarray(long_kmh))) % 360.0
    return out


def crash_keys(df: pd.DataFrame) -> np.ndarray:
    """An integer id per crash (year, psu, caseno): the unit of every fold and resample."""
    codes, _ = pd.factorize(
        df["year"].astype(str) + ":" + df["psu"].astype(str) + ":" + df["caseno"].astype(str)
    )
    return np.asarray(codes)


@dataclass(frozen=True)
class Population:
    """The fitted population and how many rows each rule removed.

    Attributes
    ----------
    rows : pandas.DataFrame
        The occupants kept (index reset).
    removed : tuple of (str, int)
        Per rule of :data:`POPULATION_RULES`, rows removed.
    """

    rows: pd.DataFrame
    removed: tuple[tuple[str, int], ...]


def fit_population(df: pd.DataFrame) -> Population:
    """The occupants the field risk models are fitted and evaluated on (module docstring)."""
    masks = {
        "known": df["delta_v_kmh"].notna() & df["iss"].notna(),
        "age": df["age_years"].notna(),
        "seat": df["seat_row"].isin([1, 2, 3]) & df["seat_side"].isin(["left", "middle", "right"]),
        "belt": df["belt"].isin(["belted", "none", "child_seat"]),
        "airbag": df["frontal_airbag"].isin(["deployed", "not_deployed", "none"]),
    }
    keep = pd.Series(True, index=df.index)
    removed = []
    for name, _ in POPULATION_RULES:
        new = keep & masks[name]
        removed.append((name, int(keep.sum() - new.sum())))
        keep = new
    return Population(rows=df[keep].reset_index(drop=True), removed=tuple(removed))
