"""The NASS-CDS 1997-2014 occupant file's units and codes, checked from the data itself.

Issue 38 item 8: integer km/h, delta-V the length of its components, the
1997-2000 km/h bands matched by key to the police-outcome file, unknown
injuries empty (NASS codes them ISS 0), stature and mass medians, folds by
crash; and the delta-V slope against NHTSA's published MAIS 3+ curve in mph.
Each check is also shown to refuse the wrong reading (mph taken as km/h).
"""

from __future__ import annotations

import csv

import numpy as np
import pandas as pd
import pytest
import statsmodels.api as sm

from models.field.measurement import EARLY_ERA_SHARE, LATE_ERA_FIRST_YEAR
from models.offline.field.occupants import (
    ISS15_PLUS,
    REGIONS,
    crash_keys,
    fit_population,
    load_occupants,
    pdof_from_components_deg,
)
from models.offline.field.published import (
    NHTSA_ALL,
    NHTSA_LOGIT_TOLERANCE,
    NHTSA_MAIS3_SLOPE_PER_MPH,
    SLOPE_RATIO_TOLERANCE,
)
from models.offline.paths import DATA_DIR
from models.units import KM_PER_MILE

POLICE_CSV = DATA_DIR / "nass-cds-1997-2000.csv"

#: The police file's km/h bands: label, lower edge (inclusive), upper edge (exclusive).
BANDS_KMH: tuple[tuple[str, float, float], ...] = (
    ("1-9km/h", 0.0, 10.0),
    ("10-24", 10.0, 25.0),
    ("25-39", 25.0, 40.0),
    ("40-54", 40.0, 55.0),
    ("55+", 55.0, float("inf")),
)


@pytest.fixture(scope="module")
def occupants() -> pd.DataFrame:
    return load_occupants()


@pytest.fixture(scope="module")
def vehicles(occupants: pd.DataFrame) -> pd.DataFrame:
    v = occupants.drop_duplicates(["year", "psu", "caseno", "vehno"])
    return v[v["delta_v_kmh"].notna()]


def _band(v_kmh: np.ndarray) -> np.ndarray:
    out = np.empty(v_kmh.shape, dtype=object)
    for label, lo, hi in BANDS_KMH:
        out[(v_kmh >= lo) & (v_kmh < hi)] = label
    return out


def test_delta_v_is_integer_km_h_using_every_integer(vehicles: pd.DataFrame) -> None:
    """NASS-CDS records whole km/h; mph converted to km/h would leave over a third of
    the integers 5-60 unused (1 mph = 1.609 km/h apart)."""
    dv = vehicles["delta_v_kmh"].to_numpy()
    assert np.all(dv == np.round(dv))
    assert set(range(5, 61)) <= set(dv.astype(int))
    as_mph_in_kmh = np.round(np.round(dv / KM_PER_MILE) * KM_PER_MILE)
    assert len(set(range(5, 61)) - set(as_mph_in_kmh.astype(int))) > 56 / 3


def test_delta_v_is_the_length_of_its_components(vehicles: pd.DataFrame) -> None:
    dv = vehicles["delta_v_kmh"].to_numpy()
    h = np.hypot(vehicles["delta_v_long_kmh"], vehicles["delta_v_lat_kmh"]).to_numpy()
    assert np.mean(np.abs(h - dv) <= 1.5) > 0.98
    # the direction of the components is the PDOF where the exterior file gives one
    pdof = vehicles["pdof1_deg"].to_numpy()
    known = ~np.isnan(pdof) & (dv >= 10)
    est = pdof_from_components_deg(
        vehicles["delta_v_long_kmh"].to_numpy(), vehicles["delta_v_lat_kmh"].to_numpy()
    )
    diff = np.abs((est[known] - pdof[known] + 180.0) % 360.0 - 180.0)
    assert np.median(diff) <= 5.0


def test_1997_2000_delta_v_falls_in_the_police_files_km_h_bands(
    vehicles: pd.DataFrame,
) -> None:
    """Matched by key (year, caseid = psu:caseno:vehno), the integer km/h of the new file
    lies in the police file's km/h band; read as mph (divided by 1.609) it does not."""
    with POLICE_CSV.open(newline="", encoding="utf-8") as fh:
        police = {(int(r["yearacc"]), r["caseid"]): r["dvcat"] for r in csv.DictReader(fh)}
    keys = zip(
        vehicles["year"], vehicles["psu"], vehicles["caseno"], vehicles["vehno"], strict=True
    )
    matched = [(i, police.get((int(y), f"{p}:{c}:{v}"))) for i, (y, p, c, v) in enumerate(keys)]
    idx = np.array([i for i, b in matched if b is not None])
    bands = np.array([b for _, b in matched if b is not None], dtype=object)
    assert idx.size > 8_000
    dv = vehicles["delta_v_kmh"].to_numpy()[idx]
    assert np.mean(_band(dv) == bands) > 0.99
    assert np.mean(_band(dv / KM_PER_MILE) == bands) < 0.7


