"""The NASS-CDS 1997-2014 occupant file: its units from the data, and the usable rows."""

from __future__ import annotations

import hashlib
import math
import re

import numpy as np
import pandas as pd
import pytest

from models.notification import AirbagState, Body, Seat
from models.offline.paths import DATA_DIR
from models.offline.regions.rows import (
    MIN_AGE_YEARS,
    OCCUPANTS_CSV,
    load_occupant_frame,
    load_occupant_rows,
    occupant_notification,
    outcome_frame,
    usable_mask,
)
from models.pulse import pdof_from_delta_v

PROVENANCE = DATA_DIR / "PROVENANCE-nass-cds-1997-2014-occupants.md"


@pytest.fixture(scope="module")
def frame() -> pd.DataFrame:
    return load_occupant_frame()


def test_the_shipped_copy_is_the_one_its_provenance_names() -> None:
    digest = hashlib.sha256(OCCUPANTS_CSV.read_bytes()).hexdigest()
    m = re.search(r"sha256 \(compressed file\) \| `([0-9a-f]{64})`", PROVENANCE.read_text())
    assert m is not None
    assert m.group(1) == digest


def test_delta_v_is_integer_km_h_using_every_integer_of_5_to_60(frame: pd.DataFrame) -> None:
    dv = frame["delta_v_kmh"].dropna().to_numpy()
    assert np.all(dv == np.round(dv))
    used = set(dv.astype(int).tolist())
    assert set(range(5, 61)) <= used
    # km/h from mph (x 1.609344, rounded) would leave over a third of them unused
    from_mph = {round(v * 1.609344) for v in range(3, 38)}
    assert len(set(range(5, 61)) - from_mph) > 56 / 3


def test_delta_v_is_the_length_of_its_components(frame: pd.DataFrame) -> None:
    sub = frame.dropna(subset=["delta_v_kmh", "delta_v_long_kmh", "delta_v_lat_kmh"])
    length = np.hypot(sub["delta_v_long_kmh"], sub["delta_v_lat_kmh"])
    assert np.mean(np.abs(length - sub["delta_v_kmh"]) <= 1.5) > 0.98


def test_stature_and_mass_are_cm_and_kg(frame: pd.DataFrame) -> None:
    adults = frame[frame["age_years"] >= 18]
    assert 165 <= adults["stature_cm"].median() <= 175
    assert 68 <= adults["mass_kg"].median() <= 80


def test_the_pdof_of_the_components_agrees_with_the_recorded_pdof(frame: pd.DataFrame) -> None:
    """The stand-in for the missing PDOF (2005) points the way NASS's own does."""
    sub = frame.dropna(subset=["pdof1_deg", "delta_v_long_kmh", "delta_v_lat_kmh"])
    sub = sub[(sub["delta_v_kmh"] >= 10) & (sub["pdof1_deg"] <= 360)]
    comp = np.array(
        [
            pdof_from_delta_v(lo, la)
            for lo, la in zip(sub["delta_v_long_kmh"], sub["delta_v_lat_kmh"], strict=True)
        ]
    )
    diff = np.abs((comp - sub["pdof1_deg"].to_numpy() + 180.0) % 360.0 - 180.0)
    assert np.mean(diff <= 10.0) > 0.95


def test_usable_rows_follow_the_rules(frame: pd.DataFrame) -> None:
    rows = load_occupant_rows()
    assert len(rows) == int(usable_mask(frame).sum())
    assert 45_000 < len(rows) < 55_000
    assert all(r.age_years >= MIN_AGE_YEARS for r in rows)
    # the front outboard and second-row seats (the ones these rows take); the wire's
    # front middle and third-row seats (issue 38) need not be among them
    five = {Seat.DRIVER, Seat.FRONT_PASSENGER, Seat.REAR_LEFT, Seat.REAR_MIDDLE, Seat.REAR_RIGHT}
    assert five <= {r.seat for r in rows} <= set(Seat)
    assert all(0.0 <= r.pdof_deg < 360.0 and r.delta_v_kmh > 0 for r in rows)
    assert len({r.key for r in rows}) == len(rows)
    outcomes = outcome_frame()
    assert list(zip(outcomes["year"], outcomes["psu"], outcomes["caseno"], strict=True))[:50] == [
        r.key[:3] for r in rows[:50]
    ]
    assert outcomes["iss"].notna().all()


def test_a_row_becomes_the_notification_the_service_reads() -> None:
    row = next(
        r
        for r in load_occupant_rows()
        if r.stature_cm is not None
        and r.stature_cm < 155
        and r.mass_kg is not None
        and r.mass_kg < 52
    )
    n = occupant_notification(row, side_airbag=AirbagState.DEPLOYED)
    occ = n.occupants[0]
    assert occ.body is Body.FEMALE_5TH
    assert occ.side_airbag is AirbagState.DEPLOYED
    assert not occ.posture_sensed
    assert n.event_id == ":".join(str(k) for k in row.key)
    assert math.isclose(n.pulse.delta_v_kmh, row.delta_v_kmh)  # type: ignore[union-attr]
