"""Tests of `models.pulse`: analytic haversine round trips, PDOF, EDR records, validation."""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np
import pytest

from models.notification import AccelerationPulse, DeltaVPulse, SummaryPulse
from models.pulse import (
    DEFAULT_HAVERSINE_DURATION_MS,
    EOE_WINDOW_S,
    KMH_PER_MPS,
    STANDARD_GRAVITY,
    ProcessedPulse,
    haversine,
    haversine_delta_v_kmh,
    pdof_from_delta_v,
    process_pulse,
)

RATE_HZ = 10_000.0


def _amplitude_g(delta_v_kmh: float, duration_s: float) -> float:
    return 2.0 * delta_v_kmh / KMH_PER_MPS / (STANDARD_GRAVITY * duration_s)


def _accel_pulse(
    delta_v_kmh: float,
    pdof_deg: float,
    duration_s: float = 0.1,
    record_s: float = 0.25,
    rate_hz: float = RATE_HZ,
    noise: np.ndarray | None = None,
) -> AccelerationPulse:
    """A haversine acceleration record along the PDOF (force from `pdof_deg`)."""
    t = np.arange(int(round(record_s * rate_hz)) + 1) / rate_hz
    a = haversine(t, _amplitude_g(delta_v_kmh, duration_s), duration_s)
    ax = -a * math.cos(math.radians(pdof_deg))
    ay = -a * math.sin(math.radians(pdof_deg))
    if noise is not None:
        ax = ax + noise
    return AccelerationPulse(
        sample_rate_hz=rate_hz, longitudinal_g=tuple(ax.tolist()), lateral_g=tuple(ay.tolist())
    )


def _edr_record(
    delta_v_kmh: float, pdof_deg: float, duration_s: float = 0.1, n: int = 26
) -> DeltaVPulse:
    """49 CFR 563 record (10 ms, 0-250 ms) of an analytic haversine pulse."""
    t = np.minimum(np.arange(n) * 0.010, duration_s)
    amp = _amplitude_g(delta_v_kmh, duration_s)
    # Integral of A g sin^2(pi t / T): A g (t/2 - T sin(2 pi t / T) / (4 pi)).
    v_kmh = (
        amp
        * STANDARD_GRAVITY
        * (t / 2.0 - duration_s * np.sin(2.0 * np.pi * t / duration_s) / (4.0 * np.pi))
        * KMH_PER_MPS
    )
    cx, cy = -math.cos(math.radians(pdof_deg)), -math.sin(math.radians(pdof_deg))
    return DeltaVPulse(
        interval_ms=10.0,
        longitudinal_kmh=tuple((v_kmh * cx).tolist()),
        lateral_kmh=tuple((v_kmh * cy).tolist()),
    )


# --------------------------------------------------------------------------- analytic


def test_haversine_delta_v_formula() -> None:
    # A g T / 2: 10 g over 100 ms is 4.903 m/s = 17.65 km/h.
    assert haversine_delta_v_kmh(10.0, 0.1) == pytest.approx(10 * 9.80665 * 0.05 * 3.6)
    t = np.linspace(0.0, 0.1, 100_001)
    a = haversine(t, 10.0, 0.1)
    assert np.trapezoid(a, t) * STANDARD_GRAVITY * KMH_PER_MPS == pytest.approx(
        haversine_delta_v_kmh(10.0, 0.1), rel=1e-9
    )
    assert haversine(np.array([-0.01, 0.0, 0.05, 0.1, 0.11]), 10.0, 0.1)[[0, 1, 2, 4]] == (
        pytest.approx([0.0, 0.0, 10.0, 0.0])
    )


