"""Public API: result fields, statuses, input validation, warm-up."""

from __future__ import annotations

import numpy as np
import pytest

from models.impact_mode import ImpactMode
from models.lpm.params import ParameterSet
from models.lpm.pulses import haversine_pulse, ncap_frontal_pulse, side_pulse
from models.lpm.simulate import STATUS_MESSAGES, LpmResult, simulate, warm_up
from models.notification import Body
from tests.models.lpm.helpers import occupant


def test_result_fields(params: ParameterSet) -> None:
    t, ax, ay = ncap_frontal_pulse()
    r = simulate(t, ax, ay, ImpactMode.FRONTAL, occupant(), params, angle_deg=10.0)
    assert isinstance(r, LpmResult)
    assert r.mode is ImpactMode.FRONTAL
    assert r.angle_deg == 10.0
    assert r.status == 0
    assert r.message == STATUS_MESSAGES[0]
    assert r.time_s.shape == (2001,)
    for k in (
        "head_accel_g",
        "neck_fx_n",
        "neck_fz_n",
        "neck_my_nm",
        "chest_deflection_mm",
        "head_x_m",
        "head_z_m",
        "t1_x_m",
        "belt_shoulder_n",
        "force_airbag_head_n",
        "vehicle_accel_g",
    ):
        assert r.histories[k].shape == r.time_s.shape, k
    with pytest.raises(ValueError, match="read-only"):
        r.histories["head_accel_g"][0] = 1.0
    assert r.info["parameter_sha256"] == params.sha256
    assert r.assessment is not None
    assert r.measures.abdomen_vc_m_s is None  # frontal has no abdomen VC


def test_measures_per_mode(params: ParameterSet) -> None:
    rear = simulate(
        *haversine_pulse(32.0, 0.09, angle_deg=180.0), ImpactMode.REAR, occupant(), params
    )
    assert rear.measures.hic15 is not None
    assert rear.measures.nij is not None
    assert rear.measures.chest_deflection_mm is None
    side = simulate(*side_pulse(), ImpactMode.NEAR_SIDE, occupant(), params)
    for k in ("hic15", "nij", "chest_cti", "abdomen_vc_m_s", "chest_vc_m_s"):
        assert getattr(side.measures, k) is not None, k


def test_side_pulse_sign_does_not_matter(params: ParameterSet) -> None:
    left = simulate(*side_pulse(right=False), ImpactMode.NEAR_SIDE, occupant(), params)
    right = simulate(*side_pulse(right=True), ImpactMode.NEAR_SIDE, occupant(), params)
    assert left.measures == right.measures


def test_short_pulse_is_padded_with_status_1(params: ParameterSet) -> None:
    t, ax, ay = haversine_pulse(56.0, 0.09, record_s=0.12)
    r = simulate(t, ax, ay, ImpactMode.FRONTAL, occupant(), params)
    assert r.status == 1
    assert r.time_s[-1] == pytest.approx(0.2)


def test_bad_inputs_raise(params: ParameterSet) -> None:
    t = np.arange(100) * 1e-4
    a = np.zeros(100)
    with pytest.raises(ValueError, match="equal length"):
        simulate(t, a[:50], a, ImpactMode.FRONTAL, occupant(), params)
    with pytest.raises(ValueError, match="uniformly increasing"):
        simulate(t[::-1], a, a, ImpactMode.FRONTAL, occupant(), params)
    bad = a.copy()
    bad[3] = np.nan
    with pytest.raises(ValueError, match="finite"):
        simulate(t, bad, a, ImpactMode.FRONTAL, occupant(), params)
    with pytest.raises(ValueError, match="duration_s"):
        simulate(t, a, a, ImpactMode.FRONTAL, occupant(), params, duration_s=5.0)


def test_warm_up_runs() -> None:
    warm_up()


def test_both_bodies_all_modes_run(params: ParameterSet) -> None:
    for body in Body:
        for mode in ImpactMode:
            pulse = (
                side_pulse()
                if mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE)
                else (
                    haversine_pulse(40.0, 0.09, angle_deg=180.0 if mode is ImpactMode.REAR else 0.0)
                )
            )
            r = simulate(*pulse, mode, occupant(body), params)
            assert r.status == 0, (body, mode)
            assert all(np.all(np.isfinite(h)) for h in r.histories.values())


def test_batch_equals_single_runs(params: ParameterSet) -> None:
    from models.lpm.simulate import BatchCase, simulate_batch

    cases = [BatchCase(*ncap_frontal_pulse(), ImpactMode.FRONTAL, occupant(b)) for b in Body] + [
        BatchCase(*side_pulse(), ImpactMode.NEAR_SIDE, occupant())
    ]
    out = simulate_batch(cases, params, workers=2)
    for c, r in zip(cases, out, strict=True):
        single = simulate(c.time_s, c.accel_x_g, c.accel_y_g, c.mode, c.occupant, params)
        assert r.measures == single.measures
        assert np.array_equal(r.histories["head_accel_g"], single.histories["head_accel_g"])


@pytest.mark.parametrize("mode", list(ImpactMode))
def test_histories_computed_on_first_read_are_the_measures_channels(
    params: ParameterSet, mode: ImpactMode
) -> None:
    """The lazy histories hold what the eager ones held, and the measures read the same
    channels (bit for bit) as the full set gives them."""
    from models.lpm import simulate as sim

    pulse = side_pulse() if mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE) else None
    if pulse is None:
        angle = 180.0 if mode is ImpactMode.REAR else 0.0
        pulse = haversine_pulse(40.0, 0.09, angle_deg=angle)
    pr = sim.prepare(*pulse, mode, occupant(), params)
    t, ys, diags, _ = sim._run_kernel(pr)
    eager = sim._histories(pr, t, ys, diags)
    lazy = simulate(*pulse, mode, occupant(), params).histories
    assert set(lazy) == set(eager)
    assert len(lazy) == len(eager)
    for name, values in eager.items():
        assert np.array_equal(lazy[name], values), name
        assert not lazy[name].flags.writeable
    channels = sim._measure_channels(pr, ys, diags)
    for name, values in channels.items():
        assert np.array_equal(values, eager[name]), name
    assert sim._measures(pr, t, channels) == sim._measures(pr, t, eager)
