"""HIC: closed forms, scaling, shift invariance, and a brute-force reference."""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from numba import njit

from models.injury.criteria import HicResult, _hic_search, _hic_window_from, _inv_cubes, hic


def _brute_force_hic(a: np.ndarray, fs: float, max_window_ms: float) -> float:
    """O(n^2) reference: every (i, j) pair, trapezoidal integral, plain ** 2.5."""
    dt = 1.0 / fs
    cum = np.concatenate(([0.0], np.cumsum((a[1:] + a[:-1]) * 0.5 * dt)))
    n = a.size
    i, j = np.triu_indices(n, k=1)
    dur = (j - i) * dt
    area = cum[j] - cum[i]
    ok = (dur <= max_window_ms * 1e-3 * (1 + 1e-9)) & (area > 0)
    if not ok.any():
        return 0.0
    vals = dur[ok] * (area[ok] / dur[ok]) ** 2.5
    return float(vals.max())


def _rect(
    amplitude: float, periods: int, fs: float, lead: int = 100, tail: int = 100
) -> np.ndarray:
    """Rectangular pulse: `periods + 1` samples at `amplitude`, lasting periods / fs s."""
    return np.concatenate((np.zeros(lead), np.full(periods + 1, amplitude), np.zeros(tail)))


@njit
def _hic_search_exhaustive(
    cum: npt.NDArray[np.float64], dt: float, nmax: int
) -> tuple[float, int, int]:
    """The reference of ``_hic_search``: every start evaluated."""
    n = cum.shape[0]
    inv_t3 = _inv_cubes(dt, nmax)
    best2 = 0.0
    bi = 0
    bj = 0
    for i in range(n - 1):
        local, lj = _hic_window_from(cum, inv_t3, i, nmax)
        if local > best2:
            best2 = local
            bi = i
            bj = lj
    return best2, bi, bj


@pytest.mark.parametrize(("amplitude", "duration_ms"), [(60.0, 5.0), (80.0, 10.0), (150.0, 2.0)])
def test_rectangular_pulse_shorter_than_window(amplitude: float, duration_ms: float) -> None:
    fs = 10_000.0
    periods = round(duration_ms * 1e-3 * fs)
    r = hic(_rect(amplitude, periods, fs, lead=100), fs, 15.0)
    assert r.value == pytest.approx(amplitude**2.5 * duration_ms * 1e-3, rel=1e-12)
    assert r.t1_s == pytest.approx(100 / fs)
    assert r.t2_s - r.t1_s == pytest.approx(duration_ms * 1e-3)


@pytest.mark.parametrize(("window_ms", "duration_ms"), [(15.0, 40.0), (36.0, 50.0), (15.0, 15.0)])
def test_rectangular_pulse_longer_than_or_equal_to_window(
    window_ms: float, duration_ms: float
) -> None:
    fs = 10_000.0
    a = 70.0
    periods = round(duration_ms * 1e-3 * fs)
    r = hic(_rect(a, periods, fs), fs, window_ms)
    # HIC_w = min(T, w) A^2.5; a window of exactly w counts ("not more than").
    assert r.value == pytest.approx(min(duration_ms, window_ms) * 1e-3 * a**2.5, rel=1e-12)
    assert r.t2_s - r.t1_s == pytest.approx(min(duration_ms, window_ms) * 1e-3)


def test_window_of_exactly_the_limit_counts() -> None:
    # 15.0 ms at 10 kHz is 150 periods; 149 would lose 1/150 of the value.
    fs = 10_000.0
    r = hic(_rect(100.0, 150, fs), fs, 15.0)
    assert r.value == pytest.approx(100.0**2.5 * 0.015, rel=1e-12)


def test_widest_window_is_not_always_the_maximum() -> None:
    # A short spike on a low plateau: the best window is short, not 36 ms wide.
    fs = 10_000.0
    a = np.full(1000, 10.0)
    a[400:420] = 200.0
    r = hic(a, fs, 36.0)
    assert r.t2_s - r.t1_s < 0.005
    assert r.value == pytest.approx(_brute_force_hic(a, fs, 36.0), rel=1e-10)
    assert r.value > 0.036 * 10.0**2.5 * 10


@pytest.mark.parametrize("k", [0.5, 2.0, 3.7])
def test_scaling_law(k: float) -> None:
    fs = 10_000.0
    t = np.arange(0, 0.12, 1 / fs)
    a = 60.0 * np.sin(np.pi * t / 0.12) ** 2 + 20.0 * np.exp(-(((t - 0.05) / 0.003) ** 2))
    assert hic(k * a, fs).value == pytest.approx(k**2.5 * hic(a, fs).value, rel=1e-10)


def test_time_shift_changes_nothing_but_the_window() -> None:
    fs = 20_000.0
    t = np.arange(0, 0.1, 1 / fs)
    a = 80.0 * np.exp(-(((t - 0.04) / 0.006) ** 2))
    shift = 137
    r0 = hic(a, fs)
    r1 = hic(np.concatenate((np.zeros(shift), a)), fs)
    assert r1.value == pytest.approx(r0.value, rel=1e-10)
    assert r1.t1_s == pytest.approx(r0.t1_s + shift / fs, abs=1e-12)
    assert r1.t2_s == pytest.approx(r0.t2_s + shift / fs, abs=1e-12)