@pytest.mark.parametrize(("delta_v_kmh", "duration_s"), [(15.0, 0.08), (50.0, 0.1), (90.0, 0.15)])
def test_acceleration_haversine_round_trip(delta_v_kmh: float, duration_s: float) -> None:
    p = process_pulse(_accel_pulse(delta_v_kmh, 0.0, duration_s))
    amp = _amplitude_g(delta_v_kmh, duration_s)
    assert p.delta_v_kmh == pytest.approx(delta_v_kmh, rel=1e-3)
    assert p.haversine.amplitude_g == pytest.approx(amp, rel=1e-3)
    assert p.haversine.duration_ms == pytest.approx(duration_s * 1e3, rel=1e-3)
    assert p.haversine.r_squared > 0.999
    assert p.peak_accel_g == pytest.approx(amp, rel=1e-3)
    # 563 end of event: after T, within one 20 ms window of it.
    assert duration_s * 1e3 <= p.duration_ms <= (duration_s + EOE_WINDOW_S) * 1e3
    # Delta-V of the fit agrees with the integrated delta-V.
    fit_dv = haversine_delta_v_kmh(p.haversine.amplitude_g, p.haversine.duration_ms / 1e3)
    assert fit_dv == pytest.approx(p.delta_v_kmh, rel=1e-3)


def test_summary_pulse_is_an_exact_haversine() -> None:
    p = process_pulse(SummaryPulse(delta_v_kmh=40.0, pdof_deg=0.0, duration_ms=80.0))
    amp = _amplitude_g(40.0, 0.08)
    assert p.haversine.amplitude_g == pytest.approx(amp)
    assert p.haversine.duration_ms == 80.0
    assert p.haversine.r_squared == 1.0
    assert p.duration_ms == 80.0
    assert p.delta_v_kmh == 40.0
    assert p.time_s[0] == 0.0
    assert p.time_s[-1] == pytest.approx(0.08)
    assert np.allclose(np.diff(p.time_s), 1.0 / RATE_HZ)
    # Integral of the series gives back the delta-V.
    dv = np.trapezoid(p.longitudinal_g, p.time_s) * STANDARD_GRAVITY * KMH_PER_MPS
    assert dv == pytest.approx(-40.0, rel=1e-6)


def test_summary_default_duration() -> None:
    p = process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=180.0))
    assert p.duration_ms == DEFAULT_HAVERSINE_DURATION_MS
    assert p.haversine.duration_ms == DEFAULT_HAVERSINE_DURATION_MS


def test_summary_through_acceleration_path_agrees() -> None:
    s = process_pulse(SummaryPulse(delta_v_kmh=35.0, pdof_deg=300.0, duration_ms=90.0))
    # Pad with 100 ms of rest so the end of event is inside the record.
    pad = np.zeros(1000)
    a = AccelerationPulse(
        sample_rate_hz=s.sample_rate_hz,
        longitudinal_g=tuple(np.concatenate([s.longitudinal_g, pad]).tolist()),
        lateral_g=tuple(np.concatenate([s.lateral_g, pad]).tolist()),
    )
    m = process_pulse(a)
    assert m.delta_v_kmh == pytest.approx(s.delta_v_kmh, rel=1e-3)
    assert m.pdof_deg == pytest.approx(s.pdof_deg, abs=0.01)
    assert m.haversine.duration_ms == pytest.approx(90.0, rel=1e-3)


# --------------------------------------------------------------------------- PDOF


@pytest.mark.parametrize(
    ("pdof_deg", "sign_x", "sign_y"),
    [(0.0, -1, 0), (90.0, 0, -1), (180.0, 1, 0), (270.0, 0, 1)],
)
def test_pdof_four_directions_acceleration(pdof_deg: float, sign_x: int, sign_y: int) -> None:
    p = process_pulse(_accel_pulse(40.0, pdof_deg))
    assert p.pdof_deg == pytest.approx(pdof_deg, abs=1e-6)
    assert 0.0 <= p.pdof_deg < 360.0
    assert np.sign(round(p.delta_v_longitudinal_kmh, 6)) == sign_x
    assert np.sign(round(p.delta_v_lateral_kmh, 6)) == sign_y


