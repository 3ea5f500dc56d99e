"""Build the packed kernel arrays of one LPM case from a parameter set.

The sagittal model (frontal and rear modes) and the coronal model (near and
far side) share the body chain of :mod:`models.lpm.kernel`; this module places
the body in its initial posture, places the vehicle surfaces, belts and airbag
around it, and converts everything into the float arrays the kernel reads.

Coordinates: origin at the occupant's initial H-point, z up; x forward
(sagittal) or toward the struck side (coronal). Vehicle-fixed surfaces are
given at mid track in the parameter set; a seat moved forward by
``seat_track_mm`` brings the occupant closer to them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from models.arrays import FloatArray
from models.impact_mode import ImpactMode
from models.lpm import kernel as K
from models.lpm.interior import BodyPoint, ContactRow, interior_plane, surface_size
from models.lpm.params import ParameterError, ParameterSet
from models.notification import Body, Occupant, Seat

__all__ = ["ContactSpec", "Model", "Restraints", "build_model"]


#: Clearance added to surfaces that touch the occupant in the neutral posture,
#: m: keeps them exactly force-free at t = 0 despite rounding.
_CLEAR = 1e-6
_NEVER = 1e9


@dataclass(frozen=True)
class Restraints:
    """Restraint timing resolved from the pulse and the notification.

    Attributes
    ----------
    airbag : bool
        Frontal airbag present and deployed.
    airbag_fire_s : float
        Firing time, s (ignored without airbag).
    belted : bool
    pretensioner_fire_s : float or None
        Pretensioner firing time, s; None when it does not fire.
    airbag_equipped : bool
        The seat has a frontal airbag (deployed or not): the shoulder belt then
        has the lower load limit ``frontal.belt.load_limit_airbag``.
    side_airbag : bool
        Side (thorax) and curtain airbag deployed on the struck side (near side only).
    side_airbag_fire_s : float
        Their firing time, s (ignored without them).
    """

    airbag: bool
    airbag_fire_s: float
    belted: bool
    pretensioner_fire_s: float | None
    airbag_equipped: bool = False
    side_airbag: bool = False
    side_airbag_fire_s: float = math.nan


@dataclass(frozen=True)
class ContactSpec:
    """A contact between a body point (circle) and a surface segment."""

    name: str
    k_body: int
    p: float
    r: float
    radius: float
    a: tuple[float, float]
    b: tuple[float, float]
    motion: tuple[float, float] = (0.0, 0.0)
    channel: int = 0
    law: int = 0
    stiff: float = 0.0
    stiff3: float = 0.0
    damp: float = 0.0
    fcap: float = 0.0
    give: float = 10.0
    k_bottom: float = 0.0
    ramp: float = 0.005
    enabled: bool = True
    share: float = -1.0
    bottom_cap: float = 0.0
    crush_viscosity: float = 200.0
    hysteresis: float = 0.0
    crush_limit: float = 0.0

    def row(self, side: float) -> list[float]:
        """The contact as a row of the kernel's contact table.

        ``side`` (+1 or -1) orients the surface normal toward the occupant.
        """
        return [
            float(self.k_body),
            self.p,
            self.r,
            self.radius,
            self.a[0],
            self.a[1],
            self.b[0],
            self.b[1],
            self.motion[0],
            self.motion[1],
            float(self.channel),
            float(self.law),
            self.stiff,
            self.stiff3,
            self.damp,
            self.fcap,
            self.give,
            self.k_bottom,
            self.ramp,
            1.0 if self.enabled else 0.0,
            side,
        ]


@dataclass(frozen=True)
class Model:
    """Packed arrays of one case (see :mod:`models.lpm.kernel` for layouts).

    Attributes
    ----------
    plane : str
        "sagittal" or "coronal".
    ll : ndarray, shape (5,)
    mb : ndarray, shape (6, 5)
    jt : ndarray, shape (4, 7)
    ch : ndarray, shape (6,)
    se : ndarray, shape (4,)
    ct : ndarray, shape (nc, kernel.NCF)
    bt : ndarray, shape (nb, 20)
    bag : ndarray, shape (8,)
    y0 : ndarray, shape (12 + 2 nb + 2 nc,)
        Initial state; every contact's arming state 1 (kernel.ARM_TIME_S).
    contact_names, belt_names : tuple of str
    """

    plane: str
    ll: FloatArray
    mb: FloatArray
    jt: FloatArray
    ch: FloatArray
    se: FloatArray
    ct: FloatArray
    bt: FloatArray
    bag: FloatArray
    y0: FloatArray
    contact_names: tuple[str, ...]
    belt_names: tuple[str, ...]
    info: dict[str, float] = field(default_factory=dict)


def _u(a: float) -> np.ndarray:
    return np.array([math.sin(a), math.cos(a)])


def _w(a: float) -> np.ndarray:
    return np.array([math.cos(a), -math.sin(a)])


def _point(q: np.ndarray, ll: np.ndarray, k: int, p: float, r: float) -> np.ndarray:
    """Position of a body point (same convention as the kernel; d = 0 here), m."""
    jx = np.zeros(K.NQ)
    jz = np.zeros(K.NQ)
    px, pz, _, _ = K.kin(q, np.zeros(K.NQ), ll, k, p, r, jx, jz, 1.0)
    return np.array([px, pz])


#: Clearance (m) a side airbag leaves to the occupant it deploys toward when the
#: gap is narrower than the bag (see :func:`_gap_filling_bag`). [R]
SIDE_BAG_CLEARANCE = 0.005


def _gap_filling_bag(c: ContactSpec, q0: np.ndarray, ll: np.ndarray, depth: float) -> ContactSpec:
    """A side-airbag contact whose bag, fully deployed, stops short of the occupant.

    A bag deploying into a gap narrower than its depth (``side.airbag.depth``)
    fills the gap instead of striking a normally seated occupant: the bag
    surface is set back by the difference (less :data:`SIDE_BAG_CLEARANCE`) and
    the give shortened by as much, so that the door or window behind the bag
    (where the contact bottoms) stays where it is.
    """
    pos = _point(q0, ll, c.k_body if c.k_body <= 4 else 2, c.p, c.r)
    a, b = np.array(c.a), np.array(c.b)
    e = (b - a) / float(np.linalg.norm(b - a))
    gap = abs(float(e[0] * (pos[1] - a[1]) - e[1] * (pos[0] - a[0]))) - c.radius
    shift = max(0.0, depth - (gap - SIDE_BAG_CLEARANCE))
    if shift == 0.0:
        return c
    normal_away = np.array([e[1], -e[0]])  # unit normal; orient it away from the occupant
    if float(np.dot(normal_away, pos - a)) > 0.0:
        normal_away = -normal_away
    a2, b2 = a + shift * normal_away, b + shift * normal_away
    return replace(
        c,
        a=(float(a2[0]), float(a2[1])),
        b=(float(b2[0]), float(b2[1])),
        give=c.give - shift,
    )


def _seg(
    center: np.ndarray, direction: np.ndarray, half: float
) -> tuple[tuple[float, float], tuple[float, float]]:
    a = center - half * direction
    b = center + half * direction
    return (float(a[0]), float(a[1])), (float(b[0]), float(b[1]))


#: Determinant below which the glass and panel lines count as parallel (m^2):
#: segment directions are tenths of a metre long, so 1e-12 is ~1e-10 rad.
_PARALLEL_DET_M2 = 1e-12
#: Round-off allowance on the panel-face fraction where the lines meet
#: (dimensionless): a windshield designed to meet the panel top exactly.
_ON_FACE_TOLERANCE = 1e-9


def _glass_to_panel(
    low: tuple[float, float],
    high: tuple[float, float],
    panel_a: tuple[float, float],
    panel_b: tuple[float, float],
) -> tuple[float, float]:
    """Lower end of the windshield segment: where the glass line meets the panel face.

    The glass is the line through ``high`` (upper end) and ``low`` (a point
    of its lower part); it is run down to the line of the panel face
    (``panel_a``-``panel_b``) so that no gap is left between the panel top
    and the glass (a head used to pass over the panel top below ``low`` and
    leave the modelled interior). Positions in m, vehicle frame. If the lines
    do not meet below ``low``, ``low`` is kept.

    Raises
    ------
    ValueError
        When the glass line meets the panel's line outside the panel face
        (the glass would be run down to a point in front of or behind the
        panel: an inconsistent parameter set).
    """
    d0 = np.subtract(low, high)
    d1 = np.subtract(panel_b, panel_a)
    det = d0[0] * -d1[1] + d1[0] * d0[1]
    if abs(det) < _PARALLEL_DET_M2:
        return low
    rhs = np.subtract(panel_a, high)
    t = (rhs[0] * -d1[1] + d1[0] * rhs[1]) / det
    if t <= 1.0:
        return low
    # where on the panel face (0 at panel_a, 1 at panel_b) the lines meet
    s = (d0[0] * rhs[1] - d0[1] * rhs[0]) / det
    if not -_ON_FACE_TOLERANCE <= s <= 1.0 + _ON_FACE_TOLERANCE:
        raise ValueError(
            f"windshield line meets the panel line outside the panel face (at {s:.3f} of "
            "its length): check frontal.windshield.* against the dash/panel geometry"
        )
    return (float(high[0] + t * d0[0]), float(high[1] + t * d0[1]))


def _body_arrays(
    ps: ParameterSet, b: str, lateral: bool
) -> tuple[FloatArray, FloatArray, FloatArray]:
    pre = f"body.{b}."
    ll = np.array(
        [0.0, ps[pre + "length.lumbar"], ps[pre + "length.thorax"], ps[pre + "length.neck"], 0.0]
    )
    rib_r = ps[pre + "chest_half_width"] if lateral else ps[pre + "sternum_offset"]
    mb = np.array(
        [
            [0, 0.0, 0.0, ps[pre + "mass.pelvis"], 0.0],
            [1, ps[pre + "cg.abdomen"], 0.0, ps[pre + "mass.abdomen"], ps[pre + "inertia.abdomen"]],
            [2, ps[pre + "cg.thorax"], 0.0, ps[pre + "mass.thorax"], ps[pre + "inertia.thorax"]],
            [5, ps[pre + "sternum_height"], rib_r, ps[pre + "mass.sternum"], 0.0],
            [3, ps[pre + "cg.neck"], 0.0, ps[pre + "mass.neck"], ps[pre + "inertia.neck"]],
            [
                4,
                ps[pre + "cg.head_up"],
                ps[pre + "cg.head_forward"],
                ps[pre + "mass.head"],
                ps[pre + "inertia.head"],
            ],
        ],
        dtype=np.float64,
    )
    if lateral:
        mb[5, 2] = 0.0  # head CG on the mid-sagittal plane
    if lateral:
        ch = np.array(
            [
                ps[pre + "rib.stiffness"],
                0.0,
                ps[pre + "rib.damping"],
                ps[pre + "rib.bottom_deflection"],
                ps[pre + "rib.bottom_stiffness"],
                0.0,
            ]
        )
    else:
        ch = np.array(
            [
                ps[pre + "chest.stiffness"],
                ps[pre + "chest.stiffness3"],
                ps[pre + "chest.damping"],
                ps[pre + "chest.bottom_deflection"],
                ps[pre + "chest.bottom_stiffness"],
                ps["frontal.belt.sternum_share"],
            ]
        )
    return ll, mb, ch


def _joint_table(
    ps: ParameterSet, b: str, lateral: bool, q0: np.ndarray, qn: np.ndarray | None = None
) -> FloatArray:
    """Joint table; ``qn`` is the neutral posture (the stops bound the range from it).

    The occupant holds a forward lean with muscle tone, so the springs rest in
    the initial posture ``q0`` (an equilibrium at t = 0), but the end of each
    joint's range is anatomical: a lumbar flexion of 25 deg leaves 19 deg less
    flexion before the stop than the neutral 5.8 deg.
    """
    names = ("lumbar", "thoracic", "lower_neck", "upper_neck")
    jt = np.zeros((4, 7))
    qref = q0 if qn is None else qn
    for j, jn in enumerate(names):
        if lateral:
            pre = f"body.{b}.joint_lateral.{jn}."
            kf = ke = ps[pre + "k"]
        else:
            pre = f"body.{b}.joint.{jn}."
            kf, ke = ps[pre + "k_flexion"], ps[pre + "k_extension"]
        rest = q0[1] if j == 0 else q0[j + 1] - q0[j]
        rest_n = qref[1] if j == 0 else qref[j + 1] - qref[j]
        jt[j] = [
            kf,
            ke,
            ps[pre + "damping"],
            ps[pre + "stop_angle"],
            ps[pre + "k_stop"],
            rest,
            rest_n - rest,
        ]
    return jt


def _belt_row(
    k: int,
    p: float,
    r: float,
    a: tuple[float, float],
    b: tuple[float, float] | None,
    stiff: float,
    damp: float,
    slack: float,
    f_limit: float,
    c_limit: float,
    pt: tuple[float, float, float, float, float] | None,
    q0: np.ndarray,
    ll: np.ndarray,
    enabled: bool,
) -> list[float]:
    pt_max, pt_speed, pt_force, pt_t0, pt_t1 = (
        pt if pt is not None else (0.0, 0.0, 1.0, _NEVER, _NEVER)
    )
    pos = _point(q0, ll, k, p, r)
    length = float(np.hypot(*(np.asarray(a) - pos)))
    if b is not None:
        length += float(np.hypot(*(np.asarray(b) - pos)))
    bb = b if b is not None else (0.0, 0.0)
    return [
        float(k),
        p,
        r,
        a[0],
        a[1],
        bb[0],
        bb[1],
        1.0 if b is not None else 0.0,
        stiff,
        damp,
        slack,
        f_limit,
        c_limit,
        pt_max,
        pt_speed,
        pt_force,
        pt_t0,
        pt_t1,
        length,
        1.0 if enabled else 0.0,
    ]


@dataclass(frozen=True)
class _Surface:
    """A surface of the interior for one occupant: segment a-b, its motion and channel."""

    a: tuple[float, float]
    b: tuple[float, float]
    motion: tuple[float, float] = (0.0, 0.0)
    channel: int = 0


#: How a surface is drawn for a contact's body point (most ignore the point).
_SurfaceFn = Callable[[BodyPoint], _Surface]


def _fixed(surface: _Surface) -> _SurfaceFn:
    """A surface that does not depend on the contact's body point."""

    def draw(_pt: BodyPoint) -> _Surface:
        return surface

    return draw


