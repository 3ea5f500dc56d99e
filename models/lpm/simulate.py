"""Public entry point of the occupant LPMs: pulse in, injury measures out.

:func:`simulate` runs the numba fixed-step kernel (semi-implicit Euler); :func:`simulate_reference`
runs ``scipy.integrate.solve_ivp`` (DOP853, tight tolerances) on the very same
right-hand side and is used by the tests and the benchmark to bound the
fixed-step error. Both return an :class:`LpmResult`.

Status table (``LpmResult.status``), scipy style: expected outcomes are
reported, not raised.

======  =========================================================================
status  meaning
======  =========================================================================
0       success
1       success; the pulse record was shorter than ``duration_s`` and was
        continued with zero acceleration
-1      the integration produced a non-finite state; histories are truncated
        and the measures are None
-2      the reference solver failed (``simulate_reference`` only)
======  =========================================================================
"""

from __future__ import annotations

import math
import os
import threading
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from models.arrays import FloatArray
from models.constants import G_MS2
from models.impact_mode import ImpactMode
from models.injury.assessment import InjuryAssessment, InjuryMeasures, assess
from models.injury.criteria import (
    VC_CONSTANTS_ES2,
    VC_CONSTANTS_SID_IIS,
    chest_deflection,
    clip_3ms,
    cti,
    hic,
    nij,
    viscous_criterion,
)
from models.injury.filters import cfc_filter_rows
from models.lpm import kernel as K
from models.lpm.assemble import Model, Restraints, build_model
from models.lpm.params import ParameterSet
from models.notification import AirbagState, Body, Occupant

__all__ = [
    "HEAD_STRIKE_CONTACTS",
    "STATUS_MESSAGES",
    "BatchCase",
    "LpmResult",
    "prepare",
    "resolve_restraints",
    "simulate",
    "simulate_batch",
    "simulate_reference",
    "head_clearance_mm",
    "warm_up",
]

G0 = G_MS2  # standard gravity, m/s^2 (models.constants)

STATUS_MESSAGES: Mapping[int, str] = MappingProxyType(
    {
        0: "success",
        1: "success; pulse shorter than the simulated duration, continued with zero acceleration",
        -1: "integration produced a non-finite state",
        -2: "reference solver failed",
    }
)


@dataclass(frozen=True)
class LpmResult:
    """Outcome of one occupant simulation.

    Attributes
    ----------
    mode : ImpactMode
    angle_deg : float
        Obliquity of the impact from the mode's axis, deg, as passed in; the
        model is driven by the pulse component on its own axis.
    measures : InjuryMeasures
        Scalar injury measures (None where the mode does not produce them or
        the run failed).
    assessment : InjuryAssessment or None
        Regional AIS, ISS and P(ISS >= 15); None when the run failed.
    time_s : ndarray, shape (n,)
        Output times, s (the integration grid).
    histories : Mapping[str, ndarray]
        Time histories, each shape (n,), unfiltered; units in the names
        (``_g``, ``_n``, ``_nm``, ``_mm``, ``_m``, ``_rad``, ``_j``).
    status : int
        See :data:`STATUS_MESSAGES`.
    message : str
    info : Mapping[str, Any]
        Parameter set name and SHA-256, firing times, contact names.
    """

    mode: ImpactMode
    angle_deg: float
    measures: InjuryMeasures
    assessment: InjuryAssessment | None
    time_s: FloatArray
    histories: Mapping[str, FloatArray]
    status: int
    message: str
    info: Mapping[str, Any]


#: Contacts of the head with the rigid interior (not airbags, not the
#: occupant's own thighs): frontal steering wheel, windshield and its lower
#: panel, dash; near side door window; far side far door. [R] Where the head
#: first meets one of them HIC15 and Nij change slope (a hinge in every input;
#: REPORT.md of the surrogates, models/surrogate/spec.py), so the surrogates
#: are fitted on each side of that onset.
HEAD_STRIKE_CONTACTS: Final[tuple[str, ...]] = (
    "wheel_head",
    "windshield_head",
    "dash_head",
    "window_head",
    "far_door_head",
)


