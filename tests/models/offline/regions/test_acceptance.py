"""Issue 39's acceptance from the data, and the near-side model against the published side test.

On the shared NASS-CDS 1997-2014 file, the share of occupants to whom the
occupant models report head/neck AIS 6 is no larger than the share with a real
AIS 5+ injury, mode by mode; at the IIHS side test's severity the near-side
model with side airbags stays near the published SID-IIs result.
"""

from __future__ import annotations

import pandas as pd
import pytest

from models.offline.regions.rows import outcome_frame
from models.offline.regions.sidecheck import PUBLISHED_AVEO, side_runs
from models.offline.regions.skill import MODES, ais_six_check, analysis_frame
from models.offline.regions.table import physics_table


@pytest.fixture(scope="module")
def frame() -> pd.DataFrame:
    return analysis_frame(physics_table(workers=1, progress=False), outcome_frame())


@pytest.mark.slow
def test_reported_ais_6_is_no_more_common_than_real_ais_5_mode_by_mode(
    frame: pd.DataFrame,
) -> None:
    rows = {r.mode: r for r in ais_six_check(frame, "reported_ais_head_neck")}
    assert set(rows) == {*MODES, "all"}
    for mode in MODES:
        r = rows[mode]
        assert r.n > 1000
        assert r.reported_ais6 <= r.real_mais5, mode
    # the cap is what holds it: the curves' own median level overstates it near side
    assert rows["near_side"].model_ais6 > rows["near_side"].real_mais5


@pytest.mark.slow
def test_the_models_ais_6_is_not_what_the_field_shows(frame: pd.DataFrame) -> None:
    """Of the occupants the curves put at AIS 6 (unsurvivable), most had no AIS 5+ injury."""
    row = next(r for r in ais_six_check(frame, "reported_ais_head_neck") if r.mode == "all")
    assert row.agree_mais5 < 0.5
    assert row.died < 0.5


def test_near_side_with_airbags_at_the_iihs_severity_is_near_the_published_test() -> None:
    runs = [
        r
        for r in side_runs()
        if r.body == "female_5th" and r.side_airbag and r.delta_v_kmh in (24.0, 28.8)
    ]
    assert len(runs) == 2
    for r in runs:
        # within a factor of two of the 2007 Aveo (SID-IIs 5F): one car, one test
        assert PUBLISHED_AVEO["hic15"] / 2 <= r.hic15 <= 2 * PUBLISHED_AVEO["hic15"]
        assert PUBLISHED_AVEO["deflection_mm"] / 2 <= r.deflection_mm <= 2 * 25.0
        # ... and its head/neck is not reported beyond AIS 1
        assert r.reported_ais <= 1