def _contacts(
    rows: Sequence[ContactRow],
    points: Mapping[str, BodyPoint],
    surfaces: Mapping[str, _SurfaceFn],
    motions: Mapping[str, tuple[float, float]],
) -> list[ContactSpec]:
    """The kernel's contacts from the interior table's rows, in table order."""
    out = []
    for row in rows:
        pt = points[row.point]
        try:
            surface = surfaces[row.surface](pt)
        except KeyError:
            raise ParameterError(f"interior contact {row.name}: unknown surface") from None
        law: dict[str, Any] = dict(row.law)
        if "law" in law:
            law["law"] = int(law["law"])
        out.append(
            ContactSpec(
                row.name,
                pt.k,
                pt.p,
                pt.r,
                pt.radius,
                surface.a,
                surface.b,
                motions[row.motion] if row.motion is not None else surface.motion,
                channel=row.channel if row.channel is not None else surface.channel,
                enabled=row.enabled,
                hysteresis=row.hysteresis,
                **law,
            )
        )
    return out


def _posture_angles(ps: ParameterSet, lean_rad: float) -> np.ndarray:
    """Sagittal generalised coordinates of the seated posture leaning by `lean_rad`."""
    a1 = -math.radians(ps["posture.torso_recline"]) + lean_rad
    a2 = a1 + math.radians(ps["posture.thorax_relative"])
    a3 = math.radians(ps["posture.neck_angle"]) + 0.5 * lean_rad
    a4 = math.radians(ps["posture.head_angle"])
    return np.array([0.0, a1, a2, a3, a4, 0.0])


