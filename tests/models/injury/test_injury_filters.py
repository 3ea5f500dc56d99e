"""CFC filter: coefficients, DC gain, -3 dB point, zero phase, padding, validation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.signal import filtfilt, freqz, lfilter_zi

from models.injury.filters import (
    ISO_6487_DESIGN_FACTOR,
    SAE_J211_DESIGN_FACTOR,
    _steady_state,
    cfc_coefficients,
    cfc_filter,
    cfc_filter_rows,
    forward_backward,
)

CLASSES = (60, 180, 600, 1000)


def _fb_gain(cfc: int, fs: float, freqs: np.ndarray, standard: str = "sae_j211") -> np.ndarray:
    """Magnitude of the forward-backward filter: |H|^2 of one pass."""
    b, a = cfc_coefficients(fs, cfc, standard=standard)  # type: ignore[arg-type]
    _, h = freqz(b, a, worN=freqs, fs=fs)
    return np.abs(h) ** 2


def test_coefficients_follow_the_j211_formula() -> None:
    fs, cfc = 10_000.0, 180
    wd = 2 * math.pi * cfc * 2.0775
    wa = math.tan(wd / fs / 2)
    den = 1 + math.sqrt(2) * wa + wa**2
    a0 = wa**2 / den
    b1 = -2 * (wa**2 - 1) / den
    b2 = (-1 + math.sqrt(2) * wa - wa**2) / den
    b, a = cfc_coefficients(fs, cfc)
    assert b == pytest.approx((a0, 2 * a0, a0), rel=1e-12)
    assert a == pytest.approx((1.0, -b1, -b2), rel=1e-12)


@pytest.mark.parametrize("cfc", CLASSES)
@pytest.mark.parametrize("fs", [10_000.0, 20_000.0, 100_000.0])
def test_one_pass_has_unit_dc_gain(cfc: int, fs: float) -> None:
    b, a = cfc_coefficients(fs, cfc)
    assert sum(b) / sum(a) == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize("cfc", CLASSES)
def test_constant_signal_is_returned_unchanged(cfc: int) -> None:
    x = np.full(500, 37.5)
    np.testing.assert_allclose(cfc_filter(x, 10_000.0, cfc), x, rtol=1e-12)


@pytest.mark.parametrize("cfc", CLASSES)
def test_minus_3db_point_near_1_667_cfc(cfc: int) -> None:
    # High sampling rate (>= 50x the class), where J211 documents -3 dB at ~1.667 CFC.
    fs = 100_000.0
    freqs = np.linspace(0.5 * cfc, 3.0 * cfc, 20_001)
    g = _fb_gain(cfc, fs, freqs)
    f3 = freqs[np.argmax(g < 1 / math.sqrt(2))]
    assert f3 / cfc == pytest.approx(1.667, rel=0.01)


def test_response_is_flat_in_band_and_attenuates_above() -> None:
    fs, cfc = 20_000.0, 1000
    g = _fb_gain(cfc, fs, np.array([0.1 * cfc, 0.5 * cfc, 1.0 * cfc, 3.0 * cfc]))
    assert g[0] == pytest.approx(1.0, abs=1e-3)
    assert g[1] > 0.99
    assert 0.85 < g[2] < 1.0  # J211 corridor: within about -1 dB at CFC
    assert g[3] < 0.2


@pytest.mark.parametrize("cfc", [60, 600])
def test_sine_at_minus_3db_frequency_through_cfc_filter(cfc: int) -> None:
    fs = 100 * cfc
    t = np.arange(0, 200 / cfc, 1 / fs)
    x = np.sin(2 * np.pi * 1.667 * cfc * t)
    y = cfc_filter(x, fs, cfc)
    mid = slice(len(t) // 4, 3 * len(t) // 4)
    assert np.std(y[mid]) / np.std(x[mid]) == pytest.approx(1 / math.sqrt(2), abs=0.01)


def test_iso_variant_uses_its_own_design_factor() -> None:
    fs, cfc = 100_000.0, 600
    freqs = np.linspace(0.5 * cfc, 3.0 * cfc, 20_001)
    f_j211 = freqs[np.argmax(_fb_gain(cfc, fs, freqs) < 1 / math.sqrt(2))]
    f_iso = freqs[np.argmax(_fb_gain(cfc, fs, freqs, "iso_6487") < 1 / math.sqrt(2))]
    ratio = ISO_6487_DESIGN_FACTOR / SAE_J211_DESIGN_FACTOR
    assert f_iso / f_j211 == pytest.approx(ratio, rel=2e-3)


def test_zero_phase_keeps_a_symmetric_pulse_symmetric() -> None:
    fs = 10_000.0
    t = np.arange(-0.05, 0.05 + 0.5 / fs, 1 / fs)
    x = np.exp(-((t / 0.004) ** 2)) * 50.0
    y = cfc_filter(x, fs, 180)
    assert int(np.argmax(y)) == int(np.argmax(x))
    np.testing.assert_allclose(y, y[::-1], atol=1e-9)


def test_linear_trend_passes_unchanged_thanks_to_odd_padding() -> None:
    x = np.linspace(-3.0, 12.0, 2000)
    np.testing.assert_allclose(cfc_filter(x, 10_000.0, 60), x, atol=1e-6)


def test_short_and_single_sample_signals() -> None:
    np.testing.assert_array_equal(cfc_filter([4.0], 10_000.0, 1000), [4.0])
    y = cfc_filter([1.0, 1.0, 1.0], 10_000.0, 60)
    np.testing.assert_allclose(y, 1.0)


@pytest.mark.parametrize(
    ("args", "name"),
    [
        (([1.0, 2.0], 10_000.0, 100), "`cfc`"),
        (([1.0, 2.0], -1.0, 60), "`sample_rate_hz`"),
        (([1.0, 2.0], float("nan"), 60), "`sample_rate_hz`"),
        (([1.0, 2.0], 3000.0, 1000), "`sample_rate_hz`"),
        (([[1.0, 2.0]], 10_000.0, 60), "`signal`"),
        (([], 10_000.0, 60), "`signal`"),
        (([1.0, float("nan")], 10_000.0, 60), "`signal`"),
    ],
)
def test_invalid_arguments_name_the_argument(args: tuple[object, ...], name: str) -> None:
    with pytest.raises(ValueError, match=name):
        cfc_filter(*args)  # type: ignore[arg-type]


def test_unknown_standard() -> None:
    with pytest.raises(ValueError, match="`standard`"):
        cfc_filter([1.0, 2.0], 10_000.0, 60, standard="din")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("cfc", "fs"),
    [(c, f) for c in CLASSES for f in (2_000.0, 10_000.0, 20_000.0) if 2 * c * 2.0775 < f],
)
def test_forward_backward_is_scipy_filtfilt_bit_for_bit(cfc: int, fs: float) -> None:
    """The cached steady state changes no bit against scipy's own filtfilt (1-D and rows)."""
    b, a = cfc_coefficients(fs, cfc)
    rng = np.random.default_rng(cfc + int(fs))
    rows = rng.normal(size=(3, 1500)).cumsum(axis=1)
    assert np.array_equal(
        forward_backward(b, a, rows, axis=1), filtfilt(b, a, rows, axis=1, padlen=0)
    )
    assert np.array_equal(forward_backward(b, a, rows[1]), filtfilt(b, a, rows[1], padlen=0))
    assert np.array_equal(
        forward_backward(b, a, rows.T, axis=0), filtfilt(b, a, rows.T, axis=0, padlen=0)
    )
    many = rng.normal(size=(9, 700)).cumsum(axis=1)  # rows stepped side by side
    assert np.array_equal(
        forward_backward(b, a, many, axis=1), filtfilt(b, a, many, axis=1, padlen=0)
    )


