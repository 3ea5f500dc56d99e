"""Numba kernel of the 2-D occupant lumped parameter models (LPMs).

One planar multibody model serves all four impact modes; the mode only changes
the plane (sagittal for frontal/rear, coronal for the side modes), the
contacts, the belts and the parameter values (assembled in
:mod:`models.lpm.assemble`).

Generalised coordinates ``q`` (shape (6,)), in the vehicle frame of the model
plane (x toward the impact for the side modes, x forward for the sagittal
modes; z up; origin at the initial H-point):

====  ==========================================================  =====
idx   meaning                                                     unit
====  ==========================================================  =====
0     pelvis (H-point) displacement along x, sliding on the seat  m
1     absolute angle of the abdomen/lumbar link from vertical     rad
2     absolute angle of the thorax link                           rad
3     absolute angle of the neck link                             rad
4     absolute angle of the head                                  rad
5     chest (sternum or near-side rib) deflection, + compression  m
====  ==========================================================  =====

Angles are positive when the link tilts toward +x. The state vector is
``y = [q, qdot, belt states]`` with two belt states per belt (webbing paid out
by the load limiter, webbing reeled in by the pretensioner), then one state per
contact (permanent crush of the structure behind the contact's give, m), then
one more per contact (its arming, 0-1: see :data:`ARM_TIME_S`):
shape (12 + 2 nb + 2 nc,).

The vehicle frame is not inertial: every mass carries ``-m a_veh`` along x,
with ``a_veh`` the vehicle acceleration resolved on the model axis. Gravity
is left out of the 200 ms event (seat friction uses the static weight as the
normal force), so that the initial posture is an exact equilibrium and a zero
pulse gives an exactly zero response.

Body point convention: a point is ``(k, p, r)``: on body ``k`` (0 pelvis,
1 abdomen, 2 thorax, 3 neck, 4 head, 5 sternum/rib), ``p`` metres along the
link axis ``u(a) = (sin a, cos a)`` from the link's lower joint and ``r``
metres along ``w(a) = (cos a, -sin a)`` (toward +x when upright). The pelvis
does not rotate: its points are fixed offsets ``(p, r)`` = (dx, dz). For the
sternum (k = 5) the point is ``p`` along the thorax link and ``r - d`` along
``w``, so that the chest deflection ``d`` moves it toward the spine; a k = 6
point follows only the share ``ch[5]`` of ``d`` (the shoulder-belt path and the
airbag's chest contact, which also bear on the shoulders and ribs).

Integrators: :func:`integrate_se` (semi-implicit Euler, production, one
right-hand side per step) and :func:`integrate_rk4`; both compiled with
``nogil`` so that cases can run in parallel threads.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from models.constants import G_MS2

__all__ = [
    "BAG_FIELDS",
    "BELT_FIELDS",
    "CONTACT_FIELDS",
    "ARM_TIME_S",
    "DIAG_FIXED",
    "GAP_NONE",
    "EDGE_RADIUS_M",
    "NQ",
    "diag_size",
    "integrate_rk4",
    "integrate_se",
    "kin",
    "points_at_rest",
    "rhs",
    "rhs_into",
]

NQ = 6
#: Standard gravity, m/s^2 (models.constants; the kernel's name for it).
G0 = G_MS2

#: Compile option of the hot loops: numba's private ``_nrt=False`` flag turns
#: off reference counting (NRT) in functions that allocate nothing. With it on,
#: every inlined helper call and row view in the right-hand side costs atomic
#: incref/decref pairs, which made the kernel about 5x slower. Passed as a dict
#: because the flag is not part of numba's typed signature.
_NO_NRT: dict[str, Any] = {"_nrt": False}

# --- column layouts of the packed parameter arrays -------------------------
# Mass table MB (nm, 5): k, p, r, mass (kg), rotational inertia (kg m^2, about CG)
# Joint table JT (4, 7): k_flex (N m/rad), k_ext (N m/rad), c (N m s/rad),
#   stop angle (rad), stop stiffness (N m/rad), rest relative angle (rad),
#   offset of the stop centre from the rest angle (rad; neutral rest - rest)
# Link lengths LL (5,): LL[j] length of link j (m), LL[0] unused
# Chest CH (6,): k (N/m), k3 (N/m^3), c (N s/m), bottoming deflection (m),
#   bottoming stiffness (N/m), share of the deflection followed by k = 6 points (-)
# Seat SE (4,): friction coefficient, normal force (N), regularisation speed (m/s),
#   slip damping (N s/m)
# Contacts CT (nc, NCF), one row per contact, columns CONTACT_FIELDS. The surface
#   moves by (mx, mz) times its motion channel: 0 fixed; 1 door intrusion (m);
#   2 frontal airbag depth (BAG timing); 3 side airbag: door intrusion plus the
#   BAG depth along the surface normal (a bag deploying from the door or roof
#   rail toward the occupant and riding on the intrusion); 4 carried by the
#   pelvis (the thighs: moves with the pelvis slide q[0], reacts on it).
#   law 0: elastic(-plastic) spring-damper; law 1: airbag (constant-force
#   plateau, pressure rise, damper)
CONTACT_FIELDS = (
    "k_body",
    "p",
    "r",
    "radius",
    "ax",
    "az",
    "bx",
    "bz",
    "mx",
    "mz",
    "channel",
    "law",
    "stiff",
    "stiff3",
    "damp",
    "fcap",
    "give",
    "k_bottom",
    "ramp",
    "enabled",
    "side",
    "ux",
    "uz",
    "length",
    "nx",
    "nz",
    "share",
    "bottom_cap",
    "crush_viscosity",
    "hysteresis",
    "crush_limit",
)
C_KB, C_P, C_R, C_RAD, C_AX, C_AZ, C_BX, C_BZ, C_MX, C_MZ, C_CH, C_LAW = range(12)
C_K, C_K3, C_C, C_FCAP, C_GIVE, C_KBOT, C_RAMP, C_EN, C_SIDE = range(12, 21)
C_UX, C_UZ, C_LEN, C_NX, C_NZ = range(21, 26)  # derived: unit direction, length, normal
# share of the chest deflection followed by a k = 6 contact point (< 0: use ch[5])
C_SHARE = 26
# force limit of the structure behind the give (secondary crush plateau, N; 0: none)
C_BCAP = 27
# viscosity of the crush beyond the give (N s/m): crush rate = (F - bottom_cap) / c
C_CCR = 28
# share of the elastic force NOT returned while the contact unloads (0: elastic)
C_HYST = 29
# stroke limit of the crush beyond the give (m; 0: unlimited): a crushed
# structure that has used its stroke is backed by the next, stiffer one
C_CLIM = 30
NCF = len(CONTACT_FIELDS)

#: Penetration speed (m/s) over which the unloading branch of a hysteretic
#: contact is blended in (``pendot`` from 0 to ``-UNLOAD_BLEND_SPEED``). [R]
#: A regularised sign of the penetration rate, like the seat friction's slip
#: speed (``seat.slip_speed``, 0.05 m/s): a hard switch at ``pendot = 0``
#: would chatter at the turning point; 0.1 m/s is small against the 2-10 m/s
#: impact speeds of the occupant on the interior, so the dissipated energy is
#: within a few per cent of the ideal hysteresis loop.
UNLOAD_BLEND_SPEED = 0.1

#: Time constant (s) of a contact's arming state. [R] A one-sided surface is
#: met from its front only. A point that goes around an end of the segment
#: (the head over the wheel rim or the top of the bag) and later comes back
#: into the segment's span from behind would otherwise be in contact at once
#: with a penetration of tens of millimetres: a force step of several kN in
#: one time step (measured before this state existed: on 14 % of the held-out
#: runs of the belted 50M without airbag the wheel-head penetration jumped by
#: more than 5 mm in one 0.1 ms step; at 55 km/h the step gave Nij 1.19 against
#: 0.74-0.83 at 54 and 56 km/h). The arming state ``A`` follows
#: ``dA/dt = (target - A) / ARM_TIME_S`` while the point is out of contact,
#: with target 1 in front of the surface and 0 once it has gone around an end
#: (beyond the span, behind the face line) or deep behind a crushable
#: structure; in contact ``A`` is held, and the contact force (and the crush
#: rate) is scaled by ``A``. Because ``A`` changes only while the force is
#: zero, a contact stays conservative (or dissipative) as before. 1 ms: short
#: against the tens of milliseconds between going around a rim and coming
#: back, ten steps of the 0.1 ms integration step (explicit Euler on the
#: relaxation is stable for dt < 2 ARM_TIME_S).
ARM_TIME_S = 1.0e-3

#: Arming state above which a contact counts as armed in the diagnostics
#: (its clearance and penetration are reported). [R] ``A`` relaxes to 0 or 1
#: with :data:`ARM_TIME_S`; half-way is the natural cut between "in front of the
#: surface" and "gone around it". Only the diagnostics use it, not the forces.
ARMED_DIAGNOSTIC = 0.5

#: Radius (m) of the rounded edge at each end of a contact surface. [R] Before,
#: the end was sharp (a point radius around the end point, from the front
#: only): a head deep in the driver bag (its centre behind the bag face line)
#: that slid past the end of the face lost the whole bag force in one step and
#: regained it when it slid back (measured: 2.4 kN off and 2.7 kN on within
#: 1.3 ms, unbelted 50M at 40 km/h). A cylinder tangent to the face makes the
#: penetration continuous across the end for centres up to this far behind the
#: face line. Measured (tests/lpm/test_contact_continuity.py grid): 0.05 m left
#: one step (head 0.164 m into the bag, 0.064 m behind its face: 210 -> 2031 N,
#: belted 50M, 59.6 km/h); 0.08 m leaves none. It adds at most
#: sqrt(r^2 + 2 r R) - r = 0.06 m (head, r = 0.1 m) of reach beyond an end, of
#: the order of the rounded edges of trim, rims and cushions. A side effect,
#: not the reason for the value: with 0.08 m the belted 50M's HIC15 without
#: airbag rises with delta-V over 20-120 km/h (with 0.05 m it fell at 70 -> 80
#: km/h, 823 -> 716, his head sliding over the top of the rim).
EDGE_RADIUS_M = 0.08

BELT_FIELDS = (
    "k_body",
    "p",
    "r",
    "ax",
    "az",
    "bx",
    "bz",
    "has_b",
    "stiff",
    "damp",
    "slack",
    "f_limit",
    "c_limit",
    "pt_max",
    "pt_speed",
    "pt_force",
    "pt_t0",
    "pt_t1",
    "length0",
    "enabled",
)
B_KB, B_P, B_R, B_AX, B_AZ, B_BX, B_BZ, B_HASB, B_K, B_C, B_SLACK = range(11)
B_FLL, B_CLL, B_PTMAX, B_PTV, B_PTF, B_PTT0, B_PTT1, B_L0, B_EN = range(11, 20)
NBF = len(BELT_FIELDS)

# Airbag timing BAG (8,): inflation start (s), full deployment (s), depth (m),
#   vent start (s), vent duration (s), vent residual fraction, deployment
#   (punch-out) damping as a fraction of the bag damper, deployment stiffness (N/m)
BAG_FIELDS = (
    "t_start",
    "t_full",
    "depth",
    "t_vent",
    "vent_duration",
    "vent_fraction",
    "deploy_damping_ratio",
    "deploy_stiffness",
)

# Diagnostics row layout (fixed part); then contact forces (nc), belt forces (nb),
# contact penetrations (nc), contact gaps (nc: the signed clearance of the
# contact point to the undeformed surface, m, positive apart; GAP_NONE where
# the surface is absent or the point is behind it)
D_HEAD_AX, D_HEAD_AZ, D_CHEST_AX, D_CHEST_AZ, D_PELV_AX = range(5)
D_NECK_FX, D_NECK_FZ, D_NECK_MY, D_P_PULSE, D_P_ACTIVE, D_KE, D_V_INT = range(5, 12)
DIAG_FIXED = 12

#: Gap recorded for a contact whose surface is not there (disabled, bag not
#: out) or that the point passes behind (disarmed), m: farther than any
#: interior distance of the models.
GAP_NONE = 1.0


@njit(cache=True)
def diag_size(nc: int, nb: int) -> int:
    """Columns of a diagnostics row for `nc` contacts and `nb` belts."""
    return DIAG_FIXED + 3 * nc + nb


@njit(cache=True, error_model="numpy")
def kin(
    q: np.ndarray,
    qd: np.ndarray,
    ll: np.ndarray,
    k: int,
    p: float,
    r: float,
    jx: np.ndarray,
    jz: np.ndarray,
    beta: float = 1.0,
) -> tuple[float, float, float, float]:
    """Kinematics of a body point (computes the link sines and cosines itself).

    See :func:`kin_sc` for the parameters and results.
    """
    sn = np.zeros(NQ)
    cs = np.zeros(NQ)
    for j in range(1, 5):
        sn[j] = math.sin(q[j])
        cs[j] = math.cos(q[j])
    return kin_sc(q, qd, ll, sn, cs, k, p, r, jx, jz, beta)


@njit(cache=True, inline="always", error_model="numpy")
def kin_sc(
    q: np.ndarray,
    qd: np.ndarray,
    ll: np.ndarray,
    sn: np.ndarray,
    cs: np.ndarray,
    k: int,
    p: float,
    r: float,
    jx: np.ndarray,
    jz: np.ndarray,
    beta: float,
) -> tuple[float, float, float, float]:
    """Kinematics of a body point.

    Parameters
    ----------
    q, qd : ndarray, shape (6,)
        Coordinates and velocities.
    ll : ndarray, shape (5,)
        Link lengths, m.
    sn, cs : ndarray, shape (6,)
        sin and cos of the link angles q[1:5] (entries 1..4).
    k : int
        Body index (0 pelvis ... 4 head, 5 sternum, 6 belt path on the chest:
        a point that follows the sternum by the fraction ``beta``).
    p, r : float
        Point coordinates on the body, m.
    jx, jz : ndarray, shape (6,)
        Output: Jacobian rows of the point position (x and z).

    Returns
    -------
    (px, pz, ddx, ddz) : tuple of float
        Position (m) and the velocity-product acceleration J-dot q-dot (m/s^2).
    """
    for i in range(NQ):
        jx[i] = 0.0
        jz[i] = 0.0
    jx[0] = 1.0
    if k == 0:
        return q[0] + p, r, 0.0, 0.0
    top = 2 if k >= 5 else k
    bd = 1.0 if k == 5 else beta
    px = q[0]
    pz = 0.0
    ddx = 0.0
    ddz = 0.0
    for j in range(1, top):
        s = sn[j]
        c = cs[j]
        lj = ll[j]
        px += lj * s
        pz += lj * c
        jx[j] = lj * c
        jz[j] = -lj * s
        w2 = qd[j] * qd[j]
        ddx -= lj * s * w2
        ddz -= lj * c * w2
    s = sn[top]
    c = cs[top]
    rr = r
    if k >= 5:
        rr = r - bd * q[5]
    # p u + rr w
    px += p * s + rr * c
    pz += p * c - rr * s
    # d/da (p u + rr w) = p w - rr u
    jx[top] = p * c - rr * s
    jz[top] = -p * s - rr * c
    w2 = qd[top] * qd[top]
    # -(p u + rr w) a'^2
    ddx -= (p * s + rr * c) * w2
    ddz -= (p * c - rr * s) * w2
    if k >= 5:
        # d/dd = -bd w ; cross term 2 bd d' a' u
        jx[5] = -bd * c
        jz[5] = bd * s
        ddx += 2.0 * bd * qd[5] * qd[top] * s
        ddz += 2.0 * bd * qd[5] * qd[top] * c
    return px, pz, ddx, ddz


@njit(cache=True, error_model="numpy")
def points_at_rest(
    q: np.ndarray, ll: np.ndarray, ks: np.ndarray, ps: np.ndarray, rs: np.ndarray
) -> np.ndarray:
    """Positions of several body points at rest (:func:`kin` of each, its numbers).

    Parameters
    ----------
    q : ndarray, shape (6,)
        Coordinates.
    ll : ndarray, shape (5,)
        Link lengths, m.
    ks : ndarray of int64, shape (m,)
        Body of each point (see :func:`kin_sc`).
    ps, rs : ndarray, shape (m,)
        Point coordinates on their bodies, m.

    Returns
    -------
    ndarray, shape (m, 2)
        x and z of each point, m; the link sines and cosines computed once.
    """
    sn = np.zeros(NQ)
    cs = np.zeros(NQ)
    for j in range(1, 5):
        sn[j] = math.sin(q[j])
        cs[j] = math.cos(q[j])
    qd = np.zeros(NQ)
    jx = np.zeros(NQ)
    jz = np.zeros(NQ)
    out = np.empty((ks.shape[0], 2))
    for i in range(ks.shape[0]):
        px, pz, _, _ = kin_sc(q, qd, ll, sn, cs, ks[i], ps[i], rs[i], jx, jz, 1.0)
        out[i, 0] = px
        out[i, 1] = pz
    return out


@njit(cache=True, inline="always", error_model="numpy")
def pos_sc(
    q: np.ndarray,
    ll: np.ndarray,
    sn: np.ndarray,
    cs: np.ndarray,
    k: int,
    p: float,
    r: float,
    beta: float,
) -> tuple[float, float]:
    """Position only of a body point (cheap test before a contact is evaluated), m."""
    if k == 0:
        return q[0] + p, r
    top = 2 if k >= 5 else k
    px = q[0]
    pz = 0.0
    for j in range(1, top):
        px += ll[j] * sn[j]
        pz += ll[j] * cs[j]
    rr = r
    if k == 5:
        rr = r - q[5]
    elif k == 6:
        rr = r - beta * q[5]
    px += p * sn[top] + rr * cs[top]
    pz += p * cs[top] - rr * sn[top]
    return px, pz


@njit(cache=True, inline="always", error_model="numpy")
def _interp(t: float, t0: float, dt: float, arr: np.ndarray) -> float:
    """Linear interpolation of a uniformly sampled channel; 0 outside."""
    n = arr.shape[0]
    x = (t - t0) / dt
    if x <= 0.0:
        return arr[0] if x > -1e-12 else 0.0
    i = int(math.floor(x))
    if i >= n - 1:
        return arr[n - 1]
    f = x - i
    return arr[i] * (1.0 - f) + arr[i + 1] * f


@njit(cache=True, inline="always", error_model="numpy")
def _bag_state(t: float, bag: np.ndarray) -> tuple[float, float, float, float, float]:
    """Airbag depth (m), depth rate (m/s), force scale (-), damper factor (-) and
    deployment stiffness (N/m, non-zero while the bag fills)."""
    t_start = bag[0]
    t_full = bag[1]
    depth = bag[2]
    if t <= t_start or depth <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0
    if t < t_full:
        x = (t - t_start) / (t_full - t_start)
        sm = x * x * (3.0 - 2.0 * x)
        dsm = 6.0 * x * (1.0 - x) / (t_full - t_start)
        # punch-out terms fade out as the bag reaches full deployment (no force jump)
        return depth * sm, depth * dsm, 1.0, bag[6] * (1.0 - x) + x, bag[7] * (1.0 - x)
    scale = 1.0
    if t > bag[3]:
        f = (t - bag[3]) / bag[4]
        if f > 1.0:
            f = 1.0
        scale = 1.0 - (1.0 - bag[5]) * f
    return depth, 0.0, scale, 1.0, 0.0


@njit(cache=True, inline="always", error_model="numpy")
def _still_crushing(ct: np.ndarray, crush: float) -> bool:
    """Whether a crushable contact (row `ct`) has stroke left at `crush` (m).

    A structure crushed to its stroke limit (``C_CLIM``, none when <= 0) is a
    stop: the next, stiffer structure behind it acts through the bottoming spring.
    """
    return bool(ct[C_CLIM] <= 0.0 or crush < ct[C_CLIM])


@njit(cache=True, inline="always", error_model="numpy")
def _contact_force(
    pen: float,
    pendot: float,
    ct: np.ndarray,
    scale: float,
    damp_on: float,
    k_dep: float,
    crush: float,
) -> tuple[float, float, float]:
    """Normal contact force (N, >= 0), its elastic part, and the crush rate (m/s).

    ``crush`` (m) is the permanent crush of the structure behind the give
    (state of the contact); it grows, viscoplastically, while the force
    beyond the give would exceed the contact's ``bottom_cap``.
    """
    ramp = ct[C_RAMP]
    fr = pen / ramp if ramp > 0.0 else 1.0
    if fr > 1.0:
        fr = 1.0
    if ct[C_LAW] == 1.0:
        # airbag: constant-force spring (plateau) and damper from full deployment
        fe = ct[C_FCAP] * scale * fr
        squeeze = ct[C_K3]  # for the airbag law: penetration where the pressure rise starts
        if pen > squeeze:
            fe += ct[C_K] * scale * (pen - squeeze)  # pressure rise as the bag is squeezed
        fe += k_dep * pen  # membrane punch-out while the bag fills
        fd = ct[C_C] * pendot * fr * damp_on
    else:
        fe = ct[C_K] * pen + ct[C_K3] * pen * pen * pen
        if ct[C_FCAP] > 0.0 and fe > ct[C_FCAP]:
            fe = ct[C_FCAP]
        fd = ct[C_C] * pendot * fr
    hyst = ct[C_HYST]
    unload = 1.0
    if hyst > 0.0 and pendot < 0.0:
        # hysteresis (MADYMO's loading/unloading characteristic): crushed trim
        # and foam, and a bag venting its gas, give back only the share
        # (1 - hysteresis) of the elastic force while the contact unloads
        u = -pendot / UNLOAD_BLEND_SPEED
        if u > 1.0:
            u = 1.0
        unload = 1.0 - hyst * u
        fe *= unload
    f = fe + fd
    if ct[C_LAW] == 0.0 and ct[C_FCAP] > 0.0 and f > ct[C_FCAP]:
        f = ct[C_FCAP]  # elastic-plastic: damping does not lift the crush force
    rate = 0.0
    xb = pen - ct[C_GIVE] - crush
    if xb > 0.0:
        fb = ct[C_KBOT] * xb * unload
        fe += fb
        f += fb
        # beyond the give the structure behind the trim (steering assembly,
        # knee-bolster bracket) crushes at a force limit instead of acting as a
        # rigid wall; the crush is permanent (dissipative)
        bcap = ct[C_BCAP]
        # until its stroke (C_CLIM) is used up: then the next, stiffer structure
        # (firewall, cross-car beam) stops it through the bottoming spring
        if bcap > 0.0 and f > bcap and _still_crushing(ct, crush):
            rate = (f - bcap) / ct[C_CCR]
            f = bcap
            if fe > bcap:
                fe = bcap
    if f < 0.0:
        f = 0.0
    return f, fe, rate


@njit(cache=True, inline="always", error_model="numpy")
def _joint_torque(rel: float, reld: float, jt: np.ndarray) -> tuple[float, float]:
    """Elastic + damping torque (N m) resisting a relative rotation, and its energy (J)."""
    if rel >= 0.0:
        k = jt[0]
    else:
        k = jt[1]
    tau = k * rel
    en = 0.5 * k * rel * rel
    # the stop limits the anatomical range, measured from the neutral posture
    # (jt[6] = neutral rest - actual rest: a forward lean uses part of the range)
    rel_a = rel - jt[6]
    ex = abs(rel_a) - jt[3]
    if ex > 0.0:
        sg = 1.0 if rel_a > 0.0 else -1.0
        tau += jt[4] * ex * sg
        en += 0.5 * jt[4] * ex * ex
    return tau + jt[2] * reld, en


@njit(cache=True, error_model="numpy")
def rhs(
    t: float,
    y: np.ndarray,
    ll: np.ndarray,
    mb: np.ndarray,
    jt: np.ndarray,
    ch: np.ndarray,
    se: np.ndarray,
    ct: np.ndarray,
    bt: np.ndarray,
    bag: np.ndarray,
    t0: float,
    dt_in: float,
    acc: np.ndarray,
    door_s: np.ndarray,
    door_v: np.ndarray,
    diag: np.ndarray,
) -> np.ndarray:
    """Time derivative of the state (allocating wrapper of :func:`rhs_into`).

    Parameters
    ----------
    t : float
        Time, s.
    y : ndarray, shape (12 + 2 nb + 2 nc,)
        State.
    ll, mb, jt, ch, se, ct, bt, bag : ndarray
        Packed parameters (see the module layouts).
    t0, dt_in : float
        Start time and step of the input channels, s.
    acc : ndarray, shape (n,)
        Vehicle acceleration on the model axis, m/s^2.
    door_s, door_v : ndarray, shape (n,)
        Prescribed surface motion channel 1 (door intrusion), m and m/s.
    diag : ndarray, shape (DIAG_FIXED + 3 nc + nb,) or (0,)
        Output diagnostics when non-empty.

    Returns
    -------
    ndarray, shape like y
    """
    dy = np.zeros_like(y)
    ws = np.zeros((NQ + 14, NQ))
    model = (ll, mb, jt, ch, se, ct, bt, bag)
    rhs_into(t, y, dy, model, (t0, dt_in, acc, door_s, door_v), diag, ws)
    return dy


# ---------------------------------------------------------------- the physics pieces
#
# The right-hand side is the sum of named pieces, each compiled inline into it
# (``inline="always"``: the same machine code as one long function, the same
# arithmetic in the same order), each adding its generalised forces to ``f``
# (shape (NQ,)) and returning the powers and energies it contributes.


@njit(cache=True, inline="always", error_model="numpy")
def _inertia(
    q: np.ndarray,
    qd: np.ndarray,
    ll: np.ndarray,
    mb: np.ndarray,
    ch: np.ndarray,
    sn: np.ndarray,
    cs: np.ndarray,
    a_veh: float,
    ws: np.ndarray,
    want: bool,
) -> float:
    """Mass matrix ``ws[0:NQ]`` (upper part) and the inertial forces of the moving frame.

    Returns the power of the pulse on the occupant, W.
    """
    m = ws[0:NQ]
    f = ws[NQ]
    jx = ws[NQ + 1]
    jz = ws[NQ + 2]
    p_pulse = 0.0
    for i in range(mb.shape[0]):
        k = int(mb[i, 0])
        mass = mb[i, 3]
        px, pz, ddx, ddz = kin_sc(q, qd, ll, sn, cs, k, mb[i, 1], mb[i, 2], jx, jz, ch[5])
        # non-zero Jacobian columns: 0..top, plus 5 for the sternum
        top = 2 if k >= 5 else k
        nn = top + 2 if k >= 5 else top + 1
        vx = 0.0
        for ia in range(nn):
            a = ia if ia <= top else 5
            vx += jx[a] * qd[a]
            f[a] -= mass * (jx[a] * (ddx + a_veh) + jz[a] * ddz)
            for ib in range(ia, nn):
                b = ib if ib <= top else 5
                m[a, b] += mass * (jx[a] * jx[b] + jz[a] * jz[b])
        p_pulse -= mass * a_veh * vx
        if 1 <= k <= 4:
            m[k, k] += mb[i, 4]
        if want and (k == 0 or k == 2 or k == 4):
            slot = k // 2  # 0 pelvis, 1 thorax, 2 head: keep J and J-dot q-dot
            for a in range(NQ):
                ws[NQ + 7 + 2 * slot, a] = jx[a]
                ws[NQ + 8 + 2 * slot, a] = jz[a]
            ws[NQ + 13, 2 * slot] = ddx
            ws[NQ + 13, 2 * slot + 1] = ddz
    for a in range(NQ):
        for b in range(a + 1, NQ):
            m[b, a] = m[a, b]
    return p_pulse


@njit(cache=True, inline="always", error_model="numpy")
def _joints(
    q: np.ndarray, qd: np.ndarray, jt: np.ndarray, f: np.ndarray, diag: np.ndarray, want: bool
) -> float:
    """Lumbar, thoracic, lower and upper neck joint torques; returns their elastic energy, J."""
    v_int = 0.0
    for j in range(1, 5):
        if j == 1:
            rel = q[1] - jt[0, 5]
            reld = qd[1]
        else:
            rel = q[j] - q[j - 1] - jt[j - 1, 5]
            reld = qd[j] - qd[j - 1]
        tau, en = _joint_torque(rel, reld, jt[j - 1])
        v_int += en
        f[j] -= tau
        if j >= 2:
            f[j - 1] += tau
        if j == 4 and want:
            diag[D_NECK_MY] = tau  # flexion (+) moment carried by the upper neck joint
    return v_int


@njit(cache=True, inline="always", error_model="numpy")
def _chest_and_seat(
    q: np.ndarray, qd: np.ndarray, ch: np.ndarray, se: np.ndarray, f: np.ndarray
) -> float:
    """Chest spring-damper with its bottoming stop, and the pelvis slip on the seat.

    Returns the chest's elastic energy, J.
    """
    d = q[5]
    fch = ch[0] * d + ch[1] * d * d * d + ch[2] * qd[5]
    v_int = 0.5 * ch[0] * d * d + 0.25 * ch[1] * d**4
    if d > ch[3]:
        fch += ch[4] * (d - ch[3])
        v_int += 0.5 * ch[4] * (d - ch[3]) ** 2
    f[5] -= fch
    f[0] -= se[0] * se[1] * math.tanh(qd[0] / se[2]) + se[3] * qd[0]
    return v_int


@njit(cache=True, inline="always", error_model="numpy")
def _surface_motion(
    ch_id: float,
    q: np.ndarray,
    qd: np.ndarray,
    s_door: float,
    v_door: float,
    depth: float,
    ddepth: float,
) -> tuple[float, float, float, float]:
    """Prescribed motion of a contact surface by channel: (s, v, bag depth, bag speed).

    Channel 1 the door intrusion; 2 the frontal airbag's deployment; 3 a side
    airbag deploying from the intruding door; 4 a surface carried by the pelvis.
    """
    if ch_id == 1.0:
        return s_door, v_door, 0.0, 0.0
    if ch_id == 4.0:
        # a surface carried by the pelvis (the thighs): it moves with the
        # pelvis slide q[0], and the contact force reacts on the pelvis
        return q[0], qd[0], 0.0, 0.0
    if ch_id == 2.0:
        return depth, ddepth, 0.0, 0.0
    if ch_id == 3.0:
        # side airbag: deploys from the door (or the roof rail) toward the
        # occupant along the surface normal and rides on the intrusion
        return s_door, v_door, depth, ddepth
    return 0.0, 0.0, 0.0, 0.0


@njit(cache=True, inline="always", error_model="numpy")
def _penetration(
    row: np.ndarray, px: float, pz: float, sv: float, bag_d: float
) -> tuple[float, float, float, bool]:
    """Penetration of a body point into a one-sided surface: (pen, nx, nz, gone around).

    The surface is the segment a-b moved by ``sv`` along its motion and by
    ``bag_d`` along its normal, with rounded ends of radius EDGE_RADIUS_M.
    """
    ax = row[C_AX] + row[C_MX] * sv + row[C_NX] * bag_d
    az = row[C_AZ] + row[C_MZ] * sv + row[C_NZ] * bag_d
    bx = row[C_BX] + row[C_MX] * sv + row[C_NX] * bag_d
    bz = row[C_BZ] + row[C_MZ] * sv + row[C_NZ] * bag_d
    # one-sided surface with its outward normal toward the occupant's side
    # (surfaces only translate, so direction, length and normal are constant)
    s = ((px - ax) * row[C_UX] + (pz - az) * row[C_UZ]) / row[C_LEN]
    snx = row[C_NX]
    snz = row[C_NZ]
    sd = (px - ax) * snx + (pz - az) * snz
    around = False  # gone around an end of the segment (or deep behind it)
    if 0.0 <= s <= 1.0:
        nx = snx
        nz = snz
        pen = row[C_RAD] - sd
    else:
        # beyond an end: the surface's rounded edge, a cylinder of radius
        # EDGE_RADIUS_M tangent to the face at the end (its centre behind the
        # face), so that the penetration and its direction are continuous
        # across the end of the span for every point less than
        # EDGE_RADIUS_M behind the face line (a point deep in a bag that
        # slides past the end of its face is pushed off the edge, not let go)
        cx = (ax if s < 0.0 else bx) - EDGE_RADIUS_M * snx
        cz = (az if s < 0.0 else bz) - EDGE_RADIUS_M * snz
        dx = px - cx
        dz = pz - cz
        dist = math.sqrt(dx * dx + dz * dz)
        nx = snx
        nz = snz
        if dist > 1e-12:
            nx = dx / dist
            nz = dz / dist
        pen = row[C_RAD] + EDGE_RADIUS_M - dist
        if pen <= 0.0 and dx * snx + dz * snz < 0.0:
            around = True  # beyond the end and behind the edge: gone around it
    return pen, nx, nz, around


@njit(cache=True, inline="always", error_model="numpy")
def _contacts(
    y: np.ndarray,
    dy: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    ll: np.ndarray,
    ch: np.ndarray,
    ct: np.ndarray,
    nb: int,
    surfaces: tuple[float, float, float, float, float, float, float],
    ws: np.ndarray,
    diag: np.ndarray,
    want: bool,
) -> tuple[float, float, float]:
    """Every contact of a body point with an interior surface, airbag or seat.

    `surfaces` is (door s, door v, bag depth, bag speed, bag force scale, bag
    damping on, bag deployment stiffness). Returns the power of the moving
    surfaces on the occupant (W) and the contact force on the head (x, z), N.
    """
    s_door, v_door, depth, ddepth, bscale, bdamp, bkdep = surfaces
    f = ws[NQ]
    jx = ws[NQ + 1]
    jz = ws[NQ + 2]
    sn = ws[NQ + 5]
    cs = ws[NQ + 6]
    nc = ct.shape[0]
    p_active = 0.0
    head_fx = 0.0
    head_fz = 0.0
    for c in range(nc):
        row = ct[c]
        if row[C_EN] == 0.0:
            if want:
                diag[DIAG_FIXED + c] = 0.0
                diag[DIAG_FIXED + nc + nb + c] = 0.0
                diag[DIAG_FIXED + 2 * nc + nb + c] = GAP_NONE
            continue
        k = int(row[C_KB])
        beta = row[C_SHARE] if row[C_SHARE] >= 0.0 else ch[5]
        px, pz = pos_sc(q, ll, sn, cs, k, row[C_P], row[C_R], beta)
        ch_id = row[C_CH]
        sv, vv, bag_d, bag_v = _surface_motion(ch_id, q, qd, s_door, v_door, depth, ddepth)
        scale = 1.0
        damp_on = 1.0
        kdep = 0.0
        if ch_id == 2.0 or ch_id == 3.0:
            scale = bscale
            damp_on = bdamp
            kdep = bkdep
            if bscale == 0.0:
                # bag not out yet: no surface, the arming state is held
                if want:
                    diag[DIAG_FIXED + c] = 0.0
                    diag[DIAG_FIXED + nc + nb + c] = 0.0
                    diag[DIAG_FIXED + 2 * nc + nb + c] = GAP_NONE
                continue
        pen, nx, nz, around = _penetration(row, px, pz, sv, bag_d)
        # a crushable structure is met from its front only: a point that went
        # around the end of the segment (the head over the wheel rim) and comes
        # back into its span from behind is not in contact with it (the depth
        # test cannot be reached from the front: there the crush follows the
        # penetration within (F - bottom_cap)/c of travel)
        arm = y[2 * NQ + 2 * nb + nc + c]
        if want:
            # geometric clearance to the undeformed surface, before the
            # crush-depth test below can mark the point as gone around
            diag[DIAG_FIXED + 2 * nc + nb + c] = (
                -pen if pen <= 0.0 or arm >= ARMED_DIAGNOSTIC else GAP_NONE
            )
        if row[C_BCAP] > 0.0:
            crush = y[2 * NQ + 2 * nb + c]
            # (a structure crushed to its stroke limit is a stop, not passed)
            if _still_crushing(row, crush) and (
                pen - row[C_GIVE] - crush > 2.0 * row[C_BCAP] / row[C_KBOT]
            ):
                pen = -1.0
                around = True
        ia = 2 * NQ + 2 * nb + nc + c
        if pen <= 0.0:
            # out of contact: arm in front of the surface, disarm behind it
            dy[ia] = ((0.0 if around else 1.0) - arm) / ARM_TIME_S
        fmag = 0.0
        if pen > 0.0:
            kin_sc(q, qd, ll, sn, cs, k, row[C_P], row[C_R], jx, jz, beta)
            vpx = 0.0
            vpz = 0.0
            for a in range(NQ):
                vpx += jx[a] * qd[a]
                vpz += jz[a] * qd[a]
            vsx = row[C_MX] * vv + row[C_NX] * bag_v
            vsz = row[C_MZ] * vv + row[C_NZ] * bag_v
            pendot = -((vpx - vsx) * nx + (vpz - vsz) * nz)
            fmag, fe, crate = _contact_force(
                pen, pendot, row, scale, damp_on, kdep, y[2 * NQ + 2 * nb + c]
            )
            # a point that entered from behind (arm ~0) is not in contact
            fmag *= arm
            dy[2 * NQ + 2 * nb + c] = crate * arm
            for a in range(NQ):
                f[a] += fmag * (nx * jx[a] + nz * jz[a])
            if ch_id == 4.0:
                # reaction on the carrying pelvis: an internal force, no external work
                f[0] -= fmag * (nx * row[C_MX] + nz * row[C_MZ])
            else:
                p_active += fmag * (nx * vsx + nz * vsz)
            if k == 4:
                head_fx += fmag * nx
                head_fz += fmag * nz
        if want:
            diag[DIAG_FIXED + c] = fmag
            # the penetration of a contact the point is in (not of one it passes behind)
            diag[DIAG_FIXED + nc + nb + c] = pen if pen > 0.0 and arm >= ARMED_DIAGNOSTIC else 0.0
    return p_active, head_fx, head_fz


@njit(cache=True, inline="always", error_model="numpy")
def _belts(
    t: float,
    y: np.ndarray,
    dy: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    ll: np.ndarray,
    ch: np.ndarray,
    bt: np.ndarray,
    nc: int,
    ws: np.ndarray,
    diag: np.ndarray,
    want: bool,
) -> tuple[float, float]:
    """Shoulder and lap belt webbing with load limiter and pretensioner.

    Returns the webbing's elastic energy (J) and the pretensioner's power (W).
    """
    f = ws[NQ]
    jx = ws[NQ + 1]
    jz = ws[NQ + 2]
    sn = ws[NQ + 5]
    cs = ws[NQ + 6]
    v_int = 0.0
    p_active = 0.0
    for b in range(bt.shape[0]):
        row = bt[b]
        pay = y[2 * NQ + 2 * b]
        pull = y[2 * NQ + 2 * b + 1]
        if row[B_EN] == 0.0:
            if want:
                diag[DIAG_FIXED + nc + b] = 0.0
            continue
        k = int(row[B_KB])
        px, pz, ddx, ddz = kin_sc(q, qd, ll, sn, cs, k, row[B_P], row[B_R], jx, jz, ch[5])
        vpx = 0.0
        vpz = 0.0
        for a in range(NQ):
            vpx += jx[a] * qd[a]
            vpz += jz[a] * qd[a]
        ux = row[B_AX] - px
        uz = row[B_AZ] - pz
        la = math.sqrt(ux * ux + uz * uz)
        ux /= la
        uz /= la
        length = la
        dirx = ux
        dirz = uz
        if row[B_HASB] != 0.0:
            wx = row[B_BX] - px
            wz = row[B_BZ] - pz
            lb = math.sqrt(wx * wx + wz * wz)
            length += lb
            dirx += wx / lb
            dirz += wz / lb
        ldot = -(dirx * vpx + dirz * vpz)
        elong = length - row[B_L0] - row[B_SLACK] + pull - pay
        fel = 0.0
        fb = 0.0
        if elong > 0.0:
            fel = row[B_K] * elong
            fr = elong / 0.002
            if fr > 1.0:
                fr = 1.0
            fb = fel + row[B_C] * ldot * fr
            # damping cannot lift the tension above the load-limiter level
            cap = row[B_FLL] if row[B_FLL] > fel else fel
            if fb > cap:
                fb = cap
            if fb < 0.0:
                fb = 0.0
            v_int += 0.5 * row[B_K] * elong * elong
            for a in range(NQ):
                f[a] += fb * (dirx * jx[a] + dirz * jz[a])
        # load limiter pay-out (viscoplastic) and pretensioner pull-in
        over = fel - row[B_FLL]
        dy[2 * NQ + 2 * b] = over / row[B_CLL] if over > 0.0 else 0.0
        rate = 0.0
        if row[B_PTT0] <= t <= row[B_PTT1]:
            gf = (row[B_PTF] - fel) / (0.2 * row[B_PTF])
            gr = (row[B_PTMAX] - pull) / 0.002
            if gf > 1.0:
                gf = 1.0
            if gr > 1.0:
                gr = 1.0
            if gf > 0.0 and gr > 0.0:
                rate = row[B_PTV] * gf * gr
        dy[2 * NQ + 2 * b + 1] = rate
        p_active += fel * rate
        if want:
            diag[DIAG_FIXED + nc + b] = fb
    return v_int, p_active


@njit(cache=True, inline="always", error_model="numpy")
def _solve_accelerations(ws: np.ndarray) -> None:
    """Solve ``M qdd = f`` in place (Cholesky: the lower part of M is overwritten).

    M is ``ws[0:NQ]``, f ``ws[NQ]``, the result ``ws[NQ + 4]`` (``ws[NQ + 3]``
    is the forward substitution's workspace).
    """
    m = ws[0:NQ]
    lo = m
    f = ws[NQ]
    z = ws[NQ + 3]
    qdd = ws[NQ + 4]
    for i in range(NQ):
        for j in range(i + 1):
            s = m[i, j]
            for kk in range(j):
                s -= lo[i, kk] * lo[j, kk]
            if i == j:
                lo[i, i] = math.sqrt(s)
            else:
                lo[i, j] = s / lo[j, j]
    for i in range(NQ):
        s = f[i]
        for kk in range(i):
            s -= lo[i, kk] * z[kk]
        z[i] = s / lo[i, i]
    for i in range(NQ - 1, -1, -1):
        s = z[i]
        for kk in range(i + 1, NQ):
            s -= lo[kk, i] * qdd[kk]
        qdd[i] = s / lo[i, i]


@njit(cache=True, inline="always", error_model="numpy")
def _body_diagnostics(
    mb: np.ndarray,
    a_veh: float,
    head_fx: float,
    head_fz: float,
    ws: np.ndarray,
    diag: np.ndarray,
) -> None:
    """Head, chest and pelvis accelerations and the upper neck forces, into `diag`."""
    qdd = ws[NQ + 4]
    # head: the mass row with k == 4; chest: k == 2; pelvis: k == 0
    for i in range(mb.shape[0]):
        k = int(mb[i, 0])
        if k != 4 and k != 2 and k != 0:
            continue
        slot = k // 2
        axx = ws[NQ + 13, 2 * slot] + a_veh
        azz = ws[NQ + 13, 2 * slot + 1]
        for a in range(NQ):
            axx += ws[NQ + 7 + 2 * slot, a] * qdd[a]
            azz += ws[NQ + 8 + 2 * slot, a] * qdd[a]
        if k == 4:
            diag[D_HEAD_AX] = axx
            diag[D_HEAD_AZ] = azz
            # force of the neck on the head, expressed along the head axes
            fnx = mb[i, 3] * axx - head_fx
            fnz = mb[i, 3] * azz - head_fz
            sa = ws[NQ + 5, 4]  # sin and cos of q[4], from the start of the step
            ca = ws[NQ + 6, 4]
            diag[D_NECK_FZ] = -(fnx * sa + fnz * ca)  # tension (+)
            diag[D_NECK_FX] = fnx * ca - fnz * sa  # anterior (+) on the head
        elif k == 2:
            diag[D_CHEST_AX] = axx
            diag[D_CHEST_AZ] = azz
        else:
            diag[D_PELV_AX] = axx


# no reference counting inside the right-hand side (see _NO_NRT): 0.4 instead of
# 2.2 us per call on the benchmark machine
@njit(cache=True, error_model="numpy", **_NO_NRT)
def rhs_into(
    t: float,
    y: np.ndarray,
    dy: np.ndarray,
    model: tuple[np.ndarray, ...],
    inputs: tuple[float, float, np.ndarray, np.ndarray, np.ndarray],
    diag: np.ndarray,
    ws: np.ndarray,
) -> None:
    """Time derivative of the state, written into `dy` (no allocation).

    Parameters
    ----------
    t : float
        Time, s.
    y : ndarray, shape (12 + 2 nb + 2 nc,)
        State.
    dy : ndarray, shape like y
        Output: the time derivative.
    model : tuple of ndarray
        The packed model ``(ll, mb, jt, ch, se, ct, bt, bag)`` (see the module
        layouts).
    inputs : tuple
        ``(t0, dt_in, acc, door_s, door_v)``: start time and step of the input
        channels (s), the vehicle acceleration on the model axis (m/s^2, shape
        (n,)) and the prescribed door intrusion and its speed (m, m/s).
    diag : ndarray, shape (DIAG_FIXED + 3 nc + nb,) or (0,)
        Output diagnostics when non-empty.
    ws : ndarray, shape (NQ + 14, NQ)
        Workspace.
    """
    ll, mb, jt, ch, se, ct, bt, bag = model
    t0, dt_in, acc, door_s, door_v = inputs
    nb = bt.shape[0]
    nc = ct.shape[0]
    q = y[0:NQ]
    qd = y[NQ : 2 * NQ]
    for i in range(dy.shape[0]):
        dy[i] = 0.0
    for i in range(ws.shape[0]):
        for j in range(NQ):
            ws[i, j] = 0.0
    f = ws[NQ]
    sn = ws[NQ + 5]
    cs = ws[NQ + 6]
    for j in range(1, 5):
        sn[j] = math.sin(y[j])
        cs[j] = math.cos(y[j])
    a_veh = _interp(t, t0, dt_in, acc)
    s_door = _interp(t, t0, dt_in, door_s)
    v_door = _interp(t, t0, dt_in, door_v)
    depth, ddepth, bscale, bdamp, bkdep = _bag_state(t, bag)
    want = diag.shape[0] > 0

    p_pulse = _inertia(q, qd, ll, mb, ch, sn, cs, a_veh, ws, want)
    v_int = _joints(q, qd, jt, f, diag, want)
    v_int += _chest_and_seat(q, qd, ch, se, f)
    p_active, head_fx, head_fz = _contacts(
        y,
        dy,
        q,
        qd,
        ll,
        ch,
        ct,
        nb,
        (s_door, v_door, depth, ddepth, bscale, bdamp, bkdep),
        ws,
        diag,
        want,
    )
    v_belt, p_belt = _belts(t, y, dy, q, qd, ll, ch, bt, nc, ws, diag, want)
    v_int += v_belt
    p_active += p_belt

    if want:
        m = ws[0:NQ]
        ke = 0.0
        for a in range(NQ):
            for b in range(NQ):
                ke += 0.5 * qd[a] * m[a, b] * qd[b]
        diag[D_KE] = ke
    _solve_accelerations(ws)
    qdd = ws[NQ + 4]
    for i in range(NQ):
        dy[i] = qd[i]
        dy[NQ + i] = qdd[i]
    if want:
        diag[D_V_INT] = v_int
        diag[D_P_PULSE] = p_pulse
        diag[D_P_ACTIVE] = p_active
        _body_diagnostics(mb, a_veh, head_fx, head_fz, ws, diag)


@njit(cache=True, error_model="numpy", nogil=True)
def integrate_rk4(
    y0: np.ndarray,
    t_end: float,
    dt: float,
    ll: np.ndarray,
    mb: np.ndarray,
    jt: np.ndarray,
    ch: np.ndarray,
    se: np.ndarray,
    ct: np.ndarray,
    bt: np.ndarray,
    bag: np.ndarray,
    t0: float,
    dt_in: float,
    acc: np.ndarray,
    door_s: np.ndarray,
    door_v: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Classical fixed-step RK4 from t = 0 to t_end.

    Returns
    -------
    ys : ndarray, shape (n, len(y0))
        State at t = i dt.
    diags : ndarray, shape (n, DIAG_FIXED + 3 nc + nb)
        Diagnostics at the same times (from the first stage of each step).
    status : int
        0 success, -1 non-finite state (integration stopped).
    """
    n = int(round(t_end / dt)) + 1
    ny = y0.shape[0]
    nd = diag_size(ct.shape[0], bt.shape[0])
    ys = np.zeros((n, ny))
    diags = np.zeros((n, nd))
    empty = np.zeros(0)
    ws = np.zeros((NQ + 14, NQ))
    ks = np.zeros((4, ny))
    yt = np.zeros(ny)
    y = y0.copy()
    status = 0
    # stage s evaluates at t + c[s] dt, from y + c[s] dt k[s - 1]; weights w
    c = np.array([0.0, 0.5, 0.5, 1.0])
    w = np.array([1.0, 2.0, 2.0, 1.0]) / 6.0
    model = (ll, mb, jt, ch, se, ct, bt, bag)
    inputs = (t0, dt_in, acc, door_s, door_v)
    for i in range(n):
        t = i * dt
        ys[i] = y
        for st in range(4):
            if st == 0:
                yt[:] = y
            else:
                for j in range(ny):
                    yt[j] = y[j] + c[st] * dt * ks[st - 1, j]
            # diagnostics from the first stage only
            dg = diags[i] if st == 0 else empty
            rhs_into(t + c[st] * dt, yt, ks[st], model, inputs, dg, ws)
            if i == n - 1:
                break
        if i == n - 1:
            break
        ok = True
        for j in range(ny):
            for st in range(4):
                y[j] += dt * w[st] * ks[st, j]
            if not math.isfinite(y[j]):
                ok = False
        if not ok:
            status = -1
            ys = ys[: i + 1]
            diags = diags[: i + 1]
            break
    return ys, diags, status


@njit(cache=True, error_model="numpy", nogil=True, **_NO_NRT)
def _se_loop(
    y: np.ndarray,
    k1: np.ndarray,
    ws: np.ndarray,
    ys: np.ndarray,
    diags: np.ndarray,
    dt: float,
    model: tuple[np.ndarray, ...],
    inputs: tuple[float, float, np.ndarray, np.ndarray, np.ndarray],
) -> int:
    """Inner loop of :func:`integrate_se` (no allocation, no reference counting).

    Returns the number of rows written; fewer than ``ys.shape[0]`` when the
    state became non-finite.
    """
    n = ys.shape[0]
    ny = y.shape[0]
    for i in range(n):
        t = i * dt
        for j in range(ny):
            ys[i, j] = y[j]
        rhs_into(t, y, k1, model, inputs, diags[i], ws)
        if i == n - 1:
            break
        ok = True
        for j in range(NQ):
            y[NQ + j] += dt * k1[NQ + j]
            y[j] += dt * y[NQ + j]
        for j in range(2 * NQ, ny):
            y[j] += dt * k1[j]
        for j in range(ny):
            if not math.isfinite(y[j]):
                ok = False
        if not ok:
            return i + 1
    return n


@njit(cache=True, error_model="numpy", nogil=True)
def integrate_se(
    y0: np.ndarray,
    t_end: float,
    dt: float,
    ll: np.ndarray,
    mb: np.ndarray,
    jt: np.ndarray,
    ch: np.ndarray,
    se: np.ndarray,
    ct: np.ndarray,
    bt: np.ndarray,
    bag: np.ndarray,
    t0: float,
    dt_in: float,
    acc: np.ndarray,
    door_s: np.ndarray,
    door_v: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Semi-implicit (symplectic) Euler, one right-hand side per step.

    Velocities first (``v += dt a(t, q, v)``), then positions with the new
    velocities; belt states by explicit Euler. Same returns as
    :func:`integrate_rk4`.
    """
    n = int(round(t_end / dt)) + 1
    ny = y0.shape[0]
    nd = diag_size(ct.shape[0], bt.shape[0])
    ys = np.zeros((n, ny))
    diags = np.zeros((n, nd))
    ws = np.zeros((NQ + 14, NQ))
    k1 = np.zeros(ny)
    y = y0.copy()
    model = (ll, mb, jt, ch, se, ct, bt, bag)
    done = _se_loop(y, k1, ws, ys, diags, dt, model, (t0, dt_in, acc, door_s, door_v))
    if done < n:
        return ys[:done], diags[:done], -1
    return ys, diags, 0