def _frontal_surfaces(
    ps: ParameterSet, occ: Occupant, ll: FloatArray, qn: np.ndarray, head: BodyPoint
) -> tuple[dict[str, _SurfaceFn], float]:
    """The frontal interior (vehicle fixed: shifted by -track) and the seat (seat fixed).

    Returns the surfaces and the depth of the frontal airbag, m. The front
    passenger has no wheel, a larger bag deploying from the instrument panel top
    and his own panel and knee-bolster geometry (``frontal.passenger.*``).
    """
    pre = f"body.{occ.body.value}."
    track = occ.seat_track_mm / 1000.0
    hub = np.array([ps["frontal.wheel.hub_x"] - track, ps["frontal.wheel.hub_z"]])
    ang = math.radians(ps["frontal.wheel.angle"])
    t_dir = np.array([-math.sin(ang), math.cos(ang)])
    n_dir = np.array([-math.cos(ang), -math.sin(ang)])
    wa, wb = _seg(hub, t_dir, ps["frontal.wheel.radius"])
    bag_depth = ps["frontal.airbag.depth"]
    if occ.seat is Seat.FRONT_PASSENGER:
        module = np.array(
            [
                ps["frontal.passenger.airbag.module_x"] - track,
                ps["frontal.passenger.airbag.module_z"],
            ]
        )
        pang = math.radians(ps["frontal.passenger.airbag.angle"])
        pt_dir = np.array([-math.sin(pang), math.cos(pang)])
        pn_dir = np.array([-math.cos(pang), -math.sin(pang)])
        ba, bb = _seg(module, pt_dir, ps["frontal.passenger.airbag.half_height"])
        bag_motion = (float(pn_dir[0]), float(pn_dir[1]))
        bag_depth = ps["frontal.passenger.airbag.depth"]
        dash_pre = "frontal.passenger.dash."
        knee_gap = ps["frontal.passenger.knee_gap"]
    else:
        ba, bb = _seg(hub, t_dir, ps["frontal.airbag.half_height"])
        bag_motion = (float(n_dir[0]), float(n_dir[1]))
        dash_pre = "frontal.dash."
        knee_gap = ps["frontal.knee.gap"]
    dash_a = (ps[dash_pre + "x0"] - track, ps[dash_pre + "z0"])
    dash_b = (ps[dash_pre + "x1"] - track, ps[dash_pre + "z1"])
    ws_a = _glass_to_panel(
        (ps["frontal.windshield.x0"] - track, ps["frontal.windshield.z0"]),
        (ps["frontal.windshield.x1"] - track, ps["frontal.windshield.z1"]),
        dash_a,
        dash_b,
    )
    ws_b = (ps["frontal.windshield.x1"] - track, ps["frontal.windshield.z1"])
    # knee bolster: placed for the 50M at mid track with the stated gap, so
    # other bodies get their own gap
    x_bolster = (
        ps["body.male_50th.thigh_length"] + ps["body.male_50th.knee_radius"] + knee_gap - track
    )
    kz = ps["body.male_50th.knee_height"]
    kh = float(surface_size(ps, "knee_bolster_half_height"))
    # the thighs: a surface carried by the pelvis (kernel channel 4), from
    # thigh_surface_start of the thigh length forward of the H-point to the top
    # of the knee, for the head and chest of an occupant folding over the lap belt
    tl = ps[pre + "thigh_length"]
    thigh_a = (ps[pre + "thigh_surface_start"] * tl, ps[pre + "thigh_top"])
    thigh_b = (tl, ps[pre + "knee_height"] + ps[pre + "knee_radius"])
    # seat back and head restraint (seat fixed): touching in the neutral posture
    sb = -math.radians(ps["seat.back_angle"])
    n_sb = _w(sb)
    u_sb = _u(sb)
    back_half = float(surface_size(ps, "seat_back_half_length"))
    hr_half = float(surface_size(ps, "head_restraint_half_length"))

    def seat_back(pt: BodyPoint) -> _Surface:
        centre = _point(qn, ll, pt.k, pt.p, pt.r) - (pt.radius + _CLEAR) * n_sb
        return _Surface(*_seg(centre, u_sb, back_half))

    def head_restraint(pt: BodyPoint) -> _Surface:
        head_pos = _point(qn, ll, pt.k, pt.p, pt.r)
        centre = head_pos - (pt.radius + ps["seat.head_restraint_backset"] + _CLEAR) * n_sb
        return _Surface(*_seg(centre, u_sb, hr_half))

    del head  # the head restraint is drawn from the contact's own point
    fixed = {
        "frontal_airbag": _Surface(ba, bb, bag_motion, 2),
        "steering_wheel": _Surface(wa, wb),
        "windshield": _Surface(ws_a, ws_b),
        "instrument_panel": _Surface(dash_a, dash_b),
        "knee_bolster": _Surface((x_bolster, kz - kh), (x_bolster, kz + kh)),
        "thighs": _Surface(thigh_a, thigh_b, (1.0, 0.0), 4),
    }
    surfaces: dict[str, _SurfaceFn] = {name: _fixed(s) for name, s in fixed.items()}
    surfaces["seat_back"] = seat_back
    surfaces["head_restraint"] = head_restraint
    return surfaces, bag_depth