def test_window_longer_than_the_record() -> None:
    fs = 10_000.0
    a = _rect(50.0, 20, fs, lead=3, tail=3)
    r = hic(a, fs, max_window_ms=1e9)
    assert r.value == pytest.approx(_brute_force_hic(a, fs, 1e9), rel=1e-12)


def test_trivial_signals_give_zero() -> None:
    assert hic(np.zeros(100), 10_000.0) == HicResult(0.0, 0.0, 0.0)
    assert hic([5.0], 10_000.0) == HicResult(0.0, 0.0, 0.0)
    assert hic(-np.ones(50), 10_000.0).value == 0.0
    # A window shorter than one sample period holds no pair of samples.
    assert hic(np.ones(50), 10_000.0, max_window_ms=0.05).value == 0.0


@pytest.mark.parametrize(
    ("args", "name"),
    [
        (([1.0, 2.0], 0.0), "`sample_rate_hz`"),
        (([1.0, 2.0], 10_000.0, -1.0), "`max_window_ms`"),
        (([1.0, float("inf")], 10_000.0), "`resultant_accel_g`"),
        ((np.ones((2, 3)), 10_000.0), "`resultant_accel_g`"),
    ],
)
def test_invalid_arguments(args: tuple[object, ...], name: str) -> None:
    with pytest.raises(ValueError, match=name):
        hic(*args)  # type: ignore[arg-type]


signals = arrays(
    np.float64,
    st.integers(min_value=2, max_value=60),
    elements=st.floats(min_value=0.0, max_value=300.0, allow_nan=False, allow_subnormal=False),
)


@settings(max_examples=200, deadline=None)
@given(
    a=signals,
    fs=st.sampled_from([1_000.0, 2_000.0, 5_000.0, 10_000.0]),
    window_ms=st.floats(min_value=0.5, max_value=40.0),
)
def test_matches_brute_force_reference(a: np.ndarray, fs: float, window_ms: float) -> None:
    r = hic(a, fs, window_ms)
    ref = _brute_force_hic(a, fs, window_ms)
    assert r.value == pytest.approx(ref, rel=1e-9, abs=1e-9)
    if r.value > 0:
        # The reported window reproduces the value and respects the limit.
        assert 0.0 <= r.t1_s < r.t2_s
        assert r.t2_s - r.t1_s <= window_ms * 1e-3 * (1 + 1e-9)
        i, j = round(r.t1_s * fs), round(r.t2_s * fs)
        seg = a[i : j + 1]
        area = float(np.sum((seg[1:] + seg[:-1]) * 0.5)) / fs
        dur = (j - i) / fs
        assert dur * (area / dur) ** 2.5 == pytest.approx(r.value, rel=1e-9)


@settings(max_examples=100, deadline=None)
@given(a=signals, k=st.floats(min_value=0.1, max_value=10.0))
def test_properties_scaling_and_window_monotonicity(a: np.ndarray, k: float) -> None:
    fs = 5_000.0
    h15 = hic(a, fs, 15.0).value
    assert hic(a * k, fs, 15.0).value == pytest.approx(k**2.5 * h15, rel=1e-9, abs=1e-9)
    assert hic(a, fs, 36.0).value >= h15 * (1 - 1e-12)
    assert h15 >= 0.0
    assert math.isfinite(h15)


def _cum(a: np.ndarray, dt: float) -> np.ndarray:
    cum = np.empty(a.size)
    cum[0] = 0.0
    np.cumsum(0.5 * (a[1:] + a[:-1]) * dt, out=cum[1:])
    return cum


@pytest.mark.parametrize("seed", range(6))
def test_pruned_search_is_the_exhaustive_search_bit_for_bit(seed: int) -> None:
    """Skipping starts that cannot win changes neither the value nor the window."""
    rng = np.random.default_rng(seed)
    t = np.arange(2500)
    shapes = [
        rng.normal(size=t.size),  # ringing around zero
        np.abs(rng.normal(size=t.size)) * 50.0,  # all positive, no clear peak
        80.0 * np.exp(-0.5 * ((t - rng.uniform(0, 2500)) / rng.uniform(5, 300)) ** 2)
        + rng.normal(scale=2.0, size=t.size),  # a head pulse with noise
        np.where(t % 600 < 40, 90.0, -5.0),  # equal rectangular pulses: ties
        np.full(t.size, -1.0),  # no positive window
        np.zeros(t.size),
    ]
    for a in shapes:
        for nmax in (1, 2, 150, 360, 2499):
            cum = _cum(a, 1e-4)
            assert _hic_search(cum, 1e-4, nmax) == _hic_search_exhaustive(cum, 1e-4, nmax)


@settings(max_examples=60, deadline=None)
@given(
    a=arrays(np.float64, st.integers(2, 400), elements=st.floats(-200.0, 400.0)),
    nmax=st.integers(1, 120),
)
def test_pruned_search_equals_exhaustive_on_any_signal(a: np.ndarray, nmax: int) -> None:
    cum = _cum(a, 1e-3)
    n = min(nmax, a.size - 1)
    assert _hic_search(cum, 1e-3, n) == _hic_search_exhaustive(cum, 1e-3, n)