def test_pdof_convention_from_raw_signs() -> None:
    # Frontal crash decelerates: ax < 0 gives PDOF 0.
    assert pdof_from_delta_v(-10.0, 0.0) == 0.0
    # Impact on the right pushes the car left: ay < 0 gives PDOF 90.
    assert pdof_from_delta_v(0.0, -10.0) == 90.0
    assert pdof_from_delta_v(10.0, 0.0) == 180.0
    assert pdof_from_delta_v(0.0, 10.0) == 270.0
    assert pdof_from_delta_v(-10.0, -10.0) == pytest.approx(45.0)
    assert pdof_from_delta_v(-10.0, 1e-18) == 0.0  # never 360


@pytest.mark.parametrize("pdof_deg", [0.0, 90.0, 180.0, 270.0, 20.0, 235.0])
def test_pdof_four_directions_summary_and_edr(pdof_deg: float) -> None:
    s = process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=pdof_deg))
    assert s.pdof_deg == pytest.approx(pdof_deg)
    assert pdof_from_delta_v(s.delta_v_longitudinal_kmh, s.delta_v_lateral_kmh) == pytest.approx(
        pdof_deg
    )
    e = process_pulse(_edr_record(30.0, pdof_deg))
    assert e.pdof_deg == pytest.approx(pdof_deg, abs=1e-9)


def test_summary_pdof_wraps() -> None:
    assert process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=-90.0)).pdof_deg == 270.0
    assert process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=360.0)).pdof_deg == 0.0


# --------------------------------------------------------------------------- EDR


def test_edr_record_gives_back_its_delta_v() -> None:
    rec = _edr_record(56.0, 0.0, duration_s=0.1)
    p = process_pulse(rec)
    assert p.delta_v_kmh == pytest.approx(56.0, rel=1e-12)
    assert p.delta_v_longitudinal_kmh == pytest.approx(-56.0, rel=1e-12)
    assert p.pdof_deg == 0.0
    # The piecewise-constant acceleration integrates back to the record.
    dv = np.concatenate(
        [[0.0], np.cumsum((p.longitudinal_g[1:] + p.longitudinal_g[:-1]) / 2.0 / RATE_HZ)]
    )
    dv_kmh = dv * STANDARD_GRAVITY * KMH_PER_MPS
    idx = np.arange(0, p.time_s.size, 100)
    assert np.allclose(dv_kmh[idx], rec.longitudinal_kmh, atol=0.1)
    # Duration: end of event after the pulse, within a window plus a sample.
    assert 100.0 <= p.duration_ms <= 130.0
    assert p.haversine.duration_ms == pytest.approx(100.0, rel=0.05)
    assert p.haversine.r_squared > 0.95


def test_edr_truncated_record_ends_at_record_end() -> None:
    # Event still going at the end of a 60 ms record.
    rec = _edr_record(56.0, 0.0, duration_s=0.1, n=7)
    p = process_pulse(rec)
    assert p.duration_ms == pytest.approx(60.0)
    assert p.delta_v_kmh == pytest.approx(abs(rec.longitudinal_kmh[-1]))


# --------------------------------------------------------------------------- filtering


def test_filtering_does_not_change_delta_v_materially() -> None:
    rng = np.random.default_rng(7)
    n = int(0.25 * RATE_HZ) + 1
    t = np.arange(n) / RATE_HZ
    # High-frequency ringing (400 Hz, 5 g) plus white noise (2 g rms).
    noise = 5.0 * np.sin(2 * np.pi * 400.0 * t) + rng.normal(0.0, 2.0, n)
    clean = process_pulse(_accel_pulse(50.0, 0.0))
    noisy_pulse = _accel_pulse(50.0, 0.0, noise=noise)
    noisy = process_pulse(noisy_pulse)
    # Unfiltered integral of the same record up to the same end of event.
    end = int(round(noisy.duration_ms * 1e-3 * RATE_HZ))
    raw = np.asarray(noisy_pulse.longitudinal_g)[: end + 1]
    raw_dv = -np.trapezoid(raw) / RATE_HZ * STANDARD_GRAVITY * KMH_PER_MPS
    assert noisy.delta_v_kmh == pytest.approx(raw_dv, abs=0.25)
    # The noise itself integrates to a few tenths of a km/h.
    assert noisy.delta_v_kmh == pytest.approx(clean.delta_v_kmh, abs=1.0)
    # The filter removes the ringing: the peak is close to the clean one.
    assert noisy.peak_accel_g == pytest.approx(clean.peak_accel_g, abs=1.0)
    assert noisy.haversine.r_squared > 0.99