def _frontal_belts(
    ps: ParameterSet, occ: Occupant, rs: Restraints, q0: np.ndarray, ll: FloatArray
) -> list[list[float]]:
    """Shoulder and lap belt rows (retractor load limiter, pretensioner)."""
    b = occ.body.value
    h_s, r_s = ps[f"body.{b}.sternum_height"], ps[f"body.{b}.sternum_offset"]
    track = occ.seat_track_mm / 1000.0
    pt = None
    if rs.pretensioner_fire_s is not None:
        t0 = rs.pretensioner_fire_s
        pt = (
            ps["frontal.belt.pretensioner_stroke"],
            ps["frontal.belt.pretensioner_speed"],
            ps["frontal.belt.pretensioner_force"],
            t0,
            t0 + ps["frontal.belt.pretensioner_duration"],
        )
    load_limit = ps[
        "frontal.belt.load_limit_airbag" if rs.airbag_equipped else "frontal.belt.load_limit"
    ]
    dring = (ps["frontal.belt.dring_x"] - track, ps["frontal.belt.dring_z"])
    buckle = (ps["frontal.belt.buckle_x"], ps["frontal.belt.buckle_z"])
    lap_a = (ps["frontal.belt.lap_anchor_x"], ps["frontal.belt.lap_anchor_z"])
    c_ll = ps["frontal.belt.limiter_viscosity"]
    return [
        _belt_row(
            6,
            h_s,
            r_s + 0.01,
            dring,
            buckle,
            ps["frontal.belt.shoulder_stiffness"],
            ps["frontal.belt.shoulder_damping"],
            ps["frontal.belt.shoulder_slack"],
            load_limit,
            c_ll,
            pt,
            q0,
            ll,
            rs.belted,
        ),
        _belt_row(
            0,
            0.08,
            0.03,
            lap_a,
            None,
            ps["frontal.belt.lap_stiffness"],
            ps["frontal.belt.lap_damping"],
            ps["frontal.belt.lap_slack"],
            ps["frontal.belt.load_limit_lap"],
            c_ll,
            None,
            q0,
            ll,
            rs.belted,
        ),
    ]


