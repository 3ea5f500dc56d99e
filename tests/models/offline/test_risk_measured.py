"""The measured-delta-V consistency check: its simulated measurements and its binding.

The check itself runs in ``aacn-triage fit-field`` (held out by crash, through
each fold's model); these tests hold its simulated measurements to the
measurement model they draw from, its document to the artifact it checks, and
the shipped artifact's check to the promises it reports.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from models.field.measurement import LONGITUDINAL_RATIO, SD_KMH, SIDE_RATIO
from models.field.risk_features import MAX_DELTA_V_KMH
from models.field.risk_model import default_artifact_path
from models.offline.field.risk_measured import (
    CHECK_FILE,
    check_document,
    load_check,
    simulated_measured_kmh,
    write_check,
)
from models.offline.field.risk_report import default_report_dir

DOC = json.loads(default_artifact_path().read_text(encoding="utf-8"))


def _draw(reading: str, pdof: float, n: int = 200_000) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    rec = rng.uniform(15.0, 60.0, n)
    return rec, simulated_measured_kmh(reading, rec, np.full(n, pdof), rng)


@pytest.mark.parametrize(("pdof", "ratio"), [(0.0, LONGITUDINAL_RATIO), (90.0, SIDE_RATIO)])
def test_without_scatter_a_measurement_is_the_reconstruction_over_its_directions_ratio(
    pdof: float, ratio: float
) -> None:
    rec, m = _draw("no_scatter", pdof)
    assert np.mean(m / rec) == pytest.approx(1.0 / ratio, rel=2e-3)
    # only the measurement's own tolerance (5 % SD) remains
    assert np.std(ratio * m / rec) == pytest.approx(0.05, rel=0.05)


def test_a_noisier_measurement_scatters_around_the_reconstruction_by_the_sources_sd() -> None:
    rec, m = _draw("measurement_noisier", 0.0)
    diff = rec - LONGITUDINAL_RATIO * m
    assert np.mean(diff) == pytest.approx(0.0, abs=0.1)
    assert np.std(diff) == pytest.approx(SD_KMH, rel=0.02)
    # more spread than the reconstruction it was drawn from, on the same scale
    assert np.std(LONGITUDINAL_RATIO * m) > np.std(rec)


def test_simulated_measurements_stay_in_the_features_range() -> None:
    rng = np.random.default_rng(0)
    rec = np.array([0.5, 1.0, 190.0, 200.0])
    for reading in ("no_scatter", "measurement_noisier"):
        m = simulated_measured_kmh(reading, rec, np.zeros(4), rng)
        assert np.all((m >= 1.0) & (m <= MAX_DELTA_V_KMH))
    with pytest.raises(ValueError, match="unknown reading"):
        simulated_measured_kmh("guess", rec, np.zeros(4), rng)


def test_a_check_is_bound_to_the_artifact_it_checks(tmp_path: Path) -> None:
    path = write_check(check_document(DOC, {"x": 1.0}), tmp_path / CHECK_FILE)
    assert load_check(DOC, path) is not None
    other = {**DOC, "content_sha256": "0" * 64}
    assert load_check(other, path) is None
    assert load_check(DOC, tmp_path / "absent.json") is None


def test_the_shipped_artifacts_check_keeps_its_promises_for_a_measured_delta_v() -> None:
    """The sources' reading (no scatter added to a precise measurement): weighted P/O within
    0.8-1.25 and the default point's 85 % for adults with the age sent, at the served
    threshold; the noisier-measurement bound costs sensitivity at the served threshold."""
    check = load_check(DOC, default_report_dir() / CHECK_FILE)
    assert check is not None, "the shipped artifact's measured check is missing"
    fig = check["figures"]
    adults = fig["no_scatter"]["age_sent"]["adults"]
    assert 0.8 <= adults["p_over_o_weighted"] <= 1.25
    served = fig["no_scatter"]["operating_points"]["sens85"]["adult"]
    assert served["at_served"]["sensitivity"] >= 0.85
    assert served["served_threshold"] == pytest.approx(
        DOC["operating_points"]["sens85"]["thresholds_by_knowledge"]["adult"]
    )
    bound = fig["measurement_noisier"]["operating_points"]["sens85"]["adult"]
    assert bound["at_served"]["sensitivity"] < served["at_served"]["sensitivity"]
