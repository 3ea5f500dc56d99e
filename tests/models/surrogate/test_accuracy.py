"""Surrogate vs direct LPM: held-out errors and coverage of the P(ISS >= 15) interval.

Both run on the tiny family of ``conftest.py`` built from the current LPM code.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.notification import Body
from models.offline.surrogate.build import ISS15_DECISION_PROBABILITY, lpm_outputs
from models.surrogate.evaluate import (
    _NORMALS,
    DEFAULT_POSTURE_SD_DEG,
    DEFAULT_SEAT_TRACK_SD_MM,
    SurrogateLibrary,
)
from models.surrogate.spec import P_RESOLUTION
from models.surrogate.store import read_artifact
from tests.models.surrogate.tiny import TINY_NAME, tiny_spec

#: Issue 5 "done when": median relative error of each measure and ISS15+ agreement.
MAX_MEDIAN_RELATIVE_ERROR = 0.05
MIN_DECISION_AGREEMENT = 0.97
#: Issue 5: the 95% interval must contain the Monte Carlo value in >= 90% of cases.
MIN_COVERAGE = 0.90


#: Measures whose median relative error misses the 5 % target on the tiny
#: 250-run family (the shipped families meet it: docs/surrogate/REPORT.md):
#: HIC15 and Nij have kinks in posture, seat track and duration (contact
#: onset, HIC window switches, the Nij load case switching) that a sparse
#: polynomial on 250 runs does not resolve; they are held to a regression
#: bound here.
ROUGH_MEASURES = ("hic15", "nij")
#: Regression bound for those, median relative error.
ROUGH_MAX_MEDIAN_RELATIVE_ERROR = 0.20


def _heldout_errors(directory: Path) -> tuple[dict[str, float], float]:
    lib = SurrogateLibrary.load(directory, require_all=False)
    fam = lib.family(ImpactMode.FRONTAL, Body.MALE_50TH, True, True)
    arrays, _ = read_artifact(directory / f"{TINY_NAME}.npz")
    x, y = arrays["heldout_x"], arrays["heldout_y"]  # uniform random in the domain
    assert x.shape[0] == 100
    ok = np.all(np.isfinite(y), axis=1)
    assert ok.mean() > 0.99
    pred = fam.predict(x[ok])
    y = y[ok]
    errors = {}
    for k, name in enumerate(fam.outputs):
        if name not in ("p_iss15", "iss"):
            rel = np.abs(pred[:, k] - y[:, k]) / np.maximum(np.abs(y[:, k]), 1e-12)
            errors[name] = float(np.median(rel))
    k = fam.outputs.index("p_iss15")
    thr = ISS15_DECISION_PROBABILITY
    agreement = float(np.mean((pred[:, k] >= thr) == (y[:, k] >= thr)))
    return errors, agreement


def test_heldout_points_against_direct_lpm(tiny_library_dir: Path) -> None:
    errors, agreement = _heldout_errors(tiny_library_dir)
    assert agreement > MIN_DECISION_AGREEMENT, agreement
    for name, err in errors.items():
        bound = (
            ROUGH_MAX_MEDIAN_RELATIVE_ERROR if name in ROUGH_MEASURES else MAX_MEDIAN_RELATIVE_ERROR
        )
        assert err < bound, (name, errors)


@pytest.mark.xfail(
    reason="the tiny 250-run family misses 5 % on HIC15 and Nij (by design: a test-sized"
    " build); the shipped 1000-2000-run families meet it, see"
    " tests/surrogate/test_shipped.py::test_shipped_heldout_median_per_family_under_target",
    strict=True,
)
def test_heldout_hic_nij_within_five_percent(tiny_library_dir: Path) -> None:
    errors, _ = _heldout_errors(tiny_library_dir)
    assert all(errors[n] < MAX_MEDIAN_RELATIVE_ERROR for n in ROUGH_MEASURES), errors


#: Test cases (delta-V km/h, |angle| deg, posture deg, seat track mm, duration ms):
#: spread over the tiny family's domain.
_CASES = [
    (41.0, 0.0, 5.8, 0.0, 90.0),
    (45.0, 12.0, 15.0, -60.0, 70.0),
    (48.0, 25.0, 2.0, 80.0, 110.0),
    (50.0, 5.0, 20.0, 30.0, 50.0),
    (52.0, 28.0, 10.0, -100.0, 130.0),
    (55.0, 8.0, 24.0, 110.0, 60.0),
    (57.0, 18.0, 5.8, -20.0, 140.0),
    (59.0, 3.0, 12.0, 60.0, 45.0),
    (44.0, 20.0, 0.5, -115.0, 100.0),
    (53.0, 15.0, 8.0, 0.0, 80.0),
]


@pytest.mark.slow
def test_p_iss15_interval_covers_monte_carlo(tiny_library_dir: Path) -> None:
    """The known input distribution: the default Gaussian sensor errors around
    each case's readings (clipped to the domain), the other inputs fixed. The
    Monte Carlo value is the mean P(ISS >= 15) of direct LPM runs at the sensor
    sample points."""
    lib = SurrogateLibrary.load(tiny_library_dir, require_all=False)
    fam = lib.family(ImpactMode.FRONTAL, Body.MALE_50TH, True, True)
    spec = tiny_spec()
    hits = []
    for dv, ang, post, seat, dur in _CASES:
        r = fam.propagate(
            delta_v_kmh=dv, angle_deg=ang, posture_deg=post, seat_track_mm=seat, duration_ms=dur
        )
        n = _NORMALS.shape[0]
        x = np.tile([dv, ang, post, seat, dur], (n, 1))
        x[:, 2] = np.clip(post + DEFAULT_POSTURE_SD_DEG * _NORMALS[:, 0], 0.0, 25.0)
        x[:, 3] = np.clip(seat + DEFAULT_SEAT_TRACK_SD_MM * _NORMALS[:, 1], -120.0, 120.0)
        y, status = lpm_outputs(spec, x)
        assert np.all(status >= 0)
        mc = float(np.mean(y[:, spec.outputs.index("p_iss15")]))
        lo, hi = r.p_iss15_ci95
        hits.append(lo - P_RESOLUTION <= mc <= hi + P_RESOLUTION)
    assert np.mean(hits) >= MIN_COVERAGE, hits