def _frontal_bag_schedule(
    ps: ParameterSet, rs: Restraints, bag_depth: float
) -> tuple[FloatArray, float]:
    """The frontal airbag's timing row (kernel bag layout) and its full-inflation time, s."""
    t_start = rs.airbag_fire_s + ps["frontal.airbag.delay"]
    t_full = t_start + ps["frontal.airbag.fill_time"]
    bag = np.array(
        [
            t_start if rs.airbag else _NEVER,
            t_full if rs.airbag else _NEVER + 1.0,
            bag_depth if rs.airbag else 0.0,
            t_full + ps["frontal.airbag.vent_start"],
            ps["frontal.airbag.vent_duration"],
            ps["frontal.airbag.vent_fraction"],
            ps["frontal.airbag.deployment_damping"] / ps["frontal.airbag.damping"],
            ps["frontal.airbag.deployment_stiffness"],
        ]
    )
    return bag, t_full


def _sagittal(ps: ParameterSet, occ: Occupant, rs: Restraints) -> Model:
    """The frontal and rear model: the sagittal plane, the interior of the parameter set."""
    b = occ.body.value
    ll, mb, ch = _body_arrays(ps, b, lateral=False)
    lean = math.radians(occ.posture_lumbar_flexion_deg - ps["posture.neutral_lumbar_flexion"])
    q0 = _posture_angles(ps, lean)
    qn = _posture_angles(ps, 0.0)
    jt = _joint_table(ps, b, False, q0, qn)
    mass = float(mb[:, 3].sum())
    se = np.array([ps["seat.friction"], mass * ps["seat.gravity"], ps["seat.slip_speed"], 0.0])
    conditions = [
        c
        for c, on in (("airbag", rs.airbag), ("driver", occ.seat is not Seat.FRONT_PASSENGER))
        if on
    ]
    points, rows = interior_plane(ps, "sagittal", b, lambda k: float(ll[k]), conditions)
    surfaces, bag_depth = _frontal_surfaces(ps, occ, ll, qn, points["head"])
    contacts = _contacts(rows, points, surfaces, {})
    belts = _frontal_belts(ps, occ, rs, q0, ll)
    bag, t_full = _frontal_bag_schedule(ps, rs, bag_depth)
    return _finish(
        "sagittal",
        ll,
        mb,
        jt,
        ch,
        se,
        contacts,
        belts,
        ("shoulder", "lap"),
        bag,
        q0,
        {
            "airbag_fire_s": rs.airbag_fire_s if rs.airbag else math.nan,
            "t_full_s": t_full if rs.airbag else math.nan,
            "airbag_depth_m": bag_depth,
            "pretensioner_fire_s": (
                rs.pretensioner_fire_s if rs.pretensioner_fire_s is not None else math.nan
            ),
        },
    )