def head_clearance_mm(result: LpmResult) -> float:
    """Least clearance of the head to the rigid interior over the run, mm.

    The minimum over time and over the model's :data:`HEAD_STRIKE_CONTACTS` of
    the signed gap of the head's contact point to the undeformed surface
    (``gap_<contact>_m`` histories): positive when the head never reached a
    surface (the margin left), negative the deepest penetration. Continuous
    through the onset of a head strike, unlike the measures' slopes.

    Returns
    -------
    float
        mm; NaN for a failed run; :data:`models.lpm.kernel.GAP_NONE` (in mm)
        when the model has none of those contacts.
    """
    if result.status < 0:
        return float("nan")
    gaps = [
        float(np.min(result.histories[f"gap_{c}_m"]))
        for c in HEAD_STRIKE_CONTACTS
        if f"gap_{c}_m" in result.histories
    ]
    return 1000.0 * (min(gaps) if gaps else K.GAP_NONE)


@dataclass(frozen=True)
class Prepared:
    """Kernel inputs of one case (model arrays plus input channels)."""

    model: Model
    mode: ImpactMode
    occupant: Occupant
    t0: float
    dt_in: float
    acc: FloatArray  # model-axis vehicle acceleration, m/s^2
    door_s: FloatArray
    door_v: FloatArray
    dt: float
    duration_s: float
    padded: bool
    params_name: str
    params_sha256: str


def _cumtrapz(y: FloatArray, dt: float) -> FloatArray:
    out = np.zeros_like(y)
    out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1])) * dt
    return out


def _model_axis(mode: ImpactMode, ax_g: FloatArray, ay_g: FloatArray) -> FloatArray:
    """Vehicle acceleration on the model axis, m/s^2 (see kernel docstring)."""
    if mode in (ImpactMode.FRONTAL, ImpactMode.REAR):
        return ax_g * G0
    dvy = float(np.sum(ay_g))
    sign = -1.0 if dvy > 0.0 else 1.0  # x toward the struck side
    return sign * ay_g * G0


def resolve_restraints(
    mode: ImpactMode,
    occupant: Occupant,
    params: ParameterSet,
    time_s: FloatArray,
    acc_model: FloatArray,
) -> Restraints:
    """Airbag and pretensioner states and firing times for one case.

    The frontal airbag acts when the notification says it deployed; it fires at
    ``occupant.airbag_fire_time_ms`` when given, else when the cabin delta-V on
    the model axis first exceeds ``frontal.fire.delta_v_threshold``
    (decelerating), else at ``frontal.fire.default_time``; in a rear case it
    acts only with an explicit firing time. The pretensioner
    fires with the same rule when the occupant is belted in a frontal or rear
    case, unless ``occupant.pretensioner_fired`` is False. Side modes use the
    belt as seat-slip damping (near side) or a lateral belt element (far side).
    The side and curtain airbags act in a near-side case when the notification
    says the occupant's side airbag deployed; they fire ``side.airbag.fire_time``
    after the start of the pulse (side sensing sees the door intrusion at once).
    """
    dt = float(time_s[1] - time_s[0]) if time_s.size > 1 else 1e-4
    dv = _cumtrapz(acc_model, dt)
    thr = params["frontal.fire.delta_v_threshold"]
    idx = np.flatnonzero(dv <= -thr) if mode is ImpactMode.FRONTAL else np.array([], dtype=int)
    t_thr = float(time_s[idx[0]]) if idx.size else None
    airbag = occupant.frontal_airbag is AirbagState.DEPLOYED and (
        mode is ImpactMode.FRONTAL
        or (mode is ImpactMode.REAR and occupant.airbag_fire_time_ms is not None)
    )
    if occupant.airbag_fire_time_ms is not None:
        fire = occupant.airbag_fire_time_ms / 1000.0
    elif t_thr is not None:
        fire = t_thr
    else:
        fire = params["frontal.fire.default_time"]
    pt: float | None = None
    if occupant.belted and mode in (ImpactMode.FRONTAL, ImpactMode.REAR):
        if occupant.pretensioner_fired is True:
            pt = t_thr if t_thr is not None else fire
        elif occupant.pretensioner_fired is None and t_thr is not None:
            pt = t_thr
    side_airbag = mode is ImpactMode.NEAR_SIDE and occupant.side_airbag is AirbagState.DEPLOYED
    side_fire = float(time_s[0]) + params["side.airbag.fire_time"] if side_airbag else math.nan
    return Restraints(
        airbag=airbag,
        airbag_fire_s=fire,
        belted=occupant.belted,
        pretensioner_fire_s=pt,
        airbag_equipped=occupant.frontal_airbag is not AirbagState.ABSENT,
        side_airbag=side_airbag,
        side_airbag_fire_s=side_fire,
    )


