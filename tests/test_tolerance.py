"""The comparison helpers of tests/tolerance.py accept rounding noise and still fail
on a real change (the tests that use them would otherwise be unable to fail)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.tolerance import (
    LPM_RTOL,
    RERUN_RTOL,
    assert_lpm_close,
    assert_printed_numbers_close,
    assert_tree_close,
)

STORED = {
    "n": 600,
    "name": "rear",
    "ok": True,
    "median": 0.009374192428150829,
    "quartiles": [0.01, 0.02, float("nan")],
}


def _ulps(x: float, k: int) -> float:
    for _ in range(k):
        x = math.nextafter(x, math.inf)
    return x


def test_tree_accepts_last_bit_differences() -> None:
    """The issue's own pair: 0.009374192428152635 recomputed, ...150829 stored."""
    quartiles = [_ulps(0.01, 3), 0.02, math.nan]
    fresh = {**STORED, "median": 0.009374192428152635, "quartiles": quartiles}
    assert_tree_close(fresh, STORED, rtol=RERUN_RTOL)


@pytest.mark.parametrize(
    "change",
    [
        {"median": 0.009374192428150829 * (1 + 1e-8)},
        {"n": 599},
        {"name": "front"},
        {"ok": False},
        {"quartiles": [0.01, 0.02]},
        {"quartiles": [0.01, 0.02, 0.03]},
        {"extra": 1.0},
    ],
)
def test_tree_fails_on_a_real_change(change: dict[str, object]) -> None:
    with pytest.raises(AssertionError):
        assert_tree_close({**STORED, **change}, STORED, rtol=RERUN_RTOL)


def test_lpm_outputs_allow_hinge_amplification_only() -> None:
    stored = np.array([[2.0864148891967598, 64.677, np.nan], [1.0, 2.0, 3.0]])
    fresh = stored.copy()
    fresh[0, 0] = 2.0876034032898505  # measured: 5.7e-4 relative on another code path
    close, n = assert_lpm_close(fresh, stored)
    assert (close, n) == (4, 5)
    with pytest.raises(AssertionError):
        assert_lpm_close(stored * (1 + 2 * LPM_RTOL), stored)
    failed = stored.copy()
    failed[1, 1] = np.nan
    with pytest.raises(AssertionError):
        assert_lpm_close(failed, stored)


MD = "| 10-24 | 1,234 | 0.758 | +1.0 [-0.1, +1.7] |\nseed 20261203, 10,000 resamples\n"


def test_printed_numbers_allow_one_unit_in_the_last_digit() -> None:
    assert_printed_numbers_close(MD, MD)
    flipped = MD.replace("0.758", "0.759").replace("[-0.1,", "[+0.0,")
    assert_printed_numbers_close(flipped, MD)


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ("0.758", "0.760"),  # two units
        ("0.758", "0.7580"),  # another precision
        ("1,234", "1,235"),  # a count
        ("20261203", "20261204"),  # a seed
        ("10-24", "10-25"),  # a band limit
        ("resamples", "replicates"),  # a word
        ("+1.7] |\n", "+1.7] |\n\n"),  # a line
    ],
)
def test_printed_numbers_fail_on_a_real_change(old: str, new: str) -> None:
    assert old in MD
    with pytest.raises(AssertionError):
        assert_printed_numbers_close(MD.replace(old, new), MD)