def test_lower_input_rate_is_resampled() -> None:
    p = process_pulse(_accel_pulse(40.0, 90.0, rate_hz=1_000.0))
    assert p.sample_rate_hz == RATE_HZ
    assert np.allclose(np.diff(p.time_s), 1e-4)
    assert p.time_s[-1] == pytest.approx(0.25)
    assert p.delta_v_kmh == pytest.approx(40.0, rel=5e-3)
    q = process_pulse(_accel_pulse(40.0, 90.0), output_rate_hz=2_000.0)
    assert q.time_s.size == 501
    assert q.delta_v_kmh == pytest.approx(40.0, rel=5e-3)


# --------------------------------------------------------------------------- determinism


@pytest.mark.parametrize(
    "pulse",
    [
        _accel_pulse(45.0, 30.0),
        _edr_record(45.0, 100.0),
        SummaryPulse(delta_v_kmh=45.0, pdof_deg=200.0, duration_ms=120.0),
    ],
    ids=["acceleration", "delta_v", "summary"],
)
def test_deterministic_bit_identical(
    pulse: AccelerationPulse | DeltaVPulse | SummaryPulse,
) -> None:
    a, b = process_pulse(pulse), process_pulse(pulse)
    assert a == b
    assert hash(a) == hash(b)
    for f in fields(ProcessedPulse):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.tobytes() == y.tobytes(), f.name
        else:
            assert x == y, f.name


def test_equality_sees_array_differences() -> None:
    a = process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=0.0))
    b = process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=0.0), output_rate_hz=5_000.0)
    c = process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=1.0))
    assert a != b
    assert a != c
    assert a != "pulse"


def test_arrays_are_read_only() -> None:
    p = process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=0.0))
    with pytest.raises(ValueError, match="read-only"):
        p.longitudinal_g[0] = 1.0


# --------------------------------------------------------------------------- validation