def _side_surfaces(
    ps: ParameterSet, q0: np.ndarray, ll: FloatArray, head: BodyPoint, far: bool
) -> tuple[dict[str, _SurfaceFn], dict[str, tuple[float, float]]]:
    """The side interior: door and window (near side), console, seat and far door (far side).

    Returns the surfaces and the named motions of the intruding ones.
    """
    up = ps["side.upper_intrusion_ratio"]
    # a head whose CG sits below the top of the striking barrier face is hit
    # by the barrier through the window with the full door intrusion (the
    # IIHS barrier represents a pickup/SUV front at a small occupant's head
    # height); a taller occupant's head sees the smaller upper intrusion
    head_z = float(_point(q0, ll, head.k, head.p, head.r)[1])
    up_head = 1.0 if head_z < ps["side.barrier_top_z"] else up
    motions = {
        "intrusion": (-1.0, 0.0),
        "upper_intrusion": (-up, 0.0),
        "head_intrusion": (-up_head, 0.0),
    }
    if not far:
        dx, zl, zh = ps["side.door_x"], ps["side.door_z_low"], ps["side.door_z_high"]
        wx, wz = ps["side.window_x"], ps["side.window_z_high"]
        fixed = {
            "door": _Surface((dx, zl), (dx, zh)),
            "window": _Surface((wx, zh), (ps["side.window_top_x"], wz)),  # tumblehome
        }
    else:
        cx, cz = ps["side.far.console_x"], ps["side.far.console_z_high"]
        sx, fx = ps["side.far.seat_x"], ps["side.far.door_x"]
        seat_z = surface_size(ps, "far_seat_z")
        fixed = {
            "console": _Surface((cx, float(surface_size(ps, "console_z_low"))), (cx, cz)),
            "far_seat": _Surface((sx, float(seat_z[0])), (sx, float(seat_z[1]))),
            "far_door": _Surface(
                (fx, float(surface_size(ps, "far_door_z_low"))), (fx, ps["side.window_z_high"])
            ),
        }
    return {name: _fixed(s) for name, s in fixed.items()}, motions


