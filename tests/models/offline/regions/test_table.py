"""The physics table: the service's direct occupant-model run on field rows, cached."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.offline.regions.rows import OccupantRow, load_occupant_rows, occupant_notification
from models.offline.regions.table import (
    MEASURE_COLUMNS,
    _read_cache,
    physics_input,
    physics_table,
)
from models.risk_calibration import corrected_probability, zero_load_probability
from models.triage import load_engine_models, simulate_notification


@pytest.fixture(scope="module")
def sample() -> list[OccupantRow]:
    """Two occupants of each occupant model's mode and one out of coverage."""
    from models.impact_mode import classify_impact
    from models.notification import DriveSide

    picked: dict[str, list[OccupantRow]] = {}
    for r in load_occupant_rows():
        c = classify_impact(r.pdof_deg, r.seat, DriveSide.LEFT)
        name = c.mode.value if c.in_lpm_coverage else "none"
        if len(picked.setdefault(name, [])) < 2 and r.delta_v_kmh >= 25:
            picked[name].append(r)
        if len(picked) == 5 and all(len(v) == 2 for v in picked.values()):
            break
    return [r for v in picked.values() for r in v]


def test_the_table_is_the_service_direct_run(sample: list[OccupantRow], tmp_path: Path) -> None:
    table = physics_table(sample, out_dir=tmp_path, workers=1, progress=False)
    models = load_engine_models(use_surrogates=False, use_field=False, warm=False)
    assert sorted(set(table["mode"])) == sorted(m.value for m in ImpactMode)
    for row, rec in zip(sample, table.to_dict("records"), strict=True):
        _, sims, _ = simulate_notification(occupant_notification(row), models)
        result = sims[0].result
        assert rec["in_lpm"] == int(result is not None)
        if result is None:
            assert all(np.isnan(rec[m]) for m in MEASURE_COLUMNS)
            continue
        for m in MEASURE_COLUMNS:
            v = getattr(result.measures, m)
            assert (np.isnan(rec[m]) and v is None) or rec[m] == v
        assert result.assessment is not None
        assert rec["lpm_iss"] == result.assessment.iss
        assert rec["lpm_ais_head_neck"] == result.assessment.region_ais["head_neck"]
        assert rec["lpm_p_iss15"] == result.assessment.p_iss15
        p0 = zero_load_probability(result.measures, row.body, row.age_years, result.mode)
        assert rec["lpm_p_iss15_corrected"] == corrected_probability(result.assessment.p_iss15, p0)


def test_a_rerun_resumes_from_the_cache(sample: list[OccupantRow], tmp_path: Path) -> None:
    first = physics_table(sample[:4], out_dir=tmp_path, workers=1, progress=False)
    (cache,) = tmp_path.glob("runs-*.jsonl")
    lines = cache.read_text().splitlines()
    cache.write_text("\n".join(lines[:-1]) + "\n" + lines[-1][:10])  # an interrupted write
    again = physics_table(sample, out_dir=tmp_path, workers=1, progress=False)
    records = _read_cache(cache)
    assert set(records) == {physics_input(r).text() for r in sample}
    assert again.iloc[:4].equals(first)