def _door_motion(acc: FloatArray, dt: float, params: ParameterSet) -> tuple[FloatArray, FloatArray]:
    """Inner door intrusion (m) and its rate (m/s) from the vehicle pulse.

    Momentum exchange with a barrier of mass ``m_b`` into a vehicle of mass
    ``m_v``: the barrier approaches the vehicle at ``(1 + m_v/m_b)(v - v_end)``
    (``v`` vehicle velocity on the model axis, ``v_end`` its final value); a
    fraction ``side.intrusion_fraction`` of that reaches the inner door
    surface, capped at ``side.intrusion_max``, after a smooth rise over
    ``side.intrusion_rise_time`` (outer-panel crush before the inner panel moves).
    """
    v = _cumtrapz(acc, dt)
    v_end = float(v[-1])
    ratio = 1.0 + params["side.vehicle_mass"] / params["side.barrier_mass"]
    rate = params["side.intrusion_fraction"] * ratio * np.maximum(v - v_end, 0.0)
    # the inner panel starts moving once the outer door has crushed: smooth rise
    x = np.clip(np.arange(acc.size) * dt / params["side.intrusion_rise_time"], 0.0, 1.0)
    rate = rate * x * x * (3.0 - 2.0 * x)
    s = _cumtrapz(rate, dt)
    cap = params["side.intrusion_max"]
    rate = np.where(s >= cap, 0.0, rate)
    s = np.minimum(s, cap)
    return s, rate


def prepare(
    time_s: npt.ArrayLike,
    accel_x_g: npt.ArrayLike,
    accel_y_g: npt.ArrayLike,
    mode: ImpactMode,
    occupant: Occupant,
    params: ParameterSet,
    *,
    duration_s: float = 0.2,
) -> Prepared:
    """Validate the inputs and build the kernel inputs of one case.

    Parameters are those of :func:`simulate`.

    Raises
    ------
    ValueError
        Malformed arrays (shape, non-uniform or too coarse sampling, non-finite).
    """
    t = np.ascontiguousarray(time_s, dtype=np.float64)
    ax = np.ascontiguousarray(accel_x_g, dtype=np.float64)
    ay = np.ascontiguousarray(accel_y_g, dtype=np.float64)
    if t.ndim != 1 or t.size < 2 or ax.shape != t.shape or ay.shape != t.shape:
        raise ValueError("time_s, accel_x_g and accel_y_g must be 1-D arrays of equal length >= 2")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(ax)) and np.all(np.isfinite(ay))):
        raise ValueError("pulse arrays must be finite")
    dt_in = float(t[1] - t[0])
    # np.allclose(np.diff(t), dt_in, rtol=1e-6, atol=1e-12) on finite t, without its overhead
    if dt_in <= 0.0 or not bool(np.all(np.abs(np.diff(t) - dt_in) <= 1e-12 + 1e-6 * dt_in)):
        raise ValueError("time_s must be uniformly increasing")
    if dt_in > 2e-3:
        raise ValueError("pulse sampling must be at least 500 Hz")
    if not (0.0 < duration_s <= 1.0):
        raise ValueError("duration_s must be in (0, 1] s")
    mode = ImpactMode(mode)
    # extend the record with zero acceleration to the simulated duration
    padded = bool(t[-1] - t[0] < duration_s - 0.5 * dt_in)
    n_need = int(math.ceil(duration_s / dt_in)) + 2
    if t.size < n_need:
        extra = n_need - t.size
        t = np.concatenate([t, t[-1] + dt_in * np.arange(1, extra + 1)])
        ax = np.concatenate([ax, np.zeros(extra)])
        ay = np.concatenate([ay, np.zeros(extra)])
    acc = np.ascontiguousarray(_model_axis(mode, ax, ay))
    rs = resolve_restraints(mode, occupant, params, t - t[0], acc)
    if mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE):
        door_s, door_v = _door_motion(acc, dt_in, params)
    else:
        door_s = np.zeros_like(acc)
        door_v = np.zeros_like(acc)
    model = build_model(mode, occupant, params, rs)
    return Prepared(
        model,
        mode,
        occupant,
        float(t[0]),
        dt_in,
        acc,
        door_s,
        door_v,
        params["numerics.time_step"],
        float(duration_s),
        padded,
        params.name,
        params.sha256,
    )