def _far_side_belt(ps: ParameterSet, rs: Restraints, q0: np.ndarray, ll: FloatArray) -> list[float]:
    """The far-side shoulder belt (the lap belt does not act in the coronal plane)."""
    load_limit = ps[
        "frontal.belt.load_limit_airbag" if rs.airbag_equipped else "frontal.belt.load_limit"
    ]
    return _belt_row(
        2,
        0.9 * ll[2],
        0.0,
        (ps["side.far.dring_x"], ps["side.far.dring_z"]),
        None,
        ps["side.far.shoulder_belt_stiffness"],
        ps["frontal.belt.shoulder_damping"],
        ps["frontal.belt.shoulder_slack"],
        load_limit,
        ps["frontal.belt.limiter_viscosity"],
        None,
        q0,
        ll,
        rs.belted,
    )


def _coronal(ps: ParameterSet, occ: Occupant, rs: Restraints, far: bool) -> Model:
    """The near- and far-side models: the coronal plane, the interior of the parameter set."""
    b = occ.body.value
    ll, mb, ch = _body_arrays(ps, b, lateral=True)
    # forward lean shortens the chain as seen in the coronal plane
    lean = math.radians(occ.posture_lumbar_flexion_deg - ps["posture.neutral_lumbar_flexion"])
    tilt = math.radians(ps["posture.torso_recline"]) - lean
    ll[1:4] *= math.cos(tilt) / math.cos(math.radians(ps["posture.torso_recline"]))
    q0 = np.zeros(K.NQ)
    jt = _joint_table(ps, b, True, q0)
    mass = float(mb[:, 3].sum())
    slip = ps["side.slip_damping"] * (ps["side.belt_slip_factor"] if rs.belted else 1.0)
    se = np.array([ps["seat.friction"], mass * ps["seat.gravity"], ps["seat.slip_speed"], slip])
    plane = "far_side" if far else "near_side"
    conditions = ["side_airbag"] if rs.side_airbag else ["no_side_airbag"]
    points, rows = interior_plane(ps, plane, b, lambda k: float(ll[k]), conditions)
    surfaces, motions = _side_surfaces(ps, q0, ll, points["head"], far)
    contacts = [
        _gap_filling_bag(c, q0, ll, ps["side.airbag.depth"]) if row.fills_gap else c
        for c, row in zip(_contacts(rows, points, surfaces, motions), rows, strict=True)
    ]
    belts = [_far_side_belt(ps, rs, q0, ll)] if far else []
    belt_names: tuple[str, ...] = ("shoulder",) if far else ()
    info: dict[str, float] = {}
    if rs.side_airbag and not far:
        # the coronal model has no frontal airbag: its bag timing row serves the
        # side and curtain bags (kernel channel 3); sealed bags, no venting
        t_start = rs.side_airbag_fire_s + ps["side.airbag.delay"]
        t_full = t_start + ps["side.airbag.fill_time"]
        bag = np.array([t_start, t_full, ps["side.airbag.depth"], _NEVER, 1.0, 1.0, 1.0, 0.0])
        info = {"side_airbag_fire_s": rs.side_airbag_fire_s, "side_airbag_t_full_s": t_full}
    else:
        bag = np.array([_NEVER, _NEVER + 1.0, 0.0, _NEVER, 1.0, 1.0, 0.0, 0.0])
    return _finish("coronal", ll, mb, jt, ch, se, contacts, belts, belt_names, bag, q0, info)


