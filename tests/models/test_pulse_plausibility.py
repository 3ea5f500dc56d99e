"""Tests of the maximum delta-V and of the one rule for records that are not physical."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest

from models.limits import MAX_ABS_ACCELERATION_G
from models.notification import AccelerationPulse, DeltaVPulse, SummaryPulse
from models.pulse import KMH_PER_MPS, STANDARD_GRAVITY, PulseError, process_pulse
from models.pulse_plausibility import (
    MAX_DELTA_V_REVERSALS,
    MAX_OUT_OF_BAND_ENERGY_RATIO,
    count_reversals,
    reversal_band_kmh,
)

#: The two oscillating records of issue 41 (10 ms), answered 0.6 and 2.8e-14 km/h before.
OSCILLATING: list[float] = [0, -30, 5, -40, 10, -50, 0, -20, 30, -10, 0, -60, 60, -60]
FLIPPING: list[float] = [0, 200, -200, 200, -200, 0, 0, 0, 0, 0, 0, 0, 0, 0]


def _record(longitudinal: Sequence[float], lateral: Sequence[float] | None = None) -> DeltaVPulse:
    lat = [0.0] * len(longitudinal) if lateral is None else lateral
    return DeltaVPulse(
        interval_ms=10.0,
        longitudinal_kmh=tuple(float(x) for x in longitudinal),
        lateral_kmh=tuple(float(y) for y in lat),
    )


def test_the_oscillating_record_is_refused_naming_the_field() -> None:
    with pytest.raises(PulseError, match=r"`longitudinal_kmh` is not a physical record.*turns"):
        process_pulse(_record(OSCILLATING))


def test_the_flipping_record_is_refused_for_its_implied_acceleration() -> None:
    # 200 km/h in 10 ms is 566 g, over the 500 g the acceleration input accepts
    with pytest.raises(PulseError, match=r"`longitudinal_kmh` .* element 0 to 1 .*566\.5 g"):
        process_pulse(_record(FLIPPING))


def test_the_implied_acceleration_limit_is_the_acceleration_inputs() -> None:
    # the largest step one 10 ms interval may hold: 500 g for 10 ms, in km/h
    step = MAX_ABS_ACCELERATION_G * STANDARD_GRAVITY * 0.010 * KMH_PER_MPS
    ok = [0.0, -step * 0.999, -step * 0.999, -step * 0.999]
    assert process_pulse(_record(ok)).delta_v_kmh == pytest.approx(step * 0.999)
    with pytest.raises(PulseError, match="lateral_kmh"):
        process_pulse(_record([0.0, 0.0, 0.0, 0.0], [0.0, step * 1.001, step * 1.001, 0.0]))


def test_the_same_swing_as_lateral_names_the_lateral_field() -> None:
    with pytest.raises(PulseError, match=r"`lateral_kmh` is not a physical record"):
        process_pulse(_record([0.0] * len(OSCILLATING), OSCILLATING))


def test_a_rebound_and_a_second_impact_are_physical() -> None:
    # frontal to -40, rebound to -34, second impact to -55, rebound to -48: three turns
    rec = [0, -8, -20, -32, -40, -37, -34, -34, -40, -48, -55, -52, -48, -48, -48]
    p = process_pulse(_record(rec))
    assert p.delta_v_kmh == 55.0
    assert p.pdof_deg == 0.0
    band = reversal_band_kmh(55.0)
    assert count_reversals(np.asarray(rec, dtype=float), band)[0] == MAX_DELTA_V_REVERSALS
    # one more back-and-forth of the same size is refused
    with pytest.raises(PulseError, match="turns back 4 times"):
        process_pulse(_record(rec + [-44, -44, -52, -52]))


def test_noise_of_a_563_record_is_not_a_turn() -> None:
    # a small crash quantised to the 563 resolution (1 km/h) with lateral jitter of +/-1
    lon = [0, -1, -3, -5, -7, -8, -8, -7, -8, -8, -7, -8, -8, -8]
    lat = [0, 1, 0, -1, 0, 1, 0, -1, 0, 1, 0, -1, 0, 1]
    p = process_pulse(_record(lon, lat))
    assert p.delta_v_kmh == pytest.approx(math.hypot(8.0, 1.0))
    assert reversal_band_kmh(8.0) == 2.0
    assert reversal_band_kmh(60.0) == pytest.approx(6.0)


def test_maximum_delta_v_of_a_rebounding_record() -> None:
    # 49 CFR 563 maximum delta-V: -50 km/h at 60 ms, then a 10 km/h rebound
    rec = [0, -10, -22, -34, -44, -49, -50, -47, -43, -41, -40, -40, -40, -40]
    p = process_pulse(_record(rec, [0.0, 1, 2, 3, 4, 5, 5, 5, 5, 5, 5, 5, 5, 5]))
    assert p.delta_v_kmh == pytest.approx(math.hypot(50.0, 5.0))
    assert p.delta_v_longitudinal_kmh == -50.0
    assert p.delta_v_lateral_kmh == 5.0
    # the PDOF of the vector at the maximum: frontal, a little from the left
    assert p.pdof_deg == pytest.approx(360.0 - math.degrees(math.atan2(5.0, 50.0)))


def test_maximum_delta_v_of_a_rebounding_acceleration_pulse() -> None:
    # 40 g for 40 ms (-56.5 km/h), then +20 g for 20 ms (rebound of 14.1 km/h)
    rate = 10_000.0
    a = np.zeros(2501)
    a[0:400], a[400:600] = -40.0, 20.0
    p = process_pulse(
        AccelerationPulse(
            sample_rate_hz=rate, longitudinal_g=tuple(a.tolist()), lateral_g=(0.0,) * a.size
        )
    )
    peak_dv = 40.0 * STANDARD_GRAVITY * 0.040 * KMH_PER_MPS
    assert p.delta_v_kmh == pytest.approx(peak_dv, rel=0.02)
    assert p.delta_v_kmh > peak_dv - 20.0 * STANDARD_GRAVITY * 0.020 * KMH_PER_MPS + 10.0


def test_the_maximum_delta_v_is_at_least_the_final_one() -> None:
    # monotone records: the maximum is the last value (no change from the earlier rule)
    rng = np.random.default_rng(41)
    for _ in range(20):
        steps = rng.uniform(0.0, 8.0, 13)
        rec = np.concatenate([[0.0], -np.cumsum(steps)])
        p = process_pulse(_record(rec.tolist()))
        assert p.delta_v_kmh == pytest.approx(-rec[-1], rel=1e-12)


def test_a_severe_record_with_noise_is_never_read_as_minor() -> None:
    # monotone to -60 km/h with +/-1 km/h jitter: accepted, and read as about 60
    rng = np.random.default_rng(5)
    base = np.concatenate([np.linspace(0.0, -60.0, 11), np.full(10, -60.0)])
    rec = np.round(base + rng.integers(-1, 2, base.size) * (base != 0.0))
    p = process_pulse(_record(rec.tolist()))
    assert p.delta_v_kmh >= 59.0


def test_summary_pulses_are_untouched() -> None:
    p = process_pulse(SummaryPulse(delta_v_kmh=45.0, pdof_deg=30.0))
    assert p.delta_v_kmh == 45.0
    assert p.pdof_deg == 30.0


@pytest.mark.parametrize(
    ("series", "band", "expected"),
    [
        ([0.0, -10.0, -20.0], 2.0, (0, -1)),
        ([0.0, -10.0, -5.0], 2.0, (1, 2)),
        ([0.0, -10.0, -9.0, -10.0, -9.0], 2.0, (0, -1)),
        ([0.0, 1.0, -1.0, 1.0, -1.0], 2.0, (0, -1)),
        ([0.0, 3.0, -3.0, 3.0, -3.0], 2.0, (3, 2)),
    ],
)
def test_count_reversals_hysteresis(
    series: list[float], band: float, expected: tuple[int, int]
) -> None:
    assert count_reversals(np.asarray(series), band) == expected


# ------------------------------------------------- acceleration records that look corrupt


def _acceleration(
    longitudinal: np.ndarray, lateral: np.ndarray | None = None, rate: float = 10_000.0
) -> AccelerationPulse:
    lat = np.zeros_like(longitudinal) if lateral is None else lateral
    return AccelerationPulse(
        sample_rate_hz=rate,
        longitudinal_g=tuple(float(x) for x in longitudinal),
        lateral_g=tuple(float(y) for y in lat),
    )


def _alternating(n: int, amplitude_g: float = 400.0) -> np.ndarray:
    return amplitude_g * (-1.0) ** np.arange(n)


@pytest.mark.parametrize(
    ("pulse", "field"),
    [
        # the record: +/-400 g every sample, 10 kHz, 100 ms
        (_acceleration(_alternating(1000)), "longitudinal_g"),
        (_acceleration(_alternating(100), rate=1_000.0), "longitudinal_g"),
        (_acceleration(_alternating(5000), rate=50_000.0), "longitudinal_g"),
        (_acceleration(np.zeros(1000), _alternating(1000, 150.0)), "lateral_g"),
        # on top of a real 40 g pulse: still not a vehicle's motion
        (
            _acceleration(
                -40.0 * np.sin(np.pi * np.arange(1000) / 1000) ** 2 + _alternating(1000, 100.0)
            ),
            "longitudinal_g",
        ),
    ],
    ids=["10kHz-100ms", "1kHz", "50kHz", "lateral", "on-a-pulse"],
)
def test_an_acceleration_record_changing_sign_every_sample_looks_corrupt(
    pulse: AccelerationPulse, field: str
) -> None:
    p = process_pulse(pulse)
    assert p.nonphysical is not None
    assert p.nonphysical.startswith(f"`{field}` changes sign at 100% of its samples")


def test_energy_far_above_the_band_looks_corrupt() -> None:
    # a quarter of the sampling rate: the sign changes every other sample only
    square = 400.0 * np.where((np.arange(1000) // 2) % 2 == 0, 1.0, -1.0)
    p = process_pulse(_acceleration(square))
    assert p.nonphysical is not None
    assert "more energy above the CFC 60 band than in it" in p.nonphysical
    assert MAX_OUT_OF_BAND_ENERGY_RATIO < 69.5 < MAX_OUT_OF_BAND_ENERGY_RATIO * 3


def test_a_noisy_ringing_crash_record_does_not_look_corrupt() -> None:
    # a 40 g, 100 ms pulse with structural ringing (1.5 kHz, 30 g; 400 Hz, 5 g) and 15 g
    # of white noise on both channels: a badly filtered sensor, not a corrupt record
    rng = np.random.default_rng(49)
    t = np.arange(2500) / 10_000.0
    pulse = -40.0 * np.sin(np.pi * t / 0.1) ** 2 * (t <= 0.1)
    ringing = 30.0 * np.sin(2 * np.pi * 1500.0 * t) * (t <= 0.12) + 5.0 * np.sin(
        2 * np.pi * 400 * t
    )
    p = process_pulse(
        _acceleration(pulse + ringing + rng.normal(0.0, 15.0, t.size), rng.normal(0.0, 5.0, t.size))
    )
    assert p.nonphysical is None
    # the filter keeps the crash: 40 g over 100 ms is 70.6 km/h; the noise walks a few km/h
    assert p.delta_v_kmh == pytest.approx(40.0 * STANDARD_GRAVITY * 0.1 / 2 * KMH_PER_MPS, abs=5.0)


def test_only_acceleration_records_are_checked_as_sent() -> None:
    assert process_pulse(SummaryPulse(delta_v_kmh=45.0, pdof_deg=30.0)).nonphysical is None
    rec = [0, -8, -20, -32, -40, -37, -34, -34, -40, -48, -55, -52, -48, -48, -48]
    assert process_pulse(_record(rec)).nonphysical is None