def _run_kernel(
    pr: Prepared, dt: float | None = None, method: str = "se"
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    m = pr.model
    step = pr.dt if dt is None else dt
    integ = K.integrate_rk4 if method == "rk4" else K.integrate_se
    ys, diags, status = integ(
        m.y0,
        pr.duration_s,
        step,
        m.ll,
        m.mb,
        m.jt,
        m.ch,
        m.se,
        m.ct,
        m.bt,
        m.bag,
        pr.t0,
        pr.dt_in,
        pr.acc,
        pr.door_s,
        pr.door_v,
    )
    t = (np.arange(ys.shape[0]) * step).astype(np.float64)
    return t, ys, diags, int(status)


def _filtered_stack(rows: Sequence[FloatArray], fs: float, cfc: int) -> FloatArray:
    """Several channels of one class through the CFC filter in one call.

    ``models.injury.filters.cfc_filter_rows``: bit-identical to ``cfc_filter``
    per channel (tests/lpm/test_numerics.py), the rows stepped side by side.
    """
    return cfc_filter_rows(np.vstack(rows), fs, cfc)


def _positions(m: Model, ys: FloatArray) -> dict[str, FloatArray]:
    """Joint and head-CG positions over time, m (for plots and checks)."""
    q = ys[:, : K.NQ]
    ll = m.ll
    x = q[:, 0]
    j1x = x + ll[1] * np.sin(q[:, 1])
    j1z = ll[1] * np.cos(q[:, 1])
    t1x = j1x + ll[2] * np.sin(q[:, 2])
    t1z = j1z + ll[2] * np.cos(q[:, 2])
    ocx = t1x + ll[3] * np.sin(q[:, 3])
    ocz = t1z + ll[3] * np.cos(q[:, 3])
    hp, hr = m.mb[5, 1], m.mb[5, 2]
    hx = ocx + hp * np.sin(q[:, 4]) + hr * np.cos(q[:, 4])
    hz = ocz + hp * np.cos(q[:, 4]) - hr * np.sin(q[:, 4])
    return {
        "hip_x_m": x,
        "hip_z_m": np.zeros_like(x),
        "lumbar_x_m": j1x,
        "lumbar_z_m": j1z,
        "t1_x_m": t1x,
        "t1_z_m": t1z,
        "oc_x_m": ocx,
        "oc_z_m": ocz,
        "head_x_m": hx,
        "head_z_m": hz,
    }


def _measure_channels(pr: Prepared, ys: FloatArray, diags: FloatArray) -> dict[str, FloatArray]:
    """The histories :func:`_measures` reads, computed as :func:`_histories` computes them."""
    m = pr.model
    nc = m.ct.shape[0]
    nb = m.bt.shape[0]
    h: dict[str, FloatArray] = {}
    h["head_accel_x_g"] = diags[:, K.D_HEAD_AX] / G0
    h["head_accel_z_g"] = diags[:, K.D_HEAD_AZ] / G0
    h["chest_accel_x_g"] = diags[:, K.D_CHEST_AX] / G0
    h["chest_accel_z_g"] = diags[:, K.D_CHEST_AZ] / G0
    h["neck_fx_n"] = diags[:, K.D_NECK_FX]
    h["neck_fz_n"] = diags[:, K.D_NECK_FZ]
    h["neck_my_nm"] = diags[:, K.D_NECK_MY]
    h["chest_deflection_mm"] = ys[:, 5] * 1000.0
    for c, name in enumerate(m.contact_names):
        if name in _ABDOMEN_CONTACTS:
            h[f"penetration_{name}_m"] = diags[:, K.DIAG_FIXED + nc + nb + c]
    return h


#: Contacts whose penetration history is a side-mode abdominal measure (:func:`_measures`).
_ABDOMEN_CONTACTS: Final[frozenset[str]] = frozenset({"door_abdomen", "console_abdomen"})


class _LazyHistories(Mapping[str, FloatArray]):
    """:func:`_histories` of a run, computed on first access (read-only arrays).

    The triage reads only the measures' channels (:func:`_measure_channels`);
    the full set (positions, energies, every contact's force, gap and crush)
    is for plots, checks and the offline tools, which pay for it when they
    read it. The values are those :func:`_histories` gives, bit for bit.
    """

    __slots__ = ("_args", "_done", "_lock")

    def __init__(self, pr: Prepared, t: FloatArray, ys: FloatArray, diags: FloatArray) -> None:
        self._args: tuple[Prepared, FloatArray, FloatArray, FloatArray] | None = (pr, t, ys, diags)
        self._done: Mapping[str, FloatArray] | None = None
        self._lock = threading.Lock()

    def _all(self) -> Mapping[str, FloatArray]:
        done = self._done
        if done is None:
            with self._lock:
                if self._done is None:
                    assert self._args is not None
                    self._done = MappingProxyType(_histories(*self._args))
                    self._args = None
                done = self._done
        return done

    def __getitem__(self, key: str) -> FloatArray:
        return self._all()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._all())

    def __len__(self) -> int:
        return len(self._all())


