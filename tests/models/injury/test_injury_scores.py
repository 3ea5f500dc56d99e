"""ISS rules, exact P(ISS >= t) against brute force, distribution helpers."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from models.injury.scores import (
    ISS_REGIONS,
    ais_distribution_from_cumulative,
    ais_level,
    iss,
    iss_distribution,
    p_iss_at_least,
)


def _reference_iss(levels: dict[str, int]) -> int:
    values = list(levels.values())
    if 6 in values:
        return 75
    return sum(v * v for v in sorted(values, reverse=True)[:3])


def _brute_force_p(dists: dict[str, np.ndarray], threshold: float) -> float:
    names = list(dists)
    total = 0.0
    for combo in itertools.product(range(7), repeat=len(names)):
        p = 1.0
        for name, level in zip(names, combo, strict=True):
            p *= dists[name][level]
        if p and _reference_iss(dict(zip(names, combo, strict=True))) >= threshold:
            total += p
    return total


# ---------------------------------------------------------------- ISS rules


def test_published_example() -> None:
    # AIS 3, 2 and 1 in three regions -> ISS 14.
    assert iss({"head_neck": 3, "chest": 2, "extremities": 1}) == 14


def test_only_the_three_most_severe_regions_count() -> None:
    assert iss({"head_neck": 3, "chest": 3, "abdomen": 3, "extremities": 3}) == 27
    assert iss({"head_neck": 5, "face": 1, "chest": 4, "abdomen": 4, "external": 2}) == 57


def test_ties() -> None:
    assert iss({"head_neck": 4, "chest": 4}) == 32
    assert iss(dict.fromkeys(ISS_REGIONS, 2)) == 12


def test_any_ais_6_gives_75() -> None:
    assert iss({"chest": 6}) == 75
    assert iss({"face": 1, "abdomen": 6, "external": 0}) == 75
    assert iss({"head_neck": 5, "chest": 5, "abdomen": 5}) == 75  # maximum without AIS 6


def test_fewer_than_three_regions() -> None:
    assert iss({}) == 0
    assert iss({"chest": 4}) == 16
    assert iss({"chest": 3, "abdomen": 2}) == 13
    assert iss(dict.fromkeys(ISS_REGIONS, 0)) == 0


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ({"chest": 7}, "0..6"),
        ({"chest": -1}, "0..6"),
        ({"neck": 2}, "unknown ISS region"),
        ({"chest": 2.5}, "integer"),
    ],
)
def test_invalid_region_ais(bad: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        iss(bad)  # type: ignore[arg-type]


region_levels = st.dictionaries(
    st.sampled_from(ISS_REGIONS), st.integers(min_value=0, max_value=6), max_size=6
)


@settings(max_examples=300, deadline=None)
@given(levels=region_levels)
def test_iss_properties(levels: dict[str, int]) -> None:
    s = iss(levels)
    assert s == _reference_iss(levels)
    assert 0 <= s <= 75
    # Raising any region's AIS never lowers the ISS.
    for name in ISS_REGIONS:
        raised = dict(levels)
        raised[name] = min(6, raised.get(name, 0) + 1)
        assert iss(raised) >= s
    # Only the multiset of levels matters.
    shuffled = dict(zip(ISS_REGIONS, sorted(levels.values()), strict=False))
    assert iss(shuffled) == s


# ---------------------------------------------------------------- exact P(ISS >= t)


def test_degenerate_distributions_give_an_indicator() -> None:
    onehot = {name: np.eye(7)[lvl] for name, lvl in (("head_neck", 3), ("chest", 2), ("face", 1))}
    assert p_iss_at_least(onehot, 14) == 1.0
    assert p_iss_at_least(onehot, 15) == 0.0


def test_hand_computed_case() -> None:
    # Head AIS 4 w.p. 0.2 (else 0); chest AIS 3 w.p. 0.5 (else 0); abdomen AIS 3 w.p. 0.1.
    d = {
        "head_neck": [0.8, 0, 0, 0, 0.2, 0, 0],
        "chest": [0.5, 0, 0, 0.5, 0, 0, 0],
        "abdomen": [0.9, 0, 0, 0.1, 0, 0, 0],
    }
    # ISS >= 15 iff head AIS 4, or chest and abdomen both AIS 3 (9 + 9 = 18).
    expected = 0.2 + 0.8 * 0.5 * 0.1
    assert p_iss_at_least(d) == pytest.approx(expected)


def test_all_six_regions_against_brute_force() -> None:
    rng = np.random.default_rng(7)
    d = {name: rng.dirichlet(np.ones(7) * 0.7) for name in ISS_REGIONS[:5]}
    for t in (1, 9, 15, 16, 25, 50, 75):
        assert p_iss_at_least(d, t) == pytest.approx(_brute_force_p(d, t), abs=1e-12)
    dist = iss_distribution(d)
    assert sum(dist.values()) == pytest.approx(1.0)


distribution = (
    st.lists(st.floats(min_value=0.0, max_value=1.0, allow_nan=False), min_size=7, max_size=7)
    .filter(lambda w: sum(w) > 1e-3)
    .map(lambda w: np.asarray(w) / np.sum(w))
)


@settings(max_examples=60, deadline=None)
@given(
    dists=st.dictionaries(st.sampled_from(ISS_REGIONS), distribution, min_size=1, max_size=3),
    threshold=st.integers(min_value=0, max_value=76),
)
def test_p_iss_matches_brute_force(dists: dict[str, np.ndarray], threshold: int) -> None:
    assert p_iss_at_least(dists, threshold) == pytest.approx(
        _brute_force_p(dists, threshold), abs=1e-12
    )


def test_p_iss_validation() -> None:
    with pytest.raises(ValueError, match="sum to 1"):
        p_iss_at_least({"chest": [0.5, 0, 0, 0, 0, 0, 0]})
    with pytest.raises(ValueError, match="7 entries"):
        p_iss_at_least({"chest": [1.0, 0.0]})
    with pytest.raises(ValueError, match="unknown ISS region"):
        p_iss_at_least({"pelvis": [1, 0, 0, 0, 0, 0, 0]})
    with pytest.raises(ValueError, match="non-negative"):
        p_iss_at_least({"chest": [1.2, -0.2, 0, 0, 0, 0, 0]})


# ---------------------------------------------------------------- helpers


def test_distribution_from_cumulative_and_median_level() -> None:
    p = ais_distribution_from_cumulative([0.9, 0.7, 0.5, 0.2, 0.05, 0.0])
    np.testing.assert_allclose(p, [0.1, 0.2, 0.2, 0.3, 0.15, 0.05, 0.0], atol=1e-12)
    assert ais_level(p) == 3  # P(AIS >= 3) = 0.5 exactly reaches the median
    assert ais_level(p, threshold=0.15) == 4
    assert ais_level(np.eye(7)[0]) == 0
    with pytest.raises(ValueError, match="non-increasing"):
        ais_distribution_from_cumulative([0.1, 0.2, 0, 0, 0, 0])
