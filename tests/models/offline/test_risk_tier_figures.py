"""The model card's risk-tier figures (written by the next ``fit-field``), on synthetic data
whose answers are counted by hand."""

from __future__ import annotations

import numpy as np
import pytest

from models.offline.field.risk_metrics import crash_resamples, threshold_figures, tier_figures
from models.offline.field.risk_report import tier_lines

#: Ten occupants: held-out probability, ISS 15+, survey weight, flagged by the operating
#: point (held out, so not simply p >= a threshold: the 9th is flagged at 0.015).
P = np.array([0.60, 0.30, 0.25, 0.10, 0.05, 0.03, 0.02, 0.015, 0.01, 0.001])
Y = np.array([1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0])
W = np.array([1.0, 2.0, 1.0, 4.0, 1.0, 1.0, 2.0, 1.0, 3.0, 10.0])
FLAGGED = np.array([True, True, True, True, True, True, True, True, False, False])


def test_each_tier_is_counted_as_served() -> None:
    t = tier_figures(Y, P, FLAGGED, W, 0.20, None)
    high, moderate, none = t["high"], t["moderate"], t["none"]
    # high: p >= 0.20 and flagged -> occupants 0, 1, 2 (two ISS 15+)
    assert (high["n"], high["positives"]) == (3, 2)
    # moderate: flagged below 0.20 -> 3..7 (3 and 6 ISS 15+); none: 8, 9 (8 ISS 15+)
    assert (moderate["n"], moderate["positives"]) == (5, 2)
    assert (none["n"], none["positives"]) == (2, 1)
    # five ISS 15+ occupants, weights 1 + 2 + 4 + 2 + 3 = 12
    assert high["sensitivity"] == pytest.approx(2 / 5)
    assert high["sensitivity_weighted"] == pytest.approx(3 / 12)
    assert moderate["sensitivity"] == pytest.approx(2 / 5)
    assert moderate["sensitivity_weighted"] == pytest.approx(6 / 12)
    assert none["sensitivity_weighted"] == pytest.approx(3 / 12)
    assert moderate["sensitivity_at_or_above"] == pytest.approx(4 / 5)
    assert moderate["sensitivity_at_or_above_weighted"] == pytest.approx(9 / 12)
    assert none["sensitivity_at_or_above"] == 1.0
    # PPV: the tier's share with ISS 15+, sample and weighted (high: weights 1, 2, 1)
    assert high["ppv"] == pytest.approx(2 / 3)
    assert high["ppv_weighted"] == pytest.approx(3 / 4)
    assert moderate["ppv_weighted"] == pytest.approx(6 / 9)
    # the tier's share of all occupants (total weight 26)
    assert high["flagged"] == pytest.approx(0.3)
    assert high["flagged_weighted"] == pytest.approx(4 / 26)
    assert none["flagged_weighted"] == pytest.approx(13 / 26)
    for key in ("sensitivity", "sensitivity_weighted", "flagged", "flagged_weighted"):
        assert sum(t[tier][key] for tier in t) == pytest.approx(1.0), key


def test_a_high_probability_not_flagged_is_not_high() -> None:
    """As served (models.tiers.tier_of): high needs the operating point's flag too."""
    flagged = FLAGGED.copy()
    flagged[2] = False  # p = 0.25, not flagged held out
    t = tier_figures(Y, P, flagged, W, 0.20, None)
    assert (t["high"]["n"], t["none"]["n"]) == (2, 3)


def test_the_intervals_hold_the_point_figures() -> None:
    rng = np.random.default_rng(3)
    n = 4000
    p = rng.beta(0.5, 8.0, n)
    y = (rng.random(n) < p).astype(np.float64)
    w = rng.uniform(1.0, 50.0, n)
    flagged = p >= np.quantile(p, 0.7)
    crash = np.arange(n) // 2
    t = tier_figures(y, p, flagged, w, 0.20, crash_resamples(crash, 200, 1))
    for tier in ("high", "moderate", "none"):
        for key in ("sensitivity", "ppv", "ppv_weighted", "flagged_weighted"):
            low, high = t[tier][f"{key}_ci95"]
            assert low <= t[tier][key] <= high, (tier, key)


def test_the_vehicle_at_the_cdc_threshold() -> None:
    v = threshold_figures(Y, P, W, 0.20, None)
    # flagged: 0, 1, 2; ISS 15+ vehicles 0, 1, 3, 6, 8; without 2, 4, 5, 7, 9
    assert v["sensitivity"] == pytest.approx(2 / 5)
    assert v["specificity"] == pytest.approx(4 / 5)
    assert v["specificity_weighted"] == pytest.approx(13 / 14)
    assert v["ppv"] == pytest.approx(2 / 3)
    assert v["flagged_weighted"] == pytest.approx(4 / 26)


def test_the_card_shows_each_tier_and_isps_published_point() -> None:
    crash = np.arange(P.size)
    doc = {
        "tiers": {
            "operating_point": "sens85",
            "high_threshold": 0.2,
            "heldout": tier_figures(Y, P, FLAGGED, W, 0.20, crash_resamples(crash, 20, 2)),
            "vehicle_at_high_threshold": threshold_figures(Y, P, W, 0.20, None),
        }
    }
    text = "\n".join(tier_lines(doc))
    for tier in ("`high`", "`moderate`", "`none`"):
        assert tier in text
    assert "| `high` | P >= the high-risk threshold (and flagged) | 3 (2) | 40.0 %" in text
    assert "75.0 %" in text  # the high tier's weighted PPV
    assert "| OnStar ISP (published) | 40.0 % | 98.0 % |" in text
    assert "80.0 %" in text  # the vehicle's specificity at 0.20
    assert tier_lines({}) == []