def _histories(
    pr: Prepared, t: FloatArray, ys: FloatArray, diags: FloatArray
) -> dict[str, FloatArray]:
    m = pr.model
    nc = m.ct.shape[0]
    nb = m.bt.shape[0]
    h: dict[str, FloatArray] = {}
    h["vehicle_accel_g"] = np.interp(t, np.arange(pr.acc.size) * pr.dt_in, pr.acc) / G0
    h["door_intrusion_m"] = np.interp(t, np.arange(pr.door_s.size) * pr.dt_in, pr.door_s)
    h["head_accel_x_g"] = diags[:, K.D_HEAD_AX] / G0
    h["head_accel_z_g"] = diags[:, K.D_HEAD_AZ] / G0
    h["head_accel_g"] = np.hypot(h["head_accel_x_g"], h["head_accel_z_g"])
    h["chest_accel_x_g"] = diags[:, K.D_CHEST_AX] / G0
    h["chest_accel_z_g"] = diags[:, K.D_CHEST_AZ] / G0
    h["chest_accel_g"] = np.hypot(h["chest_accel_x_g"], h["chest_accel_z_g"])
    h["pelvis_accel_g"] = np.abs(diags[:, K.D_PELV_AX]) / G0
    h["neck_fx_n"] = diags[:, K.D_NECK_FX]
    h["neck_fz_n"] = diags[:, K.D_NECK_FZ]
    h["neck_my_nm"] = diags[:, K.D_NECK_MY]
    h["chest_deflection_mm"] = ys[:, 5] * 1000.0
    for i, name in enumerate(
        ("pelvis_x_m", "abdomen_angle_rad", "thorax_angle_rad", "neck_angle_rad", "head_angle_rad")
    ):
        h[name] = ys[:, i]
    h.update(_positions(m, ys))
    for c, name in enumerate(m.contact_names):
        h[f"force_{name}_n"] = diags[:, K.DIAG_FIXED + c]
        h[f"penetration_{name}_m"] = diags[:, K.DIAG_FIXED + nc + nb + c]
        h[f"gap_{name}_m"] = diags[:, K.DIAG_FIXED + 2 * nc + nb + c]
        if m.ct[c, K.C_BCAP] > 0.0:
            h[f"crush_{name}_m"] = ys[:, 2 * K.NQ + 2 * nb + c]
    for b, name in enumerate(m.belt_names):
        h[f"belt_{name}_n"] = diags[:, K.DIAG_FIXED + nc + b]
        h[f"belt_{name}_payout_m"] = ys[:, 2 * K.NQ + 2 * b]
        h[f"belt_{name}_pullin_m"] = ys[:, 2 * K.NQ + 2 * b + 1]
    dt = float(t[1] - t[0]) if t.size > 1 else pr.dt
    h["kinetic_energy_j"] = diags[:, K.D_KE]
    h["internal_energy_j"] = diags[:, K.D_V_INT]
    h["work_pulse_j"] = _cumtrapz(diags[:, K.D_P_PULSE], dt)
    h["work_active_j"] = _cumtrapz(diags[:, K.D_P_ACTIVE], dt)
    for v in h.values():
        v.flags.writeable = False
    return h


