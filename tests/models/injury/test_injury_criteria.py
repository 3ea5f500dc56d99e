"""Nij, chest deflection and compression, VC, CTI and the 3 ms clip."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from models.injury.criteria import (
    CHEST_DEPTH_MM,
    FMVSS208_CHEST_DEFLECTION_LIMIT_MM,
    NIJ_INTERCEPTS,
    NIJ_INTERCEPTS_5F_OUT_OF_POSITION,
    VC_CONSTANTS_ES2,
    NijMode,
    chest_deflection,
    clip_3ms,
    cti,
    nij,
    occipital_condyle_moment,
    viscous_criterion,
)
from models.notification import Body

M50 = Body.MALE_50TH
F05 = Body.FEMALE_5TH

# ---------------------------------------------------------------- Nij


def test_published_intercepts() -> None:
    ic = NIJ_INTERCEPTS[M50]
    assert (ic.tension_n, ic.compression_n, ic.flexion_nm, ic.extension_nm) == (
        6806.0,
        6160.0,
        310.0,
        135.0,
    )
    ic = NIJ_INTERCEPTS[F05]
    assert (ic.tension_n, ic.compression_n, ic.flexion_nm, ic.extension_nm) == (
        4287.0,
        3880.0,
        155.0,
        67.0,
    )
    assert ic.condyle_offset_m == 0.01778


@pytest.mark.parametrize(
    ("fz", "my", "mode"),
    [
        (6806.0, -135.0, NijMode.NTE),
        (6806.0, 310.0, NijMode.NTF),
        (-6160.0, -135.0, NijMode.NCE),
        (-6160.0, 310.0, NijMode.NCF),
    ],
)
def test_loads_at_the_intercepts_give_two_in_each_quadrant(
    fz: float, my: float, mode: NijMode
) -> None:
    r = nij([0.0, 0.0], [0.0, fz], [0.0, my], M50)
    assert r.value == pytest.approx(2.0)
    assert r.mode is mode
    assert r.time_index == 1
    assert r.mode_peaks[mode] == pytest.approx(2.0)


def test_pure_tension_at_the_intercept_is_one() -> None:
    r = nij([0.0], [6806.0], [0.0], M50)
    assert r.value == pytest.approx(1.0)


def test_occipital_condyle_correction() -> None:
    # Shear alone: MOCy = -0.01778 * Fx (extension for positive Fx).
    fx = 1000.0
    r = nij([fx], [0.0], [0.0], M50)
    assert r.value == pytest.approx(0.01778 * fx / 135.0)
    assert r.mode is NijMode.NTE
    np.testing.assert_allclose(occipital_condyle_moment([fx], [10.0]), [10.0 - 17.78])


def test_all_four_modes_are_tracked() -> None:
    fz = np.array([1000.0, 2000.0, -1500.0, -500.0, 0.0])
    my = np.array([-20.0, 40.0, -30.0, 80.0, 0.0])
    fx = np.zeros(5)
    r = nij(fx, fz, my, F05)
    ic = NIJ_INTERCEPTS[F05]
    expected = {
        NijMode.NTE: 1000 / ic.tension_n + 20 / ic.extension_nm,
        NijMode.NTF: max(2000 / ic.tension_n + 40 / ic.flexion_nm, 0.0),
        NijMode.NCE: 1500 / ic.compression_n + 30 / ic.extension_nm,
        NijMode.NCF: 500 / ic.compression_n + 80 / ic.flexion_nm,
    }
    for mode, value in expected.items():
        assert r.mode_peaks[mode] == pytest.approx(value), mode
    assert r.value == pytest.approx(max(expected.values()))
    assert r.mode is max(expected, key=lambda m: expected[m])


def test_mode_that_never_occurs_has_zero_peak_and_override_intercepts() -> None:
    r = nij(
        [0.0, 0.0], [100.0, 200.0], [5.0, 1.0], F05, intercepts=NIJ_INTERCEPTS_5F_OUT_OF_POSITION
    )
    assert r.nce == 0.0
    assert r.ncf == 0.0
    assert r.nte == 0.0
    assert r.value == pytest.approx(100.0 / 3880.0 + 5.0 / 155.0)


def test_nij_validation() -> None:
    with pytest.raises(ValueError, match="same shape"):
        nij([0.0], [0.0, 1.0], [0.0], M50)
    with pytest.raises(ValueError, match="`dummy`"):
        nij([0.0], [0.0], [0.0], "hybrid_iii_95th")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="`fz_n`"):
        nij([0.0], [float("nan")], [0.0], M50)


# ---------------------------------------------------------------- chest deflection, VC, CTI


def test_chest_depths_and_limits() -> None:
    assert CHEST_DEPTH_MM == {M50: 229.0, F05: 187.0}
    assert FMVSS208_CHEST_DEFLECTION_LIMIT_MM == {M50: 63.0, F05: 52.0}


def test_chest_deflection_peak_and_compression() -> None:
    d = np.array([0.0, 10.0, 63.0, 40.0, -5.0])
    r = chest_deflection(d, M50)
    assert r.peak_mm == 63.0
    assert r.compression == pytest.approx(63.0 / 229.0)
    assert r.time_index == 2
    assert chest_deflection(d, F05).compression == pytest.approx(63.0 / 187.0)
    assert chest_deflection(-np.ones(4), M50).peak_mm == 0.0


def test_vc_of_a_linear_ramp() -> None:
    # D = v t: the 4-point difference is exact; VCmax at the last interior sample.
    fs, v = 10_000.0, 6.0
    t = np.arange(0, 0.01, 1 / fs)
    d = v * t
    expected = 1.3 * v * d[-3] / 0.229
    assert viscous_criterion(d, fs, M50) == pytest.approx(expected, rel=1e-9)
    assert viscous_criterion(d, fs, F05) == pytest.approx(1.3 * v * d[-3] / 0.187, rel=1e-9)


def test_vc_of_a_quartic_uses_an_exact_derivative() -> None:
    # The 4-point central difference is exact for polynomials up to degree 4.
    fs = 5_000.0
    t = np.arange(0, 0.02, 1 / fs)
    d = 2.0e5 * t**4 + 3.0 * t**2
    v = 8.0e5 * t**3 + 6.0 * t
    vc = 1.0 * v * d / 0.140
    got = viscous_criterion(d, fs, M50, constants=VC_CONSTANTS_ES2)
    assert got == pytest.approx(vc[2:-2].max(), rel=1e-9)


def test_vc_of_a_half_sine_deflection() -> None:
    # D = A sin(w t), t in [0, pi/w]: VC = SF A^2 w sin cos / D0, max SF A^2 w / (2 D0).
    fs, amp, dur = 20_000.0, 0.05, 0.04
    w = np.pi / dur
    t = np.arange(0, dur + 0.5 / fs, 1 / fs)
    d = amp * np.sin(w * t)
    assert viscous_criterion(d, fs, M50) == pytest.approx(1.3 * amp**2 * w / (2 * 0.229), rel=1e-4)


def test_vc_validation_and_floor() -> None:
    with pytest.raises(ValueError, match="at least 5"):
        viscous_criterion([0.0, 0.1, 0.2, 0.3], 10_000.0, M50)
    assert viscous_criterion(np.linspace(0.05, 0.0, 50), 10_000.0, M50) == 0.0


def test_cti() -> None:
    assert cti(90.0, 103.0, M50) == pytest.approx(2.0)
    assert cti(45.0, 0.0, M50) == pytest.approx(0.5)
    assert cti(0.0, 103.0 * 187.0 / 229.0, F05) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="`dmax_mm`"):
        cti(10.0, -1.0, M50)


# ---------------------------------------------------------------- 3 ms clip


def test_clip_of_a_rectangular_pulse() -> None:
    fs = 10_000.0
    a = np.zeros(200)
    a[50:80] = 70.0  # exactly 30 samples = 3 ms
    assert clip_3ms(a, fs) == 70.0
    assert clip_3ms(a, fs, cumulative=False) == 70.0
    a[79] = 0.0  # 2.9 ms: not held for 3 ms
    assert clip_3ms(a, fs) == 0.0


def test_cumulative_and_continuous_clip_differ_for_split_peaks() -> None:
    fs = 10_000.0
    a = np.full(300, 10.0)
    a[50:70] = 100.0  # 2 ms
    a[150:170] = 100.0  # 2 ms more, 4 ms cumulative
    assert clip_3ms(a, fs) == 100.0
    assert clip_3ms(a, fs, cumulative=False) == 10.0


def test_clip_agrees_between_definitions_for_a_single_peak() -> None:
    fs = 10_000.0
    t = np.arange(0, 0.1, 1 / fs)
    a = 55.0 * np.sin(np.pi * t / 0.1)
    assert clip_3ms(a, fs) == pytest.approx(clip_3ms(a, fs, cumulative=False))
    assert clip_3ms(a, fs) < a.max()


def test_clip_validation() -> None:
    with pytest.raises(ValueError, match="at least 3 ms"):
        clip_3ms(np.ones(10), 10_000.0)
    with pytest.raises(ValueError, match="`sample_rate_hz`"):
        clip_3ms(np.ones(10), 100.0)


def test_results_are_frozen() -> None:
    r = chest_deflection([1.0, 2.0], M50)
    with pytest.raises(dataclasses.FrozenInstanceError):
        r.peak_mm = 3.0  # type: ignore[misc]


def _nij_arrays(fx: np.ndarray, fz: np.ndarray, my: np.ndarray, body: Body) -> tuple:
    """Nij in array form (the formula as first written): the reference of the one-pass scan."""
    ic = NIJ_INTERCEPTS[body]
    moc = my - ic.condyle_offset_m * fx
    tension = fz >= 0.0
    flexion = moc >= 0.0
    series = np.where(tension, fz / ic.tension_n, -fz / ic.compression_n) + np.where(
        flexion, moc / ic.flexion_nm, -moc / ic.extension_nm
    )
    masks = (tension & ~flexion, tension & flexion, ~tension & ~flexion, ~tension & flexion)
    peaks = tuple(float(series[m].max()) if m.any() else 0.0 for m in masks)
    k = int(np.argmax(series))
    return float(series[k]), k, peaks


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("body", list(Body))
def test_nij_one_pass_is_the_array_formula_bit_for_bit(seed: int, body: Body) -> None:
    rng = np.random.default_rng(seed)
    n = 2500
    fx, fz, my = (rng.normal(scale=s, size=n).cumsum() for s in (40.0, 120.0, 4.0))
    if seed == 0:
        fz = np.abs(fz)  # tension only: the compression cases never occur
    value, k, peaks = _nij_arrays(fx, fz, my, body)
    r = nij(fx, fz, my, body)
    assert (r.value, r.time_index) == (value, k)
    assert (r.nte, r.ntf, r.nce, r.ncf) == peaks