def _good_accel(**kw: object) -> AccelerationPulse:
    base = _accel_pulse(40.0, 0.0)
    args: dict[str, object] = {
        "sample_rate_hz": base.sample_rate_hz,
        "longitudinal_g": base.longitudinal_g,
        "lateral_g": base.lateral_g,
    }
    args.update(kw)
    return AccelerationPulse(**args)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("pulse", "field"),
    [
        (lambda: _good_accel(sample_rate_hz=0.0), "sample_rate_hz"),
        (lambda: _good_accel(sample_rate_hz=-10_000.0), "sample_rate_hz"),
        (lambda: _good_accel(sample_rate_hz=float("nan")), "sample_rate_hz"),
        (lambda: _good_accel(sample_rate_hz=200.0), "sample_rate_hz"),
        (lambda: _good_accel(longitudinal_g=(float("nan"),) * 2501), "longitudinal_g"),
        (lambda: _good_accel(lateral_g=(0.0,) * 2500 + (float("inf"),)), "lateral_g"),
        (lambda: _good_accel(lateral_g=(0.0,) * 10), "lateral_g"),
        (lambda: _good_accel(longitudinal_g=(-1.0,) * 2, lateral_g=(0.0,) * 2), "longitudinal_g"),
        (lambda: _good_accel(longitudinal_g=(-1.0,) * 50, lateral_g=(0.0,) * 50), "longitudinal_g"),
        (lambda: _good_accel(longitudinal_g=(0.0,) * 2501, lateral_g=(0.0,) * 2501), "no crash"),
        (
            lambda: _good_accel(longitudinal_g=(-50.0,) * 60_001, lateral_g=(0.0,) * 60_001),
            "too long",
        ),
        (
            lambda: _good_accel(longitudinal_g=(-100.0,) * 2501, lateral_g=(0.0,) * 2501),
            "200 km/h",
        ),
        (
            lambda: DeltaVPulse(
                interval_ms=0.0, longitudinal_kmh=(0.0,) * 26, lateral_kmh=(0.0,) * 26
            ),
            "interval_ms",
        ),
        (
            lambda: DeltaVPulse(
                interval_ms=10.0, longitudinal_kmh=(0.0, -5.0), lateral_kmh=(0.0, 0.0)
            ),
            "longitudinal_kmh",
        ),
        (
            lambda: DeltaVPulse(
                interval_ms=10.0,
                longitudinal_kmh=(0.0, -5.0, float("nan")),
                lateral_kmh=(0.0, 0.0, 0.0),
            ),
            "longitudinal_kmh",
        ),
        (
            lambda: DeltaVPulse(
                interval_ms=10.0, longitudinal_kmh=(0.0, -5.0, -9.0), lateral_kmh=(0.0, 0.0)
            ),
            "lateral_kmh",
        ),
        (
            lambda: _good_accel(longitudinal_g=(1e308,) * 2501, lateral_g=(0.0,) * 2501),
            "`longitudinal_g` element 0",
        ),
        (
            lambda: DeltaVPulse(
                interval_ms=10.0, longitudinal_kmh=(0.0, -5.0, -1e308), lateral_kmh=(0.0,) * 3
            ),
            "`longitudinal_kmh` element 2",
        ),
        (lambda: SummaryPulse(delta_v_kmh=float("inf"), pdof_deg=0.0), "delta_v_kmh"),
        (lambda: SummaryPulse(delta_v_kmh=-5.0, pdof_deg=0.0), "delta_v_kmh"),
        (lambda: SummaryPulse(delta_v_kmh=250.0, pdof_deg=0.0), "delta_v_kmh"),
        (lambda: SummaryPulse(delta_v_kmh=30.0, pdof_deg=float("nan")), "pdof_deg"),
        (lambda: SummaryPulse(delta_v_kmh=30.0, pdof_deg=0.0, duration_ms=0.0), "duration_ms"),
        (lambda: SummaryPulse(delta_v_kmh=30.0, pdof_deg=0.0, duration_ms=-1.0), "duration_ms"),
    ],
)
def test_nonsense_is_refused(pulse: object, field: str) -> None:
    with pytest.raises(ValueError, match=field):
        process_pulse(pulse())  # type: ignore[operator]


def test_pathological_record_gives_finite_numbers() -> None:
    # Delta-V out and straight back: a constant-magnitude resultant, r^2 undefined -> 0.
    p = process_pulse(
        DeltaVPulse(interval_ms=10.0, longitudinal_kmh=(0, -5, 0, 0, 0, 0), lateral_kmh=(0,) * 6)
    )
    assert p.haversine.r_squared == 0.0
    assert all(
        math.isfinite(v)
        for v in (p.delta_v_kmh, p.pdof_deg, p.peak_accel_g, p.duration_ms, p.haversine.amplitude_g)
    )
    # A 10 ms square pulse each way: the delta-V swings out and back.
    x = np.zeros(1000)
    x[100:200], x[200:300] = -100.0, 100.0
    q = process_pulse(
        AccelerationPulse(sample_rate_hz=10_000.0, longitudinal_g=tuple(x), lateral_g=(0.0,) * 1000)
    )
    assert math.isfinite(q.haversine.r_squared)
    assert "time_s" not in repr(q)


@pytest.mark.parametrize("rate", [0.0, -1.0, float("nan"), 10.0, 1e7])
def test_bad_output_rate(rate: float) -> None:
    with pytest.raises(ValueError, match="output_rate_hz"):
        process_pulse(SummaryPulse(delta_v_kmh=30.0, pdof_deg=0.0), output_rate_hz=rate)


def test_wrong_type() -> None:
    with pytest.raises(TypeError, match="pulse"):
        process_pulse("not a pulse")  # type: ignore[arg-type]