@pytest.mark.parametrize("fs", [1_000.0, 2_000.0, 10_000.0, 20_000.0, 12_345.0])
@pytest.mark.parametrize("standard", ["sae_j211", "iso_6487"])
def test_steady_state_is_scipy_lfilter_zi_bit_for_bit(fs: float, standard: str) -> None:
    for cfc in CLASSES:
        if 2 * cfc * 2.0833 >= fs:
            continue  # above the rate's Nyquist limit
        b, a = cfc_coefficients(fs, cfc, standard=standard)  # type: ignore[arg-type]
        assert np.array_equal(_steady_state(b, a), lfilter_zi(b, a))


def _numpy_padded(x: np.ndarray, width: int) -> np.ndarray:
    """The end padding written with numpy: odd reflection, then the end value repeated."""
    n = x.shape[1]
    refl = min(width, n - 1)
    head = 2.0 * x[:, :1] - x[:, refl:0:-1]
    tail = 2.0 * x[:, -1:] - x[:, -2 : -refl - 2 : -1]
    rest = width - refl
    return np.concatenate(
        (
            np.repeat(head[:, :1], rest, axis=1),
            head,
            x,
            tail,
            np.repeat(tail[:, -1:], rest, axis=1),
        ),
        axis=1,
    )


@pytest.mark.parametrize("n", [2, 3, 40, 107, 108, 2001])
@pytest.mark.parametrize("rows", [1, 3, 5])
def test_rows_are_numpy_padding_and_scipy_filtfilt_bit_for_bit(n: int, rows: int) -> None:
    """The compiled padding, passes and crop change no bit against numpy and scipy.

    Short signals (``n`` below the 107-sample pad of CFC 180 at 10 kHz) take the
    constant extension beyond the reflection.
    """
    fs, cfc = 10_000.0, 180
    width = math.ceil(max(0.010, 4.0 / (cfc * SAE_J211_DESIGN_FACTOR)) * fs)
    assert width == 107
    b, a = cfc_coefficients(fs, cfc)
    x = np.random.default_rng(n + rows).normal(size=(rows, n)).cumsum(axis=1)
    expected = filtfilt(b, a, _numpy_padded(x, width), axis=1, padlen=0)[:, width : width + n]
    got = cfc_filter_rows(x, fs, cfc)
    assert got.shape == (rows, n)
    assert got.flags.c_contiguous
    assert np.array_equal(got, expected)
    for r in range(rows):
        assert np.array_equal(cfc_filter(x[r], fs, cfc), expected[r])


def test_rows_validation() -> None:
    with pytest.raises(ValueError, match="2-D"):
        cfc_filter_rows(np.ones(5), 10_000.0, 180)
    with pytest.raises(ValueError, match="finite"):
        cfc_filter_rows(np.array([[1.0, np.nan]]), 10_000.0, 180)
    with pytest.raises(ValueError, match="empty"):
        cfc_filter_rows(np.ones((2, 0)), 10_000.0, 180)
    assert np.array_equal(cfc_filter_rows(np.array([[3.0], [4.0]]), 10_000.0, 180), [[3.0], [4.0]])