def _finish(
    plane: str,
    ll: FloatArray,
    mb: FloatArray,
    jt: FloatArray,
    ch: FloatArray,
    se: FloatArray,
    contacts: list[ContactSpec],
    belts: list[list[float]],
    belt_names: tuple[str, ...],
    bag: FloatArray,
    q0: np.ndarray,
    info: dict[str, float],
) -> Model:
    rows = []
    # every contact point at rest in one call (the numbers of _point for each)
    at_rest = K.points_at_rest(
        q0,
        ll,
        np.array([c.k_body for c in contacts], dtype=np.int64),
        np.array([c.p for c in contacts], dtype=np.float64),
        np.array([c.r for c in contacts], dtype=np.float64),
    ).tolist()
    for c, pos in zip(contacts, at_rest, strict=True):
        ex, ez = c.b[0] - c.a[0], c.b[1] - c.a[1]
        side = 1.0 if (-ez * (pos[0] - c.a[0]) + ex * (pos[1] - c.a[1])) >= 0.0 else -1.0
        length = math.hypot(ex, ez)
        ux, uz = ex / length, ez / length
        rows.append(
            c.row(side)
            + [ux, uz, length, -uz * side, ux * side, c.share, c.bottom_cap, c.crush_viscosity]
            + [c.hysteresis, c.crush_limit]
        )
    ct = np.array(rows, dtype=np.float64).reshape(-1, K.NCF)
    bt = np.array(belts, dtype=np.float64).reshape(-1, K.NBF)
    y0 = np.zeros(2 * K.NQ + 2 * bt.shape[0] + 2 * ct.shape[0])
    y0[: K.NQ] = q0
    y0[2 * K.NQ + 2 * bt.shape[0] + ct.shape[0] :] = 1.0  # every contact armed at rest
    return Model(
        plane,
        np.ascontiguousarray(ll),
        np.ascontiguousarray(mb),
        np.ascontiguousarray(jt),
        ch,
        se,
        np.ascontiguousarray(ct),
        np.ascontiguousarray(bt),
        bag,
        y0,
        tuple(c.name for c in contacts),
        belt_names,
        info,
    )


def build_model(
    mode: ImpactMode, occupant: Occupant, params: ParameterSet, restraints: Restraints
) -> Model:
    """Assemble the kernel arrays of one case.

    Parameters
    ----------
    mode : ImpactMode
        FRONTAL and REAR use the sagittal model, NEAR_SIDE and FAR_SIDE the
        coronal one.
    occupant : Occupant
        Body, posture and seat track are used here; belt and airbag states
        come through ``restraints``.
    params : ParameterSet
    restraints : Restraints
        Resolved restraint states and firing times.

    Returns
    -------
    Model
    """
    if occupant.body not in (Body.MALE_50TH, Body.FEMALE_5TH):
        raise ValueError(f"unsupported body {occupant.body!r}")
    if mode in (ImpactMode.FRONTAL, ImpactMode.REAR):
        return _sagittal(params, occupant, restraints)
    return _coronal(params, occupant, restraints, far=mode is ImpactMode.FAR_SIDE)