def _measures(pr: Prepared, t: FloatArray, h: Mapping[str, FloatArray]) -> InjuryMeasures:
    fs = 1.0 / float(t[1] - t[0])
    body: Body = pr.occupant.body
    hx, hz = _filtered_stack((h["head_accel_x_g"], h["head_accel_z_g"]), fs, 1000)
    hic15 = hic(np.hypot(hx, hz), fs, 15.0).value
    fx, fz, my = _filtered_stack((h["neck_fx_n"], h["neck_fz_n"], h["neck_my_nm"]), fs, 600)
    nij_v = nij(fx, fz, my, body).value
    if pr.mode is ImpactMode.REAR:
        return InjuryMeasures(hic15=hic15, nij=nij_v)
    side = pr.mode in (ImpactMode.NEAR_SIDE, ImpactMode.FAR_SIDE)
    abd_name = (
        "penetration_door_abdomen_m"
        if pr.mode is ImpactMode.NEAR_SIDE
        else "penetration_console_abdomen_m"
    )
    chans = [h["chest_deflection_mm"], h["chest_accel_x_g"], h["chest_accel_z_g"]]
    if side:
        chans.append(h[abd_name])
    f180 = _filtered_stack(chans, fs, 180)
    defl_mm = f180[0]
    ca = np.hypot(f180[1], f180[2])
    a3 = clip_3ms(ca, fs)
    dres = chest_deflection(np.maximum(defl_mm, 0.0), body)
    if pr.mode is ImpactMode.FRONTAL:
        vc = viscous_criterion(defl_mm / 1000.0, fs, body)
        return InjuryMeasures(
            hic15=hic15,
            nij=nij_v,
            chest_deflection_mm=dres.peak_mm,
            chest_vc_m_s=max(vc, 0.0),
            chest_a3ms_g=a3,
        )
    side_vc = VC_CONSTANTS_ES2 if body is Body.MALE_50TH else VC_CONSTANTS_SID_IIS
    vc = viscous_criterion(defl_mm / 1000.0, fs, body, constants=side_vc)
    abd = f180[3]
    vc_abd = viscous_criterion(abd, fs, body, constants=side_vc)
    return InjuryMeasures(
        hic15=hic15,
        nij=nij_v,
        chest_deflection_mm=dres.peak_mm,
        chest_vc_m_s=max(vc, 0.0),
        chest_a3ms_g=a3,
        chest_cti=cti(a3, dres.peak_mm, body),
        abdomen_vc_m_s=max(vc_abd, 0.0),
    )


