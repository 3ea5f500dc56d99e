"""Injury criteria from dummy or occupant-model time histories.

Head (HIC), upper neck (Nij), chest (peak deflection and compression, viscous
criterion, combined thoracic index, 3 ms clip acceleration). Formulas and
coefficients: ``injury-criteria.md`` section 1; labels [V]/[S]/[U]/[R] are the
reference's confidence labels (verified / secondary sources agree / single or
unconfirmed source / engineering choice, not published).

The functions take channels that are **already filtered** at the class the
criterion calls for (see :mod:`models.injury.filters`): head acceleration
components at CFC 1000 before the resultant is taken, all Nij channels at
CFC 600, chest deflection at CFC 180 (FMVSS/NCAP practice; the J211 table says
600 [U]), chest acceleration at CFC 180.

Time zero of every channel is its first sample; times in results are measured
from it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from typing import Final

import numpy as np
import numpy.typing as npt
from numba import njit

from models.notification import Body

__all__ = [
    "CHEST_DEPTH_MM",
    "CHEST_DEPTH_MM_95TH_MALE",
    "CLIP_DURATION_S",
    "CTI_INTERCEPTS",
    "FMVSS208_CHEST_A3MS_LIMIT_G",
    "FMVSS208_CHEST_DEFLECTION_LIMIT_MM",
    "FMVSS208_HIC15_LIMIT",
    "FMVSS208_HIC36_LIMIT",
    "FMVSS208_NIJ_LIMIT",
    "FMVSS213_HIC15_LIMIT",
    "HIC15_WINDOW_MS",
    "HIC36_WINDOW_MS",
    "NIJ_INTERCEPTS",
    "NIJ_INTERCEPTS_5F_OUT_OF_POSITION",
    "OCCIPITAL_CONDYLE_OFFSET_M",
    "VC_CONSTANTS",
    "VC_CONSTANTS_ES2",
    "VC_CONSTANTS_SID_IIS",
    "ChestDeflectionResult",
    "CtiIntercepts",
    "HicResult",
    "NijIntercepts",
    "NijMode",
    "NijResult",
    "VcConstants",
    "chest_deflection",
    "clip_3ms",
    "cti",
    "hic",
    "nij",
    "occipital_condyle_moment",
    "viscous_criterion",
]

# --------------------------------------------------------------------------------------
# Constants
# --------------------------------------------------------------------------------------

#: HIC15 window limit, ms. [V] 49 CFR 571.208 S6.2.
HIC15_WINDOW_MS: Final[float] = 15.0
#: HIC36 window limit, ms. [V] 49 CFR 571.208 (older text).
HIC36_WINDOW_MS: Final[float] = 36.0
#: FMVSS 208 HIC15 limit. [V] 49 CFR 571.208 S6.2.
FMVSS208_HIC15_LIMIT: Final[float] = 700.0
#: FMVSS 208 HIC36 limit (older text). [V] 49 CFR 571.208.
FMVSS208_HIC36_LIMIT: Final[float] = 1000.0
#: FMVSS 213 HIC15 limit. [V] 49 CFR 571.213.
FMVSS213_HIC15_LIMIT: Final[float] = 500.0
#: FMVSS 208 Nij limit (each of the four modes). [S] 49 CFR 571.208 S6.6; the
#: intercepts below are defined so that Nij = 1.0 is the limit.
FMVSS208_NIJ_LIMIT: Final[float] = 1.0
#: FMVSS 208 chest deflection limits, mm. [U] reference section 1.
FMVSS208_CHEST_DEFLECTION_LIMIT_MM: Final[dict[Body, float]] = {
    Body.MALE_50TH: 63.0,
    Body.FEMALE_5TH: 52.0,
}
#: FMVSS 208 chest resultant acceleration limit, g, 3 ms clip. [U] reference section 1.
FMVSS208_CHEST_A3MS_LIMIT_G: Final[float] = 60.0

#: Offset between the upper-neck load cell and the occipital condyle, m, for the
#: Hybrid III 50M and 5F. [S] 49 CFR 572.123 ("Moment = My - (0.01778 m) x Fx");
#: pyisomme ``calculate_neck_MOCy``.
OCCIPITAL_CONDYLE_OFFSET_M: Final[float] = 0.01778

#: Chest depth, mm (the D0 of compression and VC). [S] SAE J1727 table as cited
#: by websat.io; pyisomme VC constants.
CHEST_DEPTH_MM: Final[dict[Body, float]] = {
    Body.MALE_50TH: 229.0,
    Body.FEMALE_5TH: 187.0,
}
#: Chest depth of the Hybrid III 95th male, mm. [S] same sources.
CHEST_DEPTH_MM_95TH_MALE: Final[float] = 254.0

#: Duration of the clip of :func:`clip_3ms`, s. [U] FMVSS 208 chest acceleration
#: limit "except for intervals whose cumulative duration is not more than 3 ms".
CLIP_DURATION_S: Final[float] = 0.003


@dataclass(frozen=True)
class NijIntercepts:
    """Critical intercepts of Nij for one dummy (all magnitudes, positive).

    Attributes
    ----------
    tension_n, compression_n : float
        Fzc for tension and compression, N.
    flexion_nm, extension_nm : float
        Myc for flexion and extension, N m.
    condyle_offset_m : float
        D in MOCy = My - D Fx, m.
    """

    tension_n: float
    compression_n: float
    flexion_nm: float
    extension_nm: float
    condyle_offset_m: float = OCCIPITAL_CONDYLE_OFFSET_M


#: Nij intercepts per dummy, in-position. [S] public MATLAB NCAP-rating script
#: (NHTSA test v11660) and pyisomme ``calculate.py`` agree (reference section 1):
#: Hybrid III 50M 6806 N / 6160 N / 310 N m / 135 N m; 5F in-position
#: 4287 N / 3880 N / 155 N m / 67 N m.
NIJ_INTERCEPTS: Final[dict[Body, NijIntercepts]] = {
    Body.MALE_50TH: NijIntercepts(6806.0, 6160.0, 310.0, 135.0),
    Body.FEMALE_5TH: NijIntercepts(4287.0, 3880.0, 155.0, 67.0),
}
#: Hybrid III 5F out-of-position intercepts. [S] pyisomme / [U]; not used by
#: default (the occupant models are in position).
NIJ_INTERCEPTS_5F_OUT_OF_POSITION: Final[NijIntercepts] = NijIntercepts(3880.0, 3880.0, 155.0, 61.0)


@dataclass(frozen=True)
class VcConstants:
    """Viscous-criterion constants of one dummy.

    Attributes
    ----------
    scale_factor : float
        SF, dimensionless.
    deformation_constant_m : float
        D0, m (the chest depth for the Hybrid III family).
    """

    scale_factor: float
    deformation_constant_m: float


#: VC constants per Hybrid III dummy: SF = 1.3, D0 = 229 mm (50M), 187 mm (5F).
#: [S] SAE J1727 table (websat.io) and pyisomme agree.
VC_CONSTANTS: Final[dict[Body, VcConstants]] = {
    Body.MALE_50TH: VcConstants(1.3, 0.229),
    Body.FEMALE_5TH: VcConstants(1.3, 0.187),
}
#: VC constants of the EuroSID / ES-2 / ES-2re side dummy: SF 1.0, D0 140 mm. [S]
VC_CONSTANTS_ES2: Final[VcConstants] = VcConstants(1.0, 0.140)
#: VC constants of the SID-IIs side dummy: SF 1.0, D0 138 mm. [S]
VC_CONSTANTS_SID_IIS: Final[VcConstants] = VcConstants(1.0, 0.138)


@dataclass(frozen=True)
class CtiIntercepts:
    """Intercepts of the combined thoracic index.

    Attributes
    ----------
    acceleration_g : float
        Aint, g.
    deflection_mm : float
        Dint, mm.
    """

    acceleration_g: float
    deflection_mm: float


#: CTI intercepts. Hybrid III 50M: Aint = 90 g, Dint = 103 mm, [U] from a single
#: public MATLAB NCAP script attributed to Kleinberger et al. 1998 (NHTSA);
#: to be checked against Kleinberger 1998 ch. 4.
#: Hybrid III 5F: not found in the sources [R]. Chosen: Aint = 90 g and
#: Dint = 103 * 187 / 229 = 84.1 mm, i.e. the deflection intercept scaled by
#: chest depth and the acceleration intercept unchanged, the same way FMVSS 208
#: scales its limits between the two dummies (63 -> 52 mm, 60 g for both).
CTI_INTERCEPTS: Final[dict[Body, CtiIntercepts]] = {
    Body.MALE_50TH: CtiIntercepts(90.0, 103.0),
    Body.FEMALE_5TH: CtiIntercepts(90.0, 103.0 * 187.0 / 229.0),
}


# --------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------


def _as_channel(x: npt.ArrayLike, name: str, min_len: int = 1) -> npt.NDArray[np.float64]:
    a = np.ascontiguousarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"`{name}` must be 1-D, got shape {a.shape}.")
    if a.size < min_len:
        raise ValueError(f"`{name}` must have at least {min_len} sample(s), got {a.size}.")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"`{name}` must be finite (no NaN or inf).")
    return a


def _check_rate(sample_rate_hz: float) -> float:
    fs = float(sample_rate_hz)
    if not (math.isfinite(fs) and fs > 0.0):
        raise ValueError("`sample_rate_hz` must be a positive finite number.")
    return fs


def _check_body(dummy: Body) -> Body:
    try:
        return Body(dummy)
    except ValueError:
        raise ValueError(f"`dummy` must be a Body, got {dummy!r}.") from None


# --------------------------------------------------------------------------------------
# HIC
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class HicResult:
    """Head injury criterion and its window.

    Attributes
    ----------
    value : float
        HIC, dimensionless (acceleration in g, time in s).
    t1_s, t2_s : float
        Start and end of the maximising window, s from the first sample.
        Both 0.0 when no window has a positive mean acceleration.
    """

    value: float
    t1_s: float
    t2_s: float


#: Relative margin on the pruning bound of :func:`_hic_search`: far above the few
#: ulps by which the rounded bound and the rounded window value can differ (the
#: bound then only prunes a little less, never a window that could win).
_HIC_BOUND_MARGIN: Final[float] = 1e-9


@njit(cache=True)
def _window_max(x: npt.NDArray[np.float64], w: int) -> npt.NDArray[np.float64]:
    """An upper bound of ``max(x[s : s + w])`` for every start s (van Herk / Gil-Werman).

    Blocks of `w` samples, running maxima from each block's start and from its
    end: ``max(suffix[s], prefix[s + w - 1])`` is the exact window maximum for
    a full window and at least it for one cut by the end of `x`.
    """
    n = x.shape[0]
    prefix = np.empty(n)
    suffix = np.empty(n)
    for k in range(n):
        prefix[k] = x[k] if k % w == 0 else max(prefix[k - 1], x[k])
    for k in range(n - 1, -1, -1):
        suffix[k] = x[k] if (k == n - 1 or (k + 1) % w == 0) else max(suffix[k + 1], x[k])
    out = np.empty(n)
    for s in range(n):
        out[s] = max(suffix[s], prefix[min(s + w - 1, n - 1)])
    return out


@njit(cache=True)
def _inv_cubes(dt: float, nmax: int) -> npt.NDArray[np.float64]:
    """``1 / T**3`` for window lengths ``T = k dt``, k = 0..nmax (0 for k = 0), 1/s^3."""
    inv_t3 = np.empty(nmax + 1)
    inv_t3[0] = 0.0
    for k in range(1, nmax + 1):
        t = k * dt
        inv_t3[k] = 1.0 / (t * t * t)
    return inv_t3


@njit(cache=True)
def _hic_window_from(
    cum: npt.NDArray[np.float64], inv_t3: npt.NDArray[np.float64], i: int, nmax: int
) -> tuple[float, int]:
    """Largest ``A**5 / T**3`` over the windows starting at sample i, and its end (-1: none)."""
    ci = cum[i]
    jmax = min(cum.shape[0] - 1, i + nmax)
    local = 0.0
    lj = -1
    for j in range(i + 1, jmax + 1):
        area = cum[j] - ci
        if area > 0.0:
            a2 = area * area
            v = a2 * a2 * area * inv_t3[j - i]
            if v > local:
                local = v
                lj = j
    return local, lj


@njit(cache=True)
def _hic_search(cum: npt.NDArray[np.float64], dt: float, nmax: int) -> tuple[float, int, int]:
    """Exact HIC search over every sample pair (i, j), 0 < j - i <= nmax.

    ``cum[k]`` is the integral of the acceleration (g s) from sample 0 to k, and
    ``HIC(i, j) = A**2.5 / T**1.5`` with ``A = cum[j] - cum[i]``, ``T = (j - i) dt``.
    The loop compares the square ``A**5 / T**3`` (products only, no sqrt in the
    inner loop; a monotone transform of HIC for A > 0) and returns HIC squared.
    The first maximum in (i, j) order wins ties.

    Starts that cannot win are skipped, which leaves the answer (value and
    window) that of the exhaustive loop: ``A**5 / T**3 = A**2 (A / T)**3`` is at
    most ``B_i = Amax_i**2 rmax_i**3`` for every window from i, with ``Amax_i``
    the largest area from i within the limit and ``rmax_i`` the largest mean
    over one sample period there (a mean over T is at most its largest
    one-period mean). The windows from the start with the largest bound are
    evaluated first; their best value ``v*`` is reached by a real window, so a
    start with ``B_i < v*`` (with :data:`_HIC_BOUND_MARGIN`) holds no window
    that reaches the maximum or ties it. tests/models/injury/test_injury_hic.py
    holds it equal to the exhaustive loop, bit for bit.
    """
    n = cum.shape[0]
    inv_t3 = _inv_cubes(dt, nmax)
    # per start i: Amax_i (largest cum[j] - cum[i], j in (i, i + nmax]) and rmax_i
    # (largest one-period increment cum[k + 1] - cum[k], k in [i, i + nmax))
    inc = np.empty(n)
    for k in range(n - 1):
        inc[k] = cum[k + 1] - cum[k]
    inc[n - 1] = inc[n - 2] if n > 1 else 0.0
    cum_max = _window_max(cum, nmax + 1)  # cum[i .. i + nmax]; >= the max over (i, i + nmax]
    inc_max = _window_max(inc, nmax)
    bound = np.zeros(n)
    top = 0
    for i in range(n - 1):
        amax = cum_max[i] - cum[i]
        rmax = inc_max[i]
        if amax > 0.0 and rmax > 0.0:
            bound[i] = amax * amax * rmax * rmax * rmax * inv_t3[1] * (1.0 + _HIC_BOUND_MARGIN)
            if bound[i] > bound[top]:
                top = i
    floor, _ = _hic_window_from(cum, inv_t3, top, nmax)
    best2 = 0.0
    bi = 0
    bj = 0
    for i in range(n - 1):
        if bound[i] < floor or bound[i] == 0.0:
            continue
        local, lj = _hic_window_from(cum, inv_t3, i, nmax)
        if local > best2:
            best2 = local
            bi = i
            bj = lj
    return best2, bi, bj


def hic(
    resultant_accel_g: npt.ArrayLike, sample_rate_hz: float, max_window_ms: float = 15.0
) -> HicResult:
    """Head injury criterion, exact over every window up to `max_window_ms`.

    ``HIC = max over t1 < t2, t2 - t1 <= w, of (t2 - t1) [mean a_r over (t1, t2)]**2.5``
    with the resultant head-CG acceleration ``a_r`` in g and time in s
    ([V] 49 CFR 571.208 S6.2). Every pair of samples whose distance is at most
    the limit is evaluated (the limit itself included: the rule is "not more
    than" 15 ms); no widest-window shortcut is taken, because the widest window
    is not always the maximum (reference section 5, pyisomme defect 2). The
    integral is the trapezoidal rule on the samples, so for a rectangular pulse
    of ``A`` g lasting ``T`` s (``T`` a whole number of sample periods),
    ``HIC = min(T, w) A**2.5``.

    Use ``max_window_ms=15.0`` for HIC15 and ``36.0`` for HIC36. Windows are
    on the sample grid, so the effective limit is ``floor(w fs)`` periods.

    Parameters
    ----------
    resultant_accel_g : array_like, shape (n,)
        Resultant head acceleration, g, of CFC 1000 filtered components.
        Negative samples (filter ringing) are integrated as they are; windows
        whose mean is not positive contribute nothing.
    sample_rate_hz : float
        Sampling rate, Hz.
    max_window_ms : float, optional
        Largest window t2 - t1, ms (default 15).

    Returns
    -------
    HicResult
        ``value``, and the window ``t1_s``, ``t2_s`` in s from the first sample.

    Raises
    ------
    ValueError
        If the signal is not 1-D or not finite, or a rate or window is not positive.

    Notes
    -----
    O(n w fs) with a compiled loop over prefix sums: 250 ms at 10 kHz with a
    15 ms window is 2500 x 150 window evaluations.
    """
    fs = _check_rate(sample_rate_hz)
    a = _as_channel(resultant_accel_g, "resultant_accel_g")
    w = float(max_window_ms)
    if not (math.isfinite(w) and w > 0.0):
        raise ValueError("`max_window_ms` must be a positive finite number.")
    nmax_f = w * 1e-3 * fs
    nmax = int(math.floor(nmax_f + 1e-9 * max(1.0, nmax_f)))
    if a.size < 2 or nmax < 1:
        return HicResult(0.0, 0.0, 0.0)
    nmax = min(nmax, a.size - 1)  # a window cannot exceed the record
    dt = 1.0 / fs
    cum = np.empty(a.size, dtype=np.float64)
    cum[0] = 0.0
    np.cumsum(0.5 * (a[1:] + a[:-1]) * dt, out=cum[1:])
    best2, i, j = _hic_search(cum, dt, nmax)
    if best2 <= 0.0:
        return HicResult(0.0, 0.0, 0.0)
    area = float(cum[j] - cum[i])
    dur = (j - i) * dt
    # x**2.5 as x*x*sqrt(x): recompute the winner exactly from its window.
    value = area * area * math.sqrt(area) / (dur * math.sqrt(dur))
    return HicResult(value, i * dt, j * dt)


# --------------------------------------------------------------------------------------
# Nij
# --------------------------------------------------------------------------------------


class NijMode(StrEnum):
    """Loading mode of the upper neck: tension/compression x extension/flexion."""

    NTE = "NTE"
    NTF = "NTF"
    NCE = "NCE"
    NCF = "NCF"


@dataclass(frozen=True)
class NijResult:
    """Neck injury criterion.

    Attributes
    ----------
    value : float
        Peak Nij over time (the maximum of the four mode peaks).
    mode : NijMode
        Mode at the peak.
    time_index : int
        Sample index of the peak.
    nte, ntf, nce, ncf : float
        Peak of each mode over the samples in that mode; 0.0 for a mode that
        never occurs.
    """

    value: float
    mode: NijMode
    time_index: int
    nte: float
    ntf: float
    nce: float
    ncf: float

    @property
    def mode_peaks(self) -> dict[NijMode, float]:
        """Peak per mode, ``{NijMode: float}``."""
        return {
            NijMode.NTE: self.nte,
            NijMode.NTF: self.ntf,
            NijMode.NCE: self.nce,
            NijMode.NCF: self.ncf,
        }


def occipital_condyle_moment(
    fx_n: npt.ArrayLike, my_nm: npt.ArrayLike, offset_m: float = OCCIPITAL_CONDYLE_OFFSET_M
) -> npt.NDArray[np.float64]:
    """Moment about the occipital condyle, ``MOCy = My - D Fx``, N m.

    Parameters
    ----------
    fx_n : array_like, shape (n,)
        Upper-neck shear force, N.
    my_nm : array_like, shape (n,)
        Upper-neck moment at the load cell, N m.
    offset_m : float, optional
        D, m; 0.01778 for the Hybrid III 50M and 5F ([S] 49 CFR 572.123).

    Returns
    -------
    ndarray, shape (n,)
        MOCy, N m; positive is flexion.
    """
    fx = _as_channel(fx_n, "fx_n")
    my = _as_channel(my_nm, "my_nm")
    if fx.shape != my.shape:
        raise ValueError("`fx_n` and `my_nm` must have the same shape.")
    return my - offset_m * fx


def nij(
    fx_n: npt.ArrayLike,
    fz_n: npt.ArrayLike,
    my_nm: npt.ArrayLike,
    dummy: Body,
    *,
    intercepts: NijIntercepts | None = None,
) -> NijResult:
    """Neck injury criterion Nij with the occipital condyle correction.

    ``Nij(t) = Fz/Fzc + MOCy/Myc`` with ``MOCy = My - 0.01778 m * Fx`` and the
    intercept chosen by the sign of each load: ``Fz > 0`` tension, ``MOCy > 0``
    flexion (SAE J211/J1733). At each sample exactly one of NTE, NTF, NCE, NCF
    is non-zero ([S] Oasys T/HIS, Altair ``nij()``); all four are tracked
    (pyisomme omits NTF, reference section 5). A load of exactly zero is
    counted as tension / flexion; it adds 0 either way.

    Parameters
    ----------
    fx_n : array_like, shape (n,)
        Upper-neck shear force Fx, N, CFC 600.
    fz_n : array_like, shape (n,)
        Upper-neck axial force Fz, N, CFC 600; positive is tension.
    my_nm : array_like, shape (n,)
        Upper-neck moment My at the load cell, N m, CFC 600.
    dummy : Body
        Hybrid III 50th male or 5th female (in-position intercepts).
    intercepts : NijIntercepts, optional
        Override, e.g. :data:`NIJ_INTERCEPTS_5F_OUT_OF_POSITION`.

    Returns
    -------
    NijResult
    """
    body = _check_body(dummy)
    fx = _as_channel(fx_n, "fx_n")
    fz = _as_channel(fz_n, "fz_n")
    my = _as_channel(my_nm, "my_nm")
    if not (fx.shape == fz.shape == my.shape):
        raise ValueError("`fx_n`, `fz_n` and `my_nm` must have the same shape.")
    ic = NIJ_INTERCEPTS[body] if intercepts is None else intercepts
    value, k, mode_k, peaks = _nij_scan(
        fx,
        fz,
        my,
        ic.condyle_offset_m,
        ic.tension_n,
        ic.compression_n,
        ic.flexion_nm,
        ic.extension_nm,
    )
    return NijResult(
        value=float(value),
        mode=_NIJ_MODES[mode_k],
        time_index=int(k),
        nte=float(peaks[0]),
        ntf=float(peaks[1]),
        nce=float(peaks[2]),
        ncf=float(peaks[3]),
    )


#: Load cases in the order of :func:`_nij_scan`'s peaks.
_NIJ_MODES: Final[tuple[NijMode, ...]] = (NijMode.NTE, NijMode.NTF, NijMode.NCE, NijMode.NCF)


@njit(cache=True)
def _nij_scan(
    fx: npt.NDArray[np.float64],
    fz: npt.NDArray[np.float64],
    my: npt.NDArray[np.float64],
    offset_m: float,
    tension_n: float,
    compression_n: float,
    flexion_nm: float,
    extension_nm: float,
) -> tuple[float, int, int, npt.NDArray[np.float64]]:
    """Nij over the samples in one pass: its maximum, where, in which load case, and
    each load case's peak (0 where the case never occurs).

    Per sample the operations of the array form ``MOCy = My - offset Fx``,
    ``Fz / Fzc`` or ``-Fz / Fzc``, ``MOCy / Myc`` or ``-MOCy / Myc``, their sum
    (the same bits, IEEE operations without fast-math); the first maximum wins,
    as ``np.argmax``. Load cases: 0 NTE, 1 NTF, 2 NCE, 3 NCF.
    """
    peaks = np.zeros(4)
    seen = np.zeros(4, dtype=np.bool_)
    best = -np.inf
    best_i = 0
    best_mode = 0
    for i in range(fx.shape[0]):
        moc = my[i] - offset_m * fx[i]
        tension = fz[i] >= 0.0
        flexion = moc >= 0.0
        n_force = fz[i] / tension_n if tension else -fz[i] / compression_n
        n_moment = moc / flexion_nm if flexion else -moc / extension_nm
        v = n_force + n_moment
        mode = (1 if flexion else 0) if tension else (3 if flexion else 2)
        if not seen[mode] or v > peaks[mode]:
            peaks[mode] = v
            seen[mode] = True
        if v > best:
            best = v
            best_i = i
            best_mode = mode
    return best, best_i, best_mode, peaks


# --------------------------------------------------------------------------------------
# Chest
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ChestDeflectionResult:
    """Peak chest deflection and compression.

    Attributes
    ----------
    peak_mm : float
        Peak sternum-to-spine deflection, mm (compression positive; 0.0 if the
        chest never compresses).
    compression : float
        ``peak_mm / chest depth``, dimensionless (0.276 = 27.6 %).
    time_index : int
        Sample index of the peak.
    """

    peak_mm: float
    compression: float
    time_index: int


def chest_deflection(deflection_mm: npt.ArrayLike, dummy: Body) -> ChestDeflectionResult:
    """Peak chest deflection and compression C = D / chest depth.

    Parameters
    ----------
    deflection_mm : array_like, shape (n,)
        Sternum-to-spine deflection, mm, **positive in compression** (flip the
        sign of J211 channels that report compression as negative), CFC 180.
    dummy : Body
        Chest depth 229 mm (50M) or 187 mm (5F) ([S] SAE J1727 table).

    Returns
    -------
    ChestDeflectionResult
    """
    body = _check_body(dummy)
    d = _as_channel(deflection_mm, "deflection_mm")
    k = int(np.argmax(d))
    peak = max(float(d[k]), 0.0)
    return ChestDeflectionResult(peak, peak / CHEST_DEPTH_MM[body], k)


def viscous_criterion(
    deflection_m: npt.ArrayLike,
    sample_rate_hz: float,
    dummy: Body,
    *,
    constants: VcConstants | None = None,
) -> float:
    """Peak viscous criterion VCmax, m/s.

    ``VC(t) = SF V(t) C(t)`` with ``C = D / D0`` and ``V = dD/dt`` by the
    4-point central difference
    ``V(t) = [8 (D(t+dt) - D(t-dt)) - (D(t+2dt) - D(t-2dt))] / (12 dt)``
    ([S] dynasaur ``vc()`` and pyisomme ``calculate_vc``). V is defined on the
    interior samples 2 .. n-3 only; VCmax is the largest VC there, floored at 0.

    Parameters
    ----------
    deflection_m : array_like, shape (n,)
        Chest deflection, m, positive in compression, n >= 5. Filter class
        uncertain: CFC 180 in Euro NCAP / R95 practice [U], CFC 600 in the J1727
        table; the caller filters.
    sample_rate_hz : float
        Sampling rate, Hz.
    dummy : Body
        Hybrid III: SF = 1.3, D0 = 0.229 m (50M) or 0.187 m (5F) [S].
    constants : VcConstants, optional
        Override, e.g. :data:`VC_CONSTANTS_ES2` for a side-impact dummy.

    Returns
    -------
    float
        VCmax, m/s.
    """
    body = _check_body(dummy)
    fs = _check_rate(sample_rate_hz)
    d = _as_channel(deflection_m, "deflection_m", min_len=5)
    c = VC_CONSTANTS[body] if constants is None else constants
    v = (8.0 * (d[3:-1] - d[1:-3]) - (d[4:] - d[:-4])) * (fs / 12.0)
    vc = c.scale_factor * v * (d[2:-2] / c.deformation_constant_m)
    return max(float(vc.max()), 0.0)


def cti(a3ms_g: float, dmax_mm: float, dummy: Body) -> float:
    """Combined thoracic index ``CTI = Amax/Aint + Dmax/Dint``.

    Parameters
    ----------
    a3ms_g : float
        3 ms clip chest resultant acceleration, g (see :func:`clip_3ms`).
    dmax_mm : float
        Peak chest deflection, mm.
    dummy : Body
        50M: Aint = 90 g, Dint = 103 mm [U] (single public script attributed to
        Kleinberger et al. 1998). 5F: Aint = 90 g, Dint = 84.1 mm [R], see
        :data:`CTI_INTERCEPTS`.

    Returns
    -------
    float
        CTI, dimensionless.

    Notes
    -----
    CTI is published as a frontal Hybrid III measure; the reference paper
    applies it to side impact, where the channels and intercepts are a project
    decision. The same intercepts are used here for every impact mode.
    """
    body = _check_body(dummy)
    a = float(a3ms_g)
    d = float(dmax_mm)
    if not (math.isfinite(a) and a >= 0.0):
        raise ValueError("`a3ms_g` must be a finite non-negative number.")
    if not (math.isfinite(d) and d >= 0.0):
        raise ValueError("`dmax_mm` must be a finite non-negative number.")
    ic = CTI_INTERCEPTS[body]
    return a / ic.acceleration_g + d / ic.deflection_mm


def clip_3ms(
    resultant_accel_g: npt.ArrayLike, sample_rate_hz: float, *, cumulative: bool = True
) -> float:
    """3 ms clip acceleration, g.

    With ``cumulative=True`` (default, FMVSS 208 wording: the level may be
    exceeded "for intervals whose cumulative duration is not more than 3 ms")
    the result is the highest level that the signal reaches or exceeds for a
    cumulative 3 ms: the ``m``-th largest sample, ``m = round(0.003 fs)``
    samples each standing for one period. With ``cumulative=False`` it is the
    highest level held continuously for 3 ms: the maximum over windows of ``m``
    consecutive samples of the window minimum. The two agree for single-peaked
    signals; the cumulative value is never smaller.

    Parameters
    ----------
    resultant_accel_g : array_like, shape (n,)
        Resultant chest (spine) acceleration, g, CFC 180.
    sample_rate_hz : float
        Sampling rate, Hz; at least 1 sample per 3 ms (>= 334 Hz).
    cumulative : bool, optional
        Cumulative (FMVSS 208, default) or continuous clip.

    Returns
    -------
    float
        a3ms, g.

    Raises
    ------
    ValueError
        If the signal is shorter than 3 ms or the rate gives no sample per 3 ms.
    """
    fs = _check_rate(sample_rate_hz)
    a = _as_channel(resultant_accel_g, "resultant_accel_g")
    m = int(round(CLIP_DURATION_S * fs))
    if m < 1:
        raise ValueError("`sample_rate_hz` must give at least one sample per 3 ms.")
    if a.size < m:
        raise ValueError(
            f"`resultant_accel_g` must span at least 3 ms ({m} samples), got {a.size}."
        )
    if cumulative:
        return float(np.partition(a, a.size - m)[a.size - m])
    windows = np.lib.stride_tricks.sliding_window_view(a, m)
    return float(windows.min(axis=1).max())