def test_unknown_injuries_are_empty_not_zero(occupants: pd.DataFrame) -> None:
    iss = occupants["iss"]
    # an injured occupant of unknown severity (MAIS code 7) has no ISS, never 0
    assert iss[occupants["injured_severity_unknown"] == 1].isna().all()
    # the region columns are empty exactly where the ISS is
    for r in REGIONS:
        assert (occupants[f"max_ais_{r}"].isna() == iss.isna()).all(), r
    known = occupants[iss.notna() & occupants["delta_v_kmh"].notna()]
    assert len(known) == 57_002
    assert int((known["iss"] >= ISS15_PLUS).sum()) == 3_823
    # ISS 15 cannot occur (no sum of three squares of 1-5 is 15)
    assert not (iss == 15).any()
    sums = {a * a + b * b + c * c for a in range(6) for b in range(6) for c in range(6)}
    assert set(iss.dropna().unique()) <= sums | {75}
    # the worst region's AIS, squared, is part of the ISS (75 with an AIS 6)
    worst = known[[f"max_ais_{r}" for r in REGIONS]].max(axis=1).to_numpy()
    assert np.all(known["iss"].to_numpy() >= np.where(worst >= 6, 75, worst**2))


def test_stature_and_mass_are_cm_and_kg(occupants: pd.DataFrame) -> None:
    adults = occupants[occupants["age_years"] >= 16]
    assert 165 <= adults["stature_cm"].median() <= 180
    assert 65 <= adults["mass_kg"].median() <= 85


def test_occupants_of_a_crash_share_one_key(occupants: pd.DataFrame) -> None:
    keys = crash_keys(occupants)
    frame = occupants.assign(key=keys)
    per_key = frame.groupby("key")[["year", "psu", "caseno"]].nunique()
    assert (per_key == 1).all().all()
    assert keys.max() + 1 == len(occupants.drop_duplicates(["year", "psu", "caseno"]))


def test_the_delta_v_slope_in_mph_is_nhtsas(occupants: pd.DataFrame) -> None:
    """NHTSA's MAIS 3+ curve (NASS-CDS 2010-2015, weighted, mph) against the file's
    weighted univariate fit on 2010-2014: same slope within a factor sqrt(1.609),
    same logit at 25 mph within the units tolerance; mph read as km/h is refused."""
    pop = fit_population(occupants).rows
    s = pop[pop["year"] >= 2010]
    y = (s["mais"] >= 3).astype(float).to_numpy()

    def fit(v_mph: np.ndarray) -> np.ndarray:
        res = sm.GLM(
            y, sm.add_constant(v_mph), family=sm.families.Binomial(), freq_weights=s["ratwgt"]
        ).fit()
        return np.asarray(res.params)

    a, b = fit(s["delta_v_kmh"].to_numpy() / KM_PER_MILE)
    assert 1 / SLOPE_RATIO_TOLERANCE <= b / NHTSA_MAIS3_SLOPE_PER_MPH <= SLOPE_RATIO_TOLERANCE
    published = NHTSA_ALL.intercept + NHTSA_ALL.slope_per_mph * 25.0
    assert abs(a + b * 25.0 - published) <= NHTSA_LOGIT_TOLERANCE
    # the km/h numbers taken for mph (no conversion)
    _, b_wrong = fit(s["delta_v_kmh"].to_numpy())
    assert b_wrong / NHTSA_MAIS3_SLOPE_PER_MPH < 1 / SLOPE_RATIO_TOLERANCE


def test_the_fitted_population_is_named_and_counted(occupants: pd.DataFrame) -> None:
    pop = fit_population(occupants)
    rows = pop.rows
    assert len(rows) + sum(n for _, n in pop.removed) == len(occupants)
    assert rows["age_years"].notna().all()
    assert (rows["age_years"] < 16).sum() == 6172  # the children of the nine seats
    assert ((rows["age_years"] < 16) & (rows["iss"] >= 16)).sum() == 211
    assert set(rows["seat_row"]) == {1, 2, 3}
    assert set(rows["belt"]) == {"belted", "none", "child_seat"}
    # the measurement model's era shares are the fitted population's
    early = int((rows["year"] < LATE_ERA_FIRST_YEAR).sum())
    assert early == 35960
    assert early / len(rows) == pytest.approx(EARLY_ERA_SHARE, abs=5e-5)
    assert rows["iss"].notna().all()
    assert rows["delta_v_kmh"].notna().all()


def test_impact_events_are_whole_counts_of_the_vehicle(occupants: pd.DataFrame) -> None:
    """``n_events`` (feature set 2's impact count) counts a vehicle's harmful events:
    whole numbers from 1, the same for every occupant of a vehicle, and more of them
    go with more ISS 15+ (each further event is a further chance of injury)."""
    n = occupants["n_events"]
    assert n.notna().all()
    assert (n == n.round()).all()
    assert n.min() == 1
    per_vehicle = occupants.groupby(["year", "psu", "caseno", "vehno"])["n_events"].nunique()
    assert (per_vehicle == 1).all()
    known = occupants[occupants["iss"].notna() & (occupants["age_years"] >= 16)]
    rate = (known["iss"] >= ISS15_PLUS).groupby(known["n_events"].clip(1, 3)).mean()
    assert rate.is_monotonic_increasing, rate