def _result(
    pr: Prepared,
    angle_deg: float,
    t: FloatArray,
    ys: FloatArray,
    diags: FloatArray,
    status: int,
    extra: Mapping[str, Any] | None = None,
) -> LpmResult:
    if status == 0 and pr.padded:
        status = 1
    if status >= 0:
        measures = _measures(pr, t, _measure_channels(pr, ys, diags))
        assessment: InjuryAssessment | None = assess(
            measures, pr.occupant.body, pr.occupant.age_years, pr.mode.value
        )
    else:
        measures = InjuryMeasures()
        assessment = None
    info: dict[str, Any] = {
        "parameter_set": pr.params_name,
        "parameter_sha256": pr.params_sha256,
        "plane": pr.model.plane,
        "contacts": pr.model.contact_names,
        "belts": pr.model.belt_names,
        "time_step_s": float(t[1] - t[0]) if t.size > 1 else pr.dt,
        **pr.model.info,
    }
    if extra:
        info.update(extra)
    return LpmResult(
        pr.mode,
        float(angle_deg),
        measures,
        assessment,
        t,
        _LazyHistories(pr, t, ys, diags),
        status,
        STATUS_MESSAGES[status],
        MappingProxyType(info),
    )


def simulate(
    time_s: npt.ArrayLike,
    accel_x_g: npt.ArrayLike,
    accel_y_g: npt.ArrayLike,
    mode: ImpactMode,
    occupant: Occupant,
    params: ParameterSet,
    *,
    angle_deg: float = 0.0,
    duration_s: float = 0.2,
) -> LpmResult:
    """Simulate one occupant with the fixed-step numba kernel (semi-implicit Euler).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Uniform sample times of the pulse, s (time zero at the first sample).
    accel_x_g, accel_y_g : array_like, shape (n,)
        Vehicle acceleration, g, SAE J211 axes (x forward, y right); a frontal
        crash has negative x acceleration.
    mode : ImpactMode
        Which LPM to run. FRONTAL/REAR use ``accel_x_g``; NEAR_SIDE/FAR_SIDE
        use ``accel_y_g`` signed toward the struck side.
    occupant : Occupant
    params : ParameterSet
    angle_deg : float, optional
        Obliquity from the mode's axis, deg (reported in the result).
    duration_s : float, optional
        Simulated time, s (0.2 by default).

    Returns
    -------
    LpmResult
    """
    pr = prepare(time_s, accel_x_g, accel_y_g, mode, occupant, params, duration_s=duration_s)
    t, ys, diags, status = _run_kernel(pr)
    return _result(pr, angle_deg, t, ys, diags, status)


@dataclass(frozen=True)
class BatchCase:
    """Inputs of one case of :func:`simulate_batch` (arguments of :func:`simulate`)."""

    time_s: FloatArray
    accel_x_g: FloatArray
    accel_y_g: FloatArray
    mode: ImpactMode
    occupant: Occupant
    angle_deg: float = 0.0
    duration_s: float = 0.2


def simulate_batch(
    cases: Sequence[BatchCase], params: ParameterSet, *, workers: int | None = None
) -> list[LpmResult]:
    """Simulate many cases; the compiled kernels run in parallel threads.

    The kernels release the GIL (numba ``nogil``), so ``workers`` threads
    (default: the CPU count) integrate cases while the calling thread prepares
    and post-processes the others (pipelined); each result is identical to
    :func:`simulate` on the same case.

    Parameters
    ----------
    cases : sequence of BatchCase
    params : ParameterSet
    workers : int, optional

    Returns
    -------
    list of LpmResult, in the order of ``cases``
    """
    from collections import deque
    from concurrent.futures import Future, ThreadPoolExecutor

    def prep(c: BatchCase) -> Prepared:
        return prepare(
            c.time_s, c.accel_x_g, c.accel_y_g, c.mode, c.occupant, params, duration_s=c.duration_s
        )

    n = workers or os.cpu_count() or 1
    if n <= 1:
        out = []
        for c in cases:
            pr = prep(c)
            out.append(_result(pr, c.angle_deg, *_run_kernel(pr)))
        return out
    # pipeline: the compiled kernels (nogil) run in the worker threads while the
    # calling thread prepares the next cases and post-processes finished ones
    # (filters, criteria and assessment hold the GIL most of the time); a window
    # of 4 cases per worker bounds the memory held by pending histories
    results: list[LpmResult] = []
    window = 4 * n
    todo = iter(cases)
    pending: deque[
        tuple[BatchCase, Prepared, Future[tuple[FloatArray, FloatArray, FloatArray, int]]]
    ] = deque()
    with ThreadPoolExecutor(max_workers=n) as ex:

        def submit() -> bool:
            c = next(todo, None)
            if c is None:
                return False
            pr = prep(c)
            pending.append((c, pr, ex.submit(_run_kernel, pr)))
            return True

        while len(pending) < window and submit():
            pass
        while pending:
            c, pr, fut = pending.popleft()
            submit()
            results.append(_result(pr, c.angle_deg, *fut.result()))
    return results


def simulate_reference(
    time_s: npt.ArrayLike,
    accel_x_g: npt.ArrayLike,
    accel_y_g: npt.ArrayLike,
    mode: ImpactMode,
    occupant: Occupant,
    params: ParameterSet,
    *,
    angle_deg: float = 0.0,
    duration_s: float = 0.2,
    rtol: float = 1e-8,
    atol: float = 1e-10,
    method: str = "DOP853",
) -> LpmResult:
    """Same case through ``scipy.integrate.solve_ivp`` (reference path).

    The right-hand side is the compiled kernel function, so both paths solve
    the same equations; outputs are on the same grid as :func:`simulate`.
    Extra parameters: ``rtol``, ``atol`` and ``method`` of ``solve_ivp``.
    """
    from scipy.integrate import solve_ivp

    pr = prepare(time_s, accel_x_g, accel_y_g, mode, occupant, params, duration_s=duration_s)
    m = pr.model
    empty = np.zeros(0)
    args = (
        m.ll,
        m.mb,
        m.jt,
        m.ch,
        m.se,
        m.ct,
        m.bt,
        m.bag,
        pr.t0,
        pr.dt_in,
        pr.acc,
        pr.door_s,
        pr.door_v,
    )

    def fun(tt: float, y: FloatArray) -> FloatArray:
        return np.asarray(K.rhs(tt, y, *args, empty))

    n = int(round(pr.duration_s / pr.dt)) + 1
    t = (np.arange(n) * pr.dt).astype(np.float64)
    sol = solve_ivp(fun, (0.0, t[-1]), m.y0, method=method, t_eval=t, rtol=rtol, atol=atol)
    if not sol.success or sol.y.shape[1] != n:
        empty_h = np.zeros((1, m.y0.size))
        nd = K.diag_size(m.ct.shape[0], m.bt.shape[0])
        res = _result(pr, angle_deg, t[:1], empty_h, np.zeros((1, nd)), -1)
        return LpmResult(
            res.mode,
            res.angle_deg,
            res.measures,
            None,
            res.time_s,
            res.histories,
            -2,
            STATUS_MESSAGES[-2],
            res.info,
        )
    ys = np.ascontiguousarray(sol.y.T)
    nd = K.diag_size(m.ct.shape[0], m.bt.shape[0])
    diags = np.zeros((n, nd))
    for i in range(n):
        K.rhs(float(t[i]), ys[i], *args, diags[i])
    return _result(pr, angle_deg, t, ys, diags, 0, {"nfev": int(sol.nfev)})


def warm_up() -> None:
    """Compile (or load from the numba cache) the kernels and the measure code.

    Runs one short simulation per plane. The cache directory follows
    ``NUMBA_CACHE_DIR`` when set.
    """
    from models.lpm.params import load_parameter_set
    from models.notification import Seat

    ps = load_parameter_set()
    t = np.arange(0, 0.03, 1e-4)
    a = np.zeros_like(t)
    occ = Occupant(
        seat=Seat.DRIVER, body=Body.MALE_50TH, belted=True, frontal_airbag=AirbagState.DEPLOYED
    )
    for mode in (ImpactMode.FRONTAL, ImpactMode.NEAR_SIDE):
        simulate(t, a, a, mode, occ, ps, duration_s=0.02)
